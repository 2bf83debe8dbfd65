"""`hems experiment` end to end: the tables, figures and verdicts a user gets from the command."""

from __future__ import annotations

import subprocess
import sys


def _hems(*args, cwd):
    return subprocess.run(
        [sys.executable, "-m", "hems_ros.cli.main", "experiment", *args],
        capture_output=True,
        text=True,
        timeout=300,
        cwd=cwd,
    )


def test_ch6_writes_tables_figures_and_verdicts(tmp_path):
    out = tmp_path / "ch6"
    done = _hems("ch6", "-o", str(out), cwd=tmp_path)
    assert done.returncode == 0, done.stderr
    lines = done.stdout.splitlines()
    # one progress line per run, then the claims check, then the verdicts
    assert sum(" bpid " in line for line in lines) == 8
    assert any(line.startswith("checking the chapter 6 claims") for line in lines)
    assert (
        "  ok   Force control: steady-state error at most 0.1 N with the sensor noise: step "
        "0.049 N, staircase 0.024 N" in lines
    )
    assert any(
        line.startswith(
            "  MISS Position control: RMSE at most 3x Table 6.1: sine_0.125 4.565 mm (55.0x)"
        )
        for line in lines
    )
    assert (
        f"  why each MISS, with the runs that show it: {out / 'ch6.md'}, 'Not reproduced, and why'"
        in lines
    )
    md = (out / "ch6.md").read_text()
    assert "Not reproduced, and why:" in md
    assert "| ramp | 0.019 / 0.142 / 7.46 |" in md
    assert "0.067 mm on the ramp (3.5x Table 6.1" in md
    assert sorted(p.name for p in out.glob("*.png"))[:2] == [
        "ch6_force_sine_0.125.png",
        "ch6_force_sine_0.25.png",
    ]
    assert len(list(out.glob("*.png"))) == 8 and "![ch6_position_ramp](ch6_position_ramp.png)" in md


def test_docs_needs_both_chapters(tmp_path):
    done = _hems("ch5", "--docs", str(tmp_path / "docs"), cwd=tmp_path)
    assert done.returncode == 2
    assert "--docs needs chapter 'all'" in done.stdout
    assert not (tmp_path / "docs").exists()
