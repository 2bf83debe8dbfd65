"""docs/validation.md is what `hems validate` writes now."""

from __future__ import annotations

import difflib
from pathlib import Path

from hems_ros.reports import validation

DOCS = Path(__file__).resolve().parents[2] / "docs"


def test_docs_validation_is_current(tmp_path):
    generated = validation.run(tmp_path, progress=lambda message: None).read_text()
    committed = (DOCS / "validation.md").read_text()
    diff = "\n".join(
        difflib.unified_diff(
            committed.splitlines(),
            generated.splitlines(),
            "committed",
            "generated",
            lineterm="",
            n=0,
        )
    )
    assert generated == committed, (
        "docs/validation.md is stale; run `hems validate`:\n" + diff[:3000]
    )
