"""Conversions between rclpy times and float seconds."""

from builtin_interfaces.msg import Time

from hems_ros.nodes.wire import seconds_of, stamp


def seconds(node) -> float:
    """The node's clock (wall or /clock sim time) in seconds."""
    return node.get_clock().now().nanoseconds * 1e-9


def to_msg(time_s: float) -> Time:
    sec, nanosec = stamp(time_s)
    return Time(sec=sec, nanosec=nanosec)


def from_msg(time: Time) -> float:
    return seconds_of(time.sec, time.nanosec)
