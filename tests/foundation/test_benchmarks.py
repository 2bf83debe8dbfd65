"""Every benchmark runs to its end: each benchmarks/bench_*.py with ``--smoke`` (the same code
in seconds, no floors; benchmarks/smoke.py) exits 0 and prints its table with numbers, so a
change that breaks a benchmark fails here instead of at the next `make bench`. A new
benchmark is picked up by its file name."""

from __future__ import annotations

import re
import subprocess
import sys
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[2]
BENCHMARKS = sorted((REPO / "benchmarks").glob("bench_*.py"))
# these start the node graph (tens of seconds each even when short): not in make test-quick
STARTS_THE_GRAPH = (
    "bench_graph*.py",
    "bench_sim_rate.py",
    "bench_recorder_cpu.py",
    "bench_first_runs.py",
)
# 12, 0.25, -1.5e-3, 51,072, 4.1%, 2.20x: a number as the tables print one
NUMBER = re.compile(r"(?<![\w.])[-+]?\d[\d,]*(\.\d+)?(e[-+]?\d+)?(?![\w.])", re.IGNORECASE)
NOT_A_NUMBER = re.compile(r"\b(nan|inf)\b", re.IGNORECASE)


def _cases() -> list:
    return [
        pytest.param(
            path,
            id=path.stem,
            marks=[pytest.mark.slow] if any(map(path.match, STARTS_THE_GRAPH)) else [],
        )
        for path in BENCHMARKS
    ]


def table_rows(text: str) -> list[str]:
    """Lines of ``text`` with at least three numbers: rows of a table of measurements."""
    return [line for line in text.splitlines() if len(NUMBER.findall(line)) >= 3]


def test_a_table_row_is_told_from_prose() -> None:
    assert table_rows("  write     51,072 msg/s   floor 50,000   ratio 1.02\nrun 2 of 2 done") == [
        "  write     51,072 msg/s   floor 50,000   ratio 1.02"
    ]
    assert table_rows("| composed | max | 3.10 | index | 0.123 | -0.4 | 1e-3 |") != []
    assert table_rows("separate   could not enable: supervisor at FAULT (index)") == []


def test_the_benchmarks_are_found() -> None:
    assert {p.name for p in BENCHMARKS} >= {"bench_physics.py", "bench_graph.py"}


@pytest.mark.parametrize("path", _cases())
def test_the_benchmark_runs_to_its_end_in_smoke_mode(path: Path) -> None:
    done = subprocess.run(
        [sys.executable, str(path), "--smoke"],
        cwd=REPO,
        capture_output=True,
        text=True,
        timeout=900,
    )
    output = f"stdout:\n{done.stdout[-3000:]}\nstderr:\n{done.stderr[-3000:]}"
    assert done.returncode == 0, output
    assert table_rows(done.stdout), output
    assert not NOT_A_NUMBER.search(done.stdout), output
