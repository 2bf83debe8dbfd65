"""A controller sends its idle status only while no feedback comes: each control step
restarts the idle timer, so a node fed at 100 Hz never wakes for it."""

from __future__ import annotations

import time


def test_control_steps_hold_off_the_idle_status_and_silence_lets_it_fire(context):
    from hems_ros.nodes.finger_controller import FingerControllerNode

    node = FingerControllerNode(context=context)
    try:
        period_ns = node.idle_timer.timer_period_ns
        assert period_ns == 100_000_000
        for _ in range(3):
            time.sleep(0.06)
            node.control((0, 0))
            assert node.idle_timer.time_until_next_call() > 0.9 * period_ns
        assert not node.idle_timer.is_ready()
        time.sleep(0.12)
        assert node.idle_timer.is_ready()
        sent = node.status_sequence
        node.idle_timer.callback()
        assert node.status_sequence == sent + 1
    finally:
        node.destroy_node()


def test_the_other_modes_feedback_is_taken_only_when_a_status_goes_out(context, matched_publisher):
    import rclpy
    from hems_msgs.msg import WireForce

    from hems_ros.nodes.finger_controller import FingerControllerNode
    from hems_ros.ros import qos

    node = FingerControllerNode(context=context)
    helper = rclpy.create_node("force_sender", context=context)
    try:
        assert node.loop.setpoint.mode == "position" and node.status_every == 2
        publisher = matched_publisher(helper, WireForce, "/hems/index/wire_force", qos.SENSOR)
        node.loop.reading("position", 0.0, (0, 0))
        node.control((0, 0))  # the first step reports at once (a new status key)
        publisher.publish(WireForce(finger="index", force=7.5))
        time.sleep(0.05)
        node.control((0, 0))  # no status at this step: the force stays queued
        assert node.loop.readings["force"].value is None
        node.control((0, 0))  # the second step since the last status sends one, with the force
        assert node.loop.readings["force"].value == 7.5
    finally:
        helper.destroy_node()
        node.destroy_node()


def test_the_supervisor_status_is_taken_with_the_status_steps_and_the_idle_status(
    context, matched_publisher
):
    import rclpy
    from hems_msgs.msg import SupervisorStatus

    from hems_ros.nodes.finger_controller import FingerControllerNode
    from hems_ros.ros import qos

    node = FingerControllerNode(context=context)
    helper = rclpy.create_node("supervisor_stand_in", context=context)
    try:
        assert node.supervisor_sub in node.polled  # never wakes the controller
        publisher = matched_publisher(
            helper, SupervisorStatus, "/hems/supervisor/status", qos.STATUS
        )
        node.loop.reading("position", 0.0, (0, 0))
        node.control((0, 0))  # reports the new key: the next status is due two steps on
        publisher.publish(SupervisorStatus(state=SupervisorStatus.ENABLED))
        time.sleep(0.05)
        node.control((0, 0))
        assert not node.loop.enabled
        node.control((0, 0))  # a status step: taken before the duty is computed
        assert node.loop.enabled and node.status_sequence >= 2
        publisher.publish(SupervisorStatus(state=SupervisorStatus.ESTOP))
        time.sleep(0.05)
        node.on_idle()  # with no feedback the idle status takes it
        assert not node.loop.enabled and node.loop.duty == 0.0
    finally:
        helper.destroy_node()
        node.destroy_node()


def test_after_a_pause_the_controller_reports_the_queued_encoder_reading_not_the_old_one(
    context, matched_publisher, one_round
):
    # A controller process not scheduled for longer than the idle period wakes with its idle
    # timer ready and encoder readings queued; an idle status sent first repeated the reading
    # from before the pause, which the supervisor took for a stale encoder (FAULT).
    import rclpy
    from hems_msgs.msg import EncoderReading

    from hems_ros.nodes.finger_controller import FingerControllerNode
    from hems_ros.ros import qos

    node = FingerControllerNode(context=context)
    helper = rclpy.create_node("encoder_stand_in", context=context)
    reported = []
    publish_status = node.publish_status

    def recording_status() -> None:
        publish_status()
        reported.append(node.loop.readings["position"].stamp)

    node.publish_status = recording_status
    try:
        publisher = matched_publisher(helper, EncoderReading, "/hems/index/encoder", qos.SENSOR)
        reading = EncoderReading(
            finger="index", counts=10, position=1e-5, resolution=1e-6, sequence=1
        )
        reading.header.stamp.sec = 1
        publisher.publish(reading)
        time.sleep(0.05)
        one_round(node)
        assert node.loop.readings["position"].stamp == (1, 0)
        reading.header.stamp.sec, reading.sequence = 2, 2
        publisher.publish(reading)
        time.sleep(0.15)  # longer than the 0.1 s idle period
        assert node.idle_timer.is_ready()
        reported.clear()
        one_round(node)
        assert node.loop.readings["position"].stamp == (2, 0)
        assert (1, 0) not in reported
    finally:
        helper.destroy_node()
        node.destroy_node()
