"""docs/validation.md is what `hems validate` writes now."""

from __future__ import annotations

from committed_pages import assert_page_current

from hems_ros.reports import validation


def test_docs_validation_is_current(tmp_path):
    generated = validation.run(tmp_path, progress=lambda message: None).read_text()
    assert_page_current("validation.md", generated, "hems validate")
