"""The supervisor enables only units that get their controller's commands, and faults a unit
that has not taken its ENABLED (one finger's four nodes in this process, real topics)."""

from __future__ import annotations

import threading
import time

import pytest


def _remapped(*rules: str) -> dict:
    return (
        {"cli_args": ["--ros-args", *(arg for rule in rules for arg in ("-r", rule))]}
        if rules
        else {}
    )


@pytest.fixture
def one_finger(context):
    """make(unit_remaps=(), controller_remaps=()): the index finger's unit, shoulder module,
    controller and supervisor, spun on a thread until the test ends; returns the supervisor."""
    from rclpy.executors import ExternalShutdownException
    from rclpy.parameter import Parameter

    from hems_ros.nodes.actuation_unit import ActuationUnitNode
    from hems_ros.nodes.finger_controller import FingerControllerNode
    from hems_ros.nodes.shoulder_module import ShoulderModuleNode
    from hems_ros.nodes.supervisor import SupervisorNode
    from hems_ros.ros.lean_spin import spin_nodes

    nodes, threads = [], []

    def make(unit_remaps=(), controller_remaps=()):
        supervisor = SupervisorNode(
            context=context,
            parameter_overrides=[Parameter("fingers", value=["index"])],
        )
        nodes.extend(
            [
                ActuationUnitNode(context=context, **_remapped(*unit_remaps)),
                ShoulderModuleNode(context=context),
                FingerControllerNode(context=context, **_remapped(*controller_remaps)),
                supervisor,
            ]
        )

        def spin():
            try:
                spin_nodes(nodes)
            except ExternalShutdownException:
                pass

        threads.append(threading.Thread(target=spin, daemon=True))
        threads[0].start()
        return supervisor

    yield make
    context.try_shutdown()
    for thread in threads:
        thread.join(timeout=5)
    for node in nodes:
        node.destroy_node()


def _supervisor_state(client, seconds: float, until: str | None = None):
    """The supervisor's status after ``seconds``, or as soon as its state is ``until``."""
    deadline = time.monotonic() + seconds
    while True:
        status = client.snapshot(("index",), 0.1).supervisor
        if status.state_name == until or time.monotonic() >= deadline:
            return status


def test_enable_is_refused_while_the_units_watchdog_sees_no_duty_commands(one_finger):
    """The controller runs and reports fresh readings, but its commands go to another topic:
    before, this unit was enabled and the watchdog flag latched FAULT about 100 ms later."""
    from hems_ros.client.graph_client import GraphClient

    supervisor = one_finger(controller_remaps=["/hems/index/duty:=/hems/index/duty_nowhere"])
    with GraphClient("enable_gate") as client:
        # the graph is not ready until the window ends, as `hems enable` waits: the unit's
        # watchdog is also tripped for a healthy finger until discovery has matched the
        # controller's duty writer with the unit
        ok, message = client.enable_when_ready(timeout=6.0, retry_s=0.3)
        assert not ok
        assert message == (
            "the graph was not ready after 6 s: "
            "index: no duty commands reach the unit (its watchdog is tripped)"
        )
        assert supervisor.logic.state.name == "IDLE"


def test_a_unit_that_has_not_taken_enabled_faults_within_the_grace(one_finger):
    """The unit's status reader listens on another topic: it gets its duty commands (watchdog
    clear, enable accepted) but never the permission to heat."""
    from hems_ros.client.graph_client import GraphClient

    supervisor = one_finger(
        unit_remaps=["/hems/supervisor/status:=/hems/supervisor/status_nowhere"]
    )
    with GraphClient("enable_gate") as client:
        ok, message = client.enable_when_ready(timeout=20.0, retry_s=0.3)
        assert ok, message
        assert message == "ENABLED"
        status = _supervisor_state(client, 10.0, until="FAULT")
        assert status.state_name == "FAULT"
        assert status.faults[0].startswith("index: unit has not taken ENABLED for "), status.faults
        assert status.faults[0].endswith(" ms: it does not heat")
        held_ms = float(status.faults[0].split(" for ")[1].split(" ms")[0])
        assert (
            500 <= held_ms < 1500
        )  # judged on the 20 Hz unit states, as the supervisor takes them
    assert supervisor.logic.faults[0].kind == "unit not enabled"


def test_a_healthy_finger_is_enabled_and_stays_enabled(one_finger):
    from hems_ros.client.graph_client import GraphClient

    one_finger()
    with GraphClient("enable_gate") as client:
        ok, message = client.enable_when_ready(timeout=20.0, retry_s=0.3)
        assert ok, message
        assert message == "ENABLED"
        status = _supervisor_state(client, 1.0)
        assert status.state_name == "ENABLED", status.faults
