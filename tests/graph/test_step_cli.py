"""`hems step` end to end: it starts a one-finger composed graph, records it, steps the tendon
position and prints the figures it reads back from the bag."""

from __future__ import annotations

import re
import subprocess

import pytest

pytestmark = pytest.mark.slow


def test_step_records_a_step_and_prints_its_figures(venv, ros_domain_id, tmp_path):
    from hems_ros.bag import load_bag
    from hems_ros.client.step_figures import step_figures

    bag = tmp_path / "step"
    result = subprocess.run(
        [
            str(venv / "bin" / "hems"),
            "step",
            "--composed",
            "--log-level",
            "warn",
            "--before-s",
            "1",
            "--step-s",
            "4",
            "--after-s",
            "2",
            "--record",
            str(bag),
        ],
        capture_output=True,
        text=True,
        timeout=180,
    )
    assert result.returncode == 0, result.stdout[-2000:] + result.stderr[-2000:]
    printed = re.search(
        r"step: index: rmse_mm ([\d.]+), overshoot_mm (-?[\d.]+), steady_state_error_mm (-?[\d.]+)",
        result.stdout,
    )
    assert printed, result.stdout
    figures = step_figures(bag, "index", 2.0, step_s=4.0)
    assert [float(v) for v in printed.groups()] == pytest.approx(
        [figures["rmse_mm"], figures["overshoot_mm"], figures["steady_state_error_mm"]], abs=5e-4
    )
    # the index unit with Table 5.1's gains: 0.060 mm overshoot and steady-state error by hand
    assert 0.0 <= figures["overshoot_mm"] < 0.2
    assert abs(figures["steady_state_error_mm"]) < 0.1
    # every setpoint is in the bag (one that the controller status did not show at once goes
    # out again, so runs of equal values are collapsed): start 0, then 0, 20 mm, 0
    values = list(load_bag(bag, topics=["/hems/index/setpoint"])["/hems/index/setpoint"]["value"])
    assert [v for i, v in enumerate(values) if i == 0 or v != values[i - 1]] == [0.0, 0.02, 0.0]
