"""docs/experiments.md is what the code generates now: a change to the runs, the findings or
their wording shows here until `hems experiment all --docs docs` is run again."""

from __future__ import annotations

import re

from committed_pages import DOCS, assert_page_current

from hems_ros.reports.experiments import docs_page


def test_docs_experiments_is_current(ch5_runs, ch6_runs, ch5_found, ch6_found):
    committed = (DOCS / "experiments.md").read_text()
    figures = [DOCS / name for name in re.findall(r"!\[[^\]]*\]\(([^)]+)\)", committed)]
    assert len(figures) == 13 and all(f.is_file() for f in figures), figures
    generated = docs_page(
        ch5_runs, ch6_runs, list(ch5_found.values()), list(ch6_found.values()), figures
    )
    assert_page_current("experiments.md", generated, "hems experiment all --docs docs")
