"""ruff (ruff.toml: pyflakes, pycodestyle with lines of at most 100 characters, import order,
bugbear, a cyclomatic complexity of at most 15, the numpy docstring convention for the public
control and physics API, and its formatter's layout) holds over the code, and mypy (mypy.ini)
over every package of hems_ros and the benchmarks (`make lint`, `make typecheck`)."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

REPO = Path(__file__).resolve().parents[2]


def test_ruff_finds_nothing() -> None:
    ruff = Path(sys.executable).with_name("ruff")
    done = subprocess.run(
        [str(ruff), "check", "--no-cache", "hems_ros", "tests", "benchmarks", "tools"],
        cwd=REPO,
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert done.returncode == 0, done.stdout[-3000:] + done.stderr[-1000:]


def test_the_code_keeps_the_formatters_layout() -> None:
    ruff = Path(sys.executable).with_name("ruff")
    done = subprocess.run(
        [str(ruff), "format", "--check", "--no-cache", "hems_ros", "tests", "benchmarks", "tools"],
        cwd=REPO,
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert done.returncode == 0, done.stdout[-3000:] + done.stderr[-1000:]


def test_mypy_finds_nothing_in_the_packages_it_checks() -> None:
    """mypy.ini names them: every package of hems_ros and the benchmarks, unannotated function
    bodies included, with control, graph and codec fully annotated."""
    done = subprocess.run(
        [sys.executable, "-m", "mypy", "--no-incremental"],
        cwd=REPO,
        capture_output=True,
        text=True,
        timeout=600,
    )
    assert done.returncode == 0, done.stdout[-3000:] + done.stderr[-1000:]
