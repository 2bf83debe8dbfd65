"""Conversions between rclpy times and float seconds."""

from builtin_interfaces.msg import Time


def seconds(node) -> float:
    """The node's clock (wall or /clock sim time) in seconds."""
    return node.get_clock().now().nanoseconds * 1e-9


def to_msg(time_s: float) -> Time:
    nanoseconds = int(round(time_s * 1e9))
    return Time(sec=nanoseconds // 1_000_000_000, nanosec=nanoseconds % 1_000_000_000)


def from_msg(stamp: Time) -> float:
    return stamp.sec + stamp.nanosec * 1e-9
