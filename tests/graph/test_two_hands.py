"""Two hands in one ROS domain: a one-finger graph under /left (separate processes, each node
started as `ros2 run` starts it, with `-r __ns:=/left`) and one under /right (composed).
The `hems` verbs with `--namespace left` enable and move the left hand; the right hand's
supervisor stays IDLE, its finger cold and still, and nothing runs under the default /hems.
"""

from __future__ import annotations

import json
import subprocess
import time

import pytest

from hems_ros.graph import names

pytestmark = pytest.mark.slow

FINGER = "index"
TARGET_MM = 12.0


def _hems(venv, *args: str, timeout: float = 60.0) -> subprocess.CompletedProcess:
    return subprocess.run(
        [str(venv / "bin" / "hems"), *args], capture_output=True, text=True, timeout=timeout
    )


def _snapshot(namespace: str):
    from hems_ros.client.graph_client import GraphClient

    with GraphClient("hems_test_two_hands", namespace=namespace) as client:
        assert not client.fingers_without_readers((FINGER,), timeout=60.0)
        snapshot = client.snapshot(fingers=(FINGER,), seconds=1.0, supervisor_wait_s=30.0)
        # a new participant learns the other hand's topics by discovery, which can take seconds
        # on a busy host: the names it knows when its own hand answers may still lack them
        wanted = {names.topic(FINGER, "encoder", ns) for ns in ("/left", "/right")}
        deadline = time.monotonic() + 30.0
        while not wanted <= {n for n, _ in client.node.get_topic_names_and_types()}:
            if time.monotonic() > deadline:
                break
            client.spin_for(0.2)
        return snapshot, client.node.get_topic_names_and_types()


def test_verbs_with_a_namespace_move_one_hand_and_leave_the_other_untouched(ros_domain_id, venv):
    from hems_ros.launcher import Graph, GraphOptions

    left = Graph(
        GraphOptions(fingers=(FINGER,), namespace="/left", composed=False, log_level="warn")
    )
    right = Graph(GraphOptions(fingers=(FINGER,), namespace="/right", log_level="warn"))
    left.start()
    right.start()
    try:
        before, _ = _snapshot("/right")
        enabled = _hems(venv, "enable", "--namespace", "left", "--timeout", "60")
        assert enabled.returncode == 0, enabled.stdout + enabled.stderr
        moved = _hems(
            venv, "setpoint", FINGER, str(TARGET_MM), "--unit", "mm", "--namespace", "left"
        )
        assert moved.returncode == 0, moved.stdout + moved.stderr
        deadline = time.monotonic() + 20.0
        while True:
            snap, _ = _snapshot("/left")
            position_mm = 1e3 * snap.states[FINGER].tendon_position
            if abs(position_mm - TARGET_MM) < 1.5 or time.monotonic() > deadline:
                break
        assert snap.supervisor.state_name == "ENABLED"
        assert snap.controllers[FINGER].setpoint == pytest.approx(TARGET_MM * 1e-3)
        assert abs(position_mm - TARGET_MM) < 1.5, position_mm
        status = _hems(venv, "status", "--namespace", "left", "--json")
        assert status.returncode == 0, status.stdout + status.stderr
        document = json.loads(status.stdout)
        assert document["supervisor"] == {"state": "ENABLED", "faults": []}
        row = document["fingers"][FINGER]
        assert (row["mode"], row["setpoint_unit"]) == ("position", "m")
        assert row["setpoint"] == pytest.approx(TARGET_MM * 1e-3)
        assert abs(1e3 * row["tendon_position_m"] - TARGET_MM) < 1.5, row
        assert row["faults"] == [] and 0.0 <= row["duty_percent"] <= 100.0
        assert document["stream_gaps"]["loss_limit_ms"] == 400

        after, topics = _snapshot("/right")
        assert after.supervisor.state_name == "IDLE"
        assert (
            after.controllers[FINGER].setpoint == 0.0
            and after.controllers[FINGER].duty_percent == 0.0
        )
        assert (
            after.states[FINGER].electrical_energy == before.states[FINGER].electrical_energy == 0.0
        )
        assert abs(after.states[FINGER].tendon_position) < 1e-4
        status = _hems(venv, "status", "--namespace", "right")
        assert status.returncode == 0 and "supervisor: IDLE" in status.stdout, (
            status.stdout + status.stderr
        )

        topic_names = {name for name, _ in topics}
        assert names.topic(FINGER, "encoder", "/left") in topic_names
        assert names.topic(FINGER, "encoder", "/right") in topic_names
        assert not [
            name for name in topic_names if name.startswith(names.NAMESPACE + "/")
        ], topic_names
    finally:
        left.stop()
        right.stop()


def test_a_bad_namespace_is_refused_before_anything_starts(venv):
    result = _hems(venv, "status", "--namespace", "2nd-hand")
    assert result.returncode == 2
    assert (
        "namespace '2nd-hand': expected tokens of letters, digits and underscores" in result.stderr
    )
