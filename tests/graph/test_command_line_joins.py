"""Command-line tools joining an enabled graph that holds all six fingers never fault it, and
every setpoint they send is reached: benchmarks/bench_graph_joins.py with a small count, on
both layouts (the full count's result is in docs/reliability.md)."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import pytest

from hems_ros.rosenv import child_environment

pytestmark = [pytest.mark.slow, pytest.mark.graph_realtime]

BENCH = Path(__file__).resolve().parents[2] / "benchmarks" / "bench_graph_joins.py"


def test_ten_joins_per_layout_fault_nothing_and_every_setpoint_is_reached(tmp_path):
    out = tmp_path / "joins.json"
    done = subprocess.run(
        [
            sys.executable,
            str(BENCH),
            "--joins",
            "10",
            "--layouts",
            "separate,composed",
            "--json",
            str(out),
        ],
        env=child_environment(),
        capture_output=True,
        text=True,
        timeout=900,
    )
    assert done.returncode == 0, done.stdout[-3000:] + done.stderr[-3000:]
    results = json.loads(out.read_text())
    for layout in ("separate", "composed"):
        result = results[layout]
        assert "error" not in result, result
        assert result["joins"] == 10 and sum(result["by_kind"].values()) == 10
        assert result["faulted"] == 0, result["kinds"]
        assert result["missed"] == [], result["missed"]
