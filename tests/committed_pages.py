"""A generated page compared with the one committed under docs/, with the diff when stale."""

from __future__ import annotations

import difflib
from pathlib import Path

DOCS = Path(__file__).resolve().parents[1] / "docs"


def assert_page_current(name: str, generated: str, command: str) -> None:
    committed = (DOCS / name).read_text()
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
    assert generated == committed, f"docs/{name} is stale; run `{command}`:\n" + diff[:3000]
