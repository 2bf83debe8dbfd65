"""The dissertation is cited one way: "eq. 4.26", "eqs. 4.22-4.24", "Table 4.1". The heat
block is cited as its group, eqs. 4.7-4.12: the source's numbering inside it is not what the
project can check, and two numbers for one balance had crept in."""

from __future__ import annotations

import re
from pathlib import Path

REPO = Path(__file__).resolve().parents[2]
TEXTS = [
    *(REPO / "hems_ros").rglob("*.py"),
    *(REPO / "docs").glob("*.md"),
    REPO / "README.md",
    *(REPO / "benchmarks").glob("*.py"),
]
NO_PERIOD = re.compile(r"\b[Ee]qs? \d")
BARE = re.compile(r"(?:law|motion|equation|increment) \(\d\.\d{1,2}\)")
HEAT_MEMBER = re.compile(r"\b[Ee]qs?\. 4\.(?:7|8|9|10|11|12)\b(?!-4\.12)")


def _hits(pattern: re.Pattern) -> list[str]:
    return [
        f"{path.relative_to(REPO)}:{number}: {line.strip()[:80]}"
        for path in TEXTS
        for number, line in enumerate(path.read_text().splitlines(), 1)
        if pattern.search(line)
    ]


def test_equations_are_cited_with_eq_and_a_period():
    assert not _hits(NO_PERIOD)
    assert not _hits(BARE)


def test_the_heat_block_is_cited_as_its_group():
    assert not _hits(HEAT_MEMBER)
