"""A node's clock read through hems_ros.ros.clock_time: the system clock without sim time,
the /clock time once ROS time is active."""

from __future__ import annotations

import time


def test_now_ns_is_the_system_clock_until_ros_time_is_active(context):
    import rclpy
    from rclpy.time import Time

    from hems_ros.ros.clock_time import now_ns, seconds, stamp_now

    node = rclpy.create_node("clock_reader", context=context)
    try:
        before = time.time_ns()
        read = now_ns(node)
        assert before <= read <= time.time_ns()
        assert abs(read - node.get_clock().now().nanoseconds) < 5_000_000

        clock = node.get_clock()
        clock._set_ros_time_is_active(True)
        clock.set_ros_time_override(Time(seconds=123, nanoseconds=456))
        assert now_ns(node) == 123_000_000_456
        assert seconds(node) == 123_000_000_456 * 1e-9
        assert (stamp_now(node).sec, stamp_now(node).nanosec) == (123, 456)
    finally:
        node.destroy_node()
