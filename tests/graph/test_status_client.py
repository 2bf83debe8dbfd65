"""`hems status` hears a running supervisor even when discovery is slower than its listen."""

from __future__ import annotations

import subprocess
import time

from hems_ros.processes import stop_process


def test_snapshot_waits_for_the_supervisor_beyond_its_listen_time(venv, ros_domain_id):
    from hems_ros.client.graph_client import GraphClient

    supervisor = subprocess.Popen(
        [str(venv / "bin" / "python"), "-m", "hems_ros.nodes.supervisor"],
        stdout=subprocess.DEVNULL,
        stderr=subprocess.DEVNULL,
    )
    try:
        with GraphClient("hems_status_test") as client:
            start = time.monotonic()
            # no listen at all: only the wait for the supervisor can find it
            snap = client.snapshot(fingers=("index",), seconds=0.0, supervisor_wait_s=30.0)
            elapsed = time.monotonic() - start
        assert snap.supervisor is not None and snap.supervisor.state_name == "IDLE"
        assert elapsed < 30.0
        assert snap.controllers == {}
    finally:
        stop_process(supervisor, 10.0)


def test_status_rows_name_a_unit_or_controller_that_has_not_taken_enabled():
    from hems_msgs.msg import ActuatorState, ControllerStatus, SupervisorStatus

    from hems_ros.cli.commands import format_status
    from hems_ros.client.graph_client import Snapshot

    snap = Snapshot(
        controllers={
            f: ControllerStatus(finger=f, mode="position", active=f != "middle")
            for f in ("index", "middle", "ring")
        },
        states={
            f: ActuatorState(finger=f, heating_allowed=f != "ring")
            for f in ("index", "middle", "ring")
        },
        supervisor=SupervisorStatus(state=SupervisorStatus.ENABLED, state_name="ENABLED"),
    )
    rows = {line.split()[0]: line for line in format_status(snap).splitlines()}
    assert rows["index"].endswith("  -")
    assert rows["middle"].endswith("  controller inactive")
    assert rows["ring"].endswith("  unit has no heating permission")
    snap.supervisor = SupervisorStatus(state=SupervisorStatus.IDLE, state_name="IDLE")
    assert all(format_status(snap).splitlines()[i].endswith("  -") for i in (3, 4, 5))


def test_a_finger_heard_without_its_state_or_force_keeps_the_snapshot_listening_and_shows_dashes():
    from hems_msgs.msg import ActuatorState, ControllerStatus, SupervisorStatus, WireForce

    from hems_ros.cli.commands import format_status
    from hems_ros.client.graph_client import Snapshot

    snap = Snapshot(
        controllers={"index": ControllerStatus(finger="index", mode="force", setpoint=10.0)},
        supervisor=SupervisorStatus(state=SupervisorStatus.ENABLED, state_name="ENABLED"),
    )
    assert snap.incomplete()
    row = next(line for line in format_status(snap).splitlines() if line.startswith("index"))
    # was "nan nan": no state or force message had arrived within the listen
    assert row.split()[1:6] == ["force", "10.00", "N", "-", "-"] and "nan" not in row
    snap.states["index"] = ActuatorState(finger="index", tendon_position=0.012)
    assert snap.incomplete()
    snap.forces["index"] = WireForce(finger="index", force=8.0)
    assert snap.incomplete()  # the supervisor's diagnostics, once a second, not yet
    snap.diagnostics = [("ready", "true"), ("gaps index encoder", "2, longest 71 ms")]
    assert not snap.incomplete()
    # a finger listened to whose controller the supervisor hears and this snapshot not yet
    snap.fingers = ("index", "middle", "ring")
    snap.diagnostics.append(("fingers heard", "index,middle"))
    assert snap.incomplete()
    snap.controllers["middle"] = ControllerStatus(finger="middle")
    snap.states["middle"] = ActuatorState(finger="middle")
    snap.forces["middle"] = WireForce(finger="middle")
    assert not snap.incomplete()  # ring: not heard by the supervisor, nothing to wait for
    del snap.diagnostics[-1]
    lines = format_status(snap).splitlines()
    row = next(line for line in lines if line.startswith("index"))
    assert row.split()[4:6] == ["12.00", "4.00"]
    assert lines[-1].startswith("stream gaps while ENABLED: 2 gaps, longest 71 ms (index encoder)")
    snap.diagnostics = [("ready", "true"), ("gap floor ms", "50"), ("loss limit ms", "400")]
    assert format_status(snap).splitlines()[-1] == (
        "stream gaps while ENABLED: no gap over 50 ms; a stream silent for 400 ms faults"
    )
    snap.diagnostics.append(("supervisor quiets", "0, longest 0 ms"))  # none: not shown
    assert format_status(snap).splitlines()[-1].endswith("a stream silent for 400 ms faults")
    snap.diagnostics[-1] = ("supervisor quiets", "2, longest 334 ms")
    assert (
        format_status(snap)
        .splitlines()[-1]
        .endswith("faults; supervisor quiets: 2, longest 334 ms")
    )
    snap.diagnostics += [("enable taken", "85 ms (ring controller)"), ("enable grace ms", "1000")]
    assert (
        format_status(snap)
        .splitlines()[-1]
        .endswith(
            "; ENABLED taken within 85 ms (ring controller), "
            "a node that has not taken it for 1000 ms faults"
        )
    )
