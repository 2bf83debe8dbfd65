"""`hems up --sim-time`: the graph on /clock heats and tracks as on the wall clock.

The supervisor took all its subscriptions out of the wait set to drain them at its check,
/clock included; on sim time the check waited for the clock and the clock for the check, so
no periodic status came after ENABLED and every unit lost its heating permission 0.5 s later.
One composed finger (slow).
"""

from __future__ import annotations

import numpy as np
import pytest

pytestmark = pytest.mark.slow

FINGER = "index"


def test_a_sim_time_graph_keeps_heating_and_reaches_its_setpoint(ros_domain_id):
    from hems_ros.client.graph_client import GraphClient
    from hems_ros.launcher import Graph, GraphOptions

    graph = Graph(GraphOptions(fingers=(FINGER,), sim_time=True, log_level="warn"))
    graph.start()
    try:
        with GraphClient("hems_test_sim_time") as client:
            ok, message = client.enable_when_ready(60, reset=True, retry_s=0.5)
            assert ok, message
            result = client.send_setpoint(FINGER, "position", 0.020, confirm_s=5.0)
            assert result, result.message
            client.spin_for(5.0)
            first = client.snapshot(fingers=(FINGER,), seconds=0.5)
            client.spin_for(1.0)
            second = client.snapshot(fingers=(FINGER,), seconds=0.5)
        assert graph.exited() == {}
        for snap in (first, second):
            assert snap.supervisor.state_name == "ENABLED", snap.supervisor.faults
            assert snap.states[FINGER].heating_allowed
        # the supervisor's status keeps coming on sim time (10 Hz)
        stamp = lambda s: s.supervisor.header.stamp.sec + 1e-9 * s.supervisor.header.stamp.nanosec  # noqa: E731
        assert 0.5 < stamp(second) - stamp(first) < 3.0
        assert second.states[FINGER].tendon_position == pytest.approx(0.020, abs=5e-4)
    finally:
        graph.stop()


def _step(venv, tmp_path, *options: str) -> tuple[float, float, float]:
    import re
    import subprocess

    folder = tmp_path / "_".join(o.strip("-") for o in options)
    result = subprocess.run(
        [
            str(venv / "bin" / "hems"),
            "step",
            "--sim-time",
            "--fingers",
            FINGER,
            *options,
            "--log-level",
            "warn",
            "--before-s",
            "1",
            "--step-s",
            "3",
            "--after-s",
            "1",
            "--record",
            str(folder),
        ],
        capture_output=True,
        text=True,
        timeout=400,
    )
    assert result.returncode == 0, result.stdout[-2000:] + result.stderr[-2000:]
    printed = re.search(
        r"rmse_mm ([\d.]+), overshoot_mm (-?[\d.]+), steady_state_error_mm (-?[\d.]+)",
        result.stdout,
    )
    assert printed, result.stdout
    # the controller held the step for the 3 s of the graph's clock the figures cover; a
    # record's stamp is the controller's clock when it took the setpoint, which can still be a
    # control period (10 ms) behind the tool's /clock that timed the phase
    from hems_ros.bag import load_bag

    records = load_bag(folder, topics=["/hems/index/commands"])["/hems/index/commands"]
    taken = records.stamp[records["accepted"]]
    values = records["value"][records["accepted"]]
    rise = np.flatnonzero(values == 0.02)[-1]
    assert taken[rise + 1] - taken[rise] >= 3.0 - 0.01 - 1e-3
    return tuple(map(float, printed.groups()))


def test_a_step_on_sim_time_gives_the_same_figures_at_any_rate_and_layout(
    venv, ros_domain_id, tmp_path
):
    # The lockstep clock moves on only when the unit, the shoulder module and the controller
    # have answered the current sample: a plain clock at 4x once gave 0.73 and 0.40 mm of
    # overshoot where 1x gave 0.06, as the nodes fell behind it.
    runs = {
        "composed, max": _step(venv, tmp_path, "--composed", "--rate", "max"),
        "separate, 4x": _step(venv, tmp_path, "--separate", "--rate", "4"),
        "composed, 1x": _step(venv, tmp_path, "--composed", "--rate", "1"),
    }
    print(runs)
    rmse, overshoot, ss_error = runs["composed, 1x"]
    assert 5.0 < rmse < 15.0 and 0.0 <= overshoot < 0.2 and abs(ss_error) < 0.1
    for figures in runs.values():
        assert figures[0] == pytest.approx(rmse, rel=0.02)
        assert figures[1] == pytest.approx(overshoot, rel=0.02, abs=0.005)
        assert figures[2] == pytest.approx(ss_error, rel=0.02, abs=0.005)
