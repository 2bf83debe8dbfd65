"""Verbs against a graph brought up with fewer fingers: `hems grasp` names the missing
controllers before any setpoint (and before enabling), `--fingers` runs the grasp on the
fingers the graph has, enabled and disabled by the tool, also when a signal stops it;
`hems setpoint all` waits once for all the controllers, not once per missing one.

One composed finger keeps it in the default run (marked slow).
"""

from __future__ import annotations

import os
import signal
import subprocess
import time

import pytest

from hems_ros.graph import names

pytestmark = pytest.mark.slow

FINGER = "index"


@pytest.fixture(scope="module")
def one_finger_graph(ros_domain_id):
    from hems_ros.client.graph_client import GraphClient
    from hems_ros.launcher import Graph, GraphOptions

    graph = Graph(GraphOptions(fingers=(FINGER,), log_level="warn"))
    graph.start()
    try:
        with GraphClient("hems_test_partial_graph") as client:
            assert not client.fingers_without_readers((FINGER,), timeout=60.0)
            yield graph, client
    finally:
        graph.stop()


def _grasp(venv, tmp_path, *extra):
    return subprocess.run(
        [
            str(venv / "bin" / "hems"),
            "grasp",
            "--enable",
            "--plot",
            str(tmp_path / "grasp.png"),
            *extra,
        ],
        capture_output=True,
        text=True,
        timeout=120,
    )


def test_grasp_names_missing_controllers_before_it_enables(one_finger_graph, venv, tmp_path):
    graph, client = one_finger_graph
    started = time.monotonic()
    result = _grasp(venv, tmp_path)
    assert result.returncode == 1, result.stdout + result.stderr
    others = [f for f in names.FINGERS if f != FINGER]
    assert f"grasp: no finger_controller for {', '.join(others)}" in result.stderr
    assert "hems up --fingers" in result.stderr
    # one discovery wait for all of them (10 s), not one per finger while the first ones heat
    assert time.monotonic() - started < 30.0
    assert "ENABLED" not in result.stdout and "approach" not in result.stdout
    snap = client.snapshot(fingers=(FINGER,), seconds=0.5)
    assert snap.supervisor is not None and snap.supervisor.state_name != "ENABLED"
    assert snap.controllers[FINGER].duty_percent == 0.0
    assert graph.exited() == {}


def test_grasp_on_the_graphs_fingers_enables_runs_and_disables(one_finger_graph, venv, tmp_path):
    graph, client = one_finger_graph
    result = _grasp(venv, tmp_path, "--fingers", FINGER)
    assert result.returncode == 0, result.stdout[-2000:] + result.stderr[-2000:]
    lines = result.stdout.splitlines()
    assert "grasp: ENABLED" in lines and "grasp: DISABLED" in lines
    rows = [line.split() for line in lines if line.split() and line.split()[0] in names.FINGERS]
    assert [row[0] for row in rows] == [FINGER]
    assert 9.9 < float(rows[0][5]) < 10.3  # peak tendon force, N (10 N hold)
    snap = client.snapshot(fingers=(FINGER,), seconds=0.5)
    assert snap.supervisor.state_name != "ENABLED"
    assert graph.exited() == {}


def test_setpoint_all_waits_once_for_the_missing_controllers(one_finger_graph, venv):
    graph, _ = one_finger_graph
    started = time.monotonic()
    result = subprocess.run(
        [str(venv / "bin" / "hems"), "setpoint", "all", "0", "--unit", "mm", "--timeout", "8"],
        capture_output=True,
        text=True,
        timeout=120,
    )
    elapsed = time.monotonic() - started
    assert result.returncode == 1, result.stdout + result.stderr
    assert f"{FINGER}: position setpoint 0 m: in force (controller status)" in result.stdout
    for finger in names.FINGERS:
        if finger != FINGER:
            assert (
                f"{finger}: position setpoint 0 m: no finger_controller subscribed to "
                f"/hems/{finger}/setpoint" in result.stderr
            )
    assert elapsed < 20.0  # 8 s for all five missing ones, not 40 s
    assert graph.exited() == {}


@pytest.mark.parametrize("signal_name", ["SIGTERM", "SIGINT"])
def test_a_grasp_that_enabled_the_graph_disables_it_when_stopped(
    one_finger_graph, venv, tmp_path, signal_name
):
    # rclpy's handler takes the process's ROS context with the signal; a tool that could not
    # disable the graph then would leave it ENABLED, the finger heating to its last setpoint
    graph, client = one_finger_graph
    grasp = subprocess.Popen(
        [
            str(venv / "bin" / "hems"),
            "grasp",
            "--enable",
            "--fingers",
            FINGER,
            "--plot",
            str(tmp_path / "grasp.png"),
        ],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
    )
    try:
        os.set_blocking(grasp.stdout.fileno(), False)
        seen, deadline = b"", time.monotonic() + 60
        while (
            b"grasp: approach" not in seen and grasp.poll() is None and time.monotonic() < deadline
        ):
            try:
                seen += os.read(grasp.stdout.fileno(), 65536)
            except BlockingIOError:
                time.sleep(0.1)
        assert b"grasp: approach" in seen, seen
        time.sleep(1.0)  # heating
        grasp.send_signal(getattr(signal, signal_name))
        os.set_blocking(grasp.stdout.fileno(), True)
        rest, err = grasp.communicate(timeout=60)
        out, err = (seen + rest).decode(), err.decode()
    finally:
        if grasp.poll() is None:
            grasp.kill()
    assert grasp.returncode in (130, 143), out + err
    assert "grasp: stopped mid-grasp: DISABLED" in out, out + err
    assert "Traceback" not in err
    snap = client.snapshot(fingers=(FINGER,), seconds=0.5)
    assert snap.supervisor.state_name == "DISABLED"
    assert graph.exited() == {}


def test_a_setpoint_on_a_graph_not_enabled_says_nothing_heats(one_finger_graph, venv):
    graph, client = one_finger_graph
    client.call("disable")
    result = subprocess.run(
        [str(venv / "bin" / "hems"), "setpoint", FINGER, "5", "--unit", "mm", "--timeout", "5"],
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert result.returncode == 1, result.stdout + result.stderr
    assert f"{FINGER}: position setpoint 0.005 m: in force (controller status)" in result.stdout
    assert (
        "the supervisor is DISABLED: nothing heats until it is ENABLED (hems enable)"
        in result.stderr
    )
    assert graph.exited() == {}
