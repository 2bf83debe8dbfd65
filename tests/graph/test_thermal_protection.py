"""A stuck encoder on the live graph: the reading freezes while the samples stay fresh, so the
position loop heats at 100 % without end and neither the supervisor's stream monitors nor its
over-travel check see anything. The controller's estimate of the wire temperature from the
drive board's readings holds the duty at 0 at the cut-off; the simulation truth stays below
it (plus one sample)."""

from __future__ import annotations

import time

import pytest

from hems_ros.graph import names

pytestmark = pytest.mark.slow

FINGER = "index"


def _set_fault(node, fault: str) -> None:
    import rclpy
    from rcl_interfaces.msg import Parameter, ParameterType, ParameterValue
    from rcl_interfaces.srv import SetParameters

    client = node.create_client(SetParameters, f"/hems/actuation_unit_{FINGER}/set_parameters")
    assert client.wait_for_service(timeout_sec=30.0)
    request = SetParameters.Request(
        parameters=[
            Parameter(
                name="sensor_fault",
                value=ParameterValue(type=ParameterType.PARAMETER_STRING, string_value=fault),
            )
        ]
    )
    future = client.call_async(request)
    rclpy.spin_until_future_complete(node, future, timeout_sec=10.0)
    assert future.result() is not None and future.result().results[0].successful
    node.destroy_client(client)


def test_a_stuck_encoder_cannot_overheat_the_wire(ros_domain_id):
    import rclpy
    from hems_msgs.msg import ActuatorState, ControllerStatus

    from hems_ros.client.graph_client import GraphClient
    from hems_ros.launcher import Graph, GraphOptions
    from hems_ros.ros import qos

    graph = Graph(GraphOptions(fingers=(FINGER,), composed=False, log_level="warn"))
    graph.start()
    try:
        with GraphClient("hems_test_thermal") as client:
            assert not client.fingers_without_readers((FINGER,), timeout=60.0)
            truth, statuses = [], []
            client.node.create_subscription(
                ActuatorState,
                names.sim_topic(FINGER, "state"),
                lambda m: truth.append(m.wire_temperature_c),
                qos.SENSOR,
            )
            client.node.create_subscription(
                ControllerStatus,
                names.topic(FINGER, "controller_status"),
                statuses.append,
                qos.CONTROLLER_STATUS,
            )
            ok, message = client.enable_when_ready(timeout=60.0)
            assert ok, message
            _set_fault(client.node, "stuck_encoder")
            assert client.send_setpoint(FINGER, "position", 0.03, confirm_s=5.0).confirmed
            t0 = time.monotonic()
            while time.monotonic() - t0 < 12.0:
                rclpy.spin_once(client.node, timeout_sec=0.05)
            supervisor = client.supervisor_status()
            _set_fault(client.node, "")
            client.call("disable")
    finally:
        graph.stop()
    assert max(truth) < 153.0, max(truth)  # truth: never past the cut-off
    assert max(truth) > 140.0  # it did heat up to it
    assert any(s.thermal_limited for s in statuses)
    estimates = [s.wire_temperature_c for s in statuses if s.thermal_limited]
    assert min(estimates) >= 140.0 and max(estimates) < 153.0
    assert supervisor is not None and supervisor.state_name == "ENABLED", supervisor
