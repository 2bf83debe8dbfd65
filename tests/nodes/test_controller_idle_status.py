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
        node.publish_idle_status()
        assert node.status_sequence == sent + 1
    finally:
        node.destroy_node()
