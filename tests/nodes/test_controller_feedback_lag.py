"""A controller in position mode sends 0 % while its force readings lag its encoder by more
than feedback_lag_s on the unit's stamps: a lost force sensor must not leave the wire heating
blind to over-force (and the supervisor then latches only a loss that persists)."""

from __future__ import annotations


def _stamp(seconds: float) -> tuple[int, int]:
    ns = int(round(seconds * 1e9))
    return ns // 1_000_000_000, ns % 1_000_000_000


def test_duty_is_zero_while_the_other_sensor_lags_and_back_when_it_returns(context):
    from hems_ros.graph.setpoints import Setpoint
    from hems_ros.nodes.finger_controller import FingerControllerNode

    # the stamps below stand in for the module's readings: its liveliness is not watched
    node = FingerControllerNode(context=context, in_process_with=frozenset({"shoulder_module"}))
    try:
        node.enabled = True
        node.setpoint = Setpoint("position", 0.02)
        node.wire_position, node.wire_force = 0.0, 4.0
        t0 = 1000.0
        node.force_stamp = _stamp(t0)
        node.encoder_stamp = _stamp(t0 + 0.05)
        node.control(node.encoder_stamp)  # 50 ms behind: fresh enough, the loop heats
        assert node.duty == 100.0
        node.encoder_stamp = _stamp(t0 + 0.11)
        node.control(node.encoder_stamp)  # 110 ms behind (unit clock): 0 %
        assert node.duty == 0.0
        node.force_stamp = _stamp(t0 + 0.11)  # the sensor is back
        node.encoder_stamp = _stamp(t0 + 0.12)
        node.control(node.encoder_stamp)
        assert node.duty == 100.0
        node.force_stamp = (0, 0)  # never a force reading: no heating either
        node.control(_stamp(t0 + 0.13))
        assert node.duty == 0.0
    finally:
        node.destroy_node()


def test_in_force_mode_the_encoder_is_the_other_sensor(context):
    from hems_ros.graph.setpoints import Setpoint
    from hems_ros.nodes.finger_controller import FingerControllerNode

    node = FingerControllerNode(context=context)
    try:
        node.enabled = True
        node.setpoint = Setpoint("force", 10.0)
        node.controller.set_mode("force", 4.0, node.mode_gains["force"])
        node.wire_position, node.wire_force = 0.0, 4.0
        node.encoder_stamp = _stamp(2000.0)
        node.force_stamp = _stamp(2000.2)
        node.control(node.force_stamp)  # encoder 200 ms behind the force feedback
        assert node.duty == 0.0
        node.encoder_stamp = _stamp(2000.2)
        node.control(node.force_stamp)
        assert node.duty > 0.0
    finally:
        node.destroy_node()


def test_a_force_sensor_whose_module_stopped_stops_a_position_loop_within_its_lease(
    context, other_participant, wait_alive
):
    """The controller watches the liveliness of the wire-force writer (qos.WIRE_FORCE): a
    module that stops or dies is seen within the lease, before its last readings lag."""
    import time

    from hems_msgs.msg import WireForce

    from hems_ros.graph.setpoints import Setpoint
    from hems_ros.nodes import qos
    from hems_ros.nodes.finger_controller import FingerControllerNode

    node = FingerControllerNode(context=context)
    try:
        writer = other_participant.create_publisher(
            WireForce, "/hems/index/wire_force", qos.WIRE_FORCE
        )
        wait_alive(node.force_watch)
        node.enabled = True
        node.setpoint = Setpoint("position", 0.02)
        node.wire_position, node.wire_force = 0.0, 4.0
        node.force_stamp = node.encoder_stamp = _stamp(1000.0)
        node.control(node.encoder_stamp)
        assert node.duty == 100.0
        other_participant.destroy_publisher(writer)
        deadline = time.monotonic() + 2.0
        while node.force_watch.alive():
            assert time.monotonic() < deadline, "the controller still sees a module that left"
            time.sleep(0.005)
        node.control(node.encoder_stamp)  # the same fresh stamps: only the liveliness says no
        assert node.duty == 0.0
        assert node.force_watch.losses == 1
    finally:
        node.destroy_node()
