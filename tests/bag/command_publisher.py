"""A short-lived setpoint publisher for the recorder tests (runs as its own process).

Waits until ``--subscribers`` subscriptions have matched its publisher on ``--topic``,
publishes ``--count`` FingerSetpoint messages (value = ``--value`` + k mm, 100 Hz), and exits
at once, as `hems setpoint` and `ros2 topic pub --once` do. ``--best-effort`` publishes best
effort instead of reliable.
"""

from __future__ import annotations

import argparse
import sys
import time


def main() -> int:
    parser = argparse.ArgumentParser()
    parser.add_argument("--topic", default="/hems/index/setpoint")
    parser.add_argument("--subscribers", type=int, default=2)
    parser.add_argument("--count", type=int, default=1)
    parser.add_argument("--value", type=float, default=0.0, help="mm")
    parser.add_argument("--best-effort", action="store_true")
    args = parser.parse_args()

    import rclpy
    from rclpy.qos import QoSProfile, ReliabilityPolicy

    from hems_msgs.msg import FingerSetpoint

    rclpy.init()
    node = rclpy.create_node("command_publisher")
    reliability = ReliabilityPolicy.BEST_EFFORT if args.best_effort else ReliabilityPolicy.RELIABLE
    publisher = node.create_publisher(FingerSetpoint, args.topic, QoSProfile(depth=10, reliability=reliability))
    deadline = time.monotonic() + 30.0
    while publisher.get_subscription_count() < args.subscribers:
        if time.monotonic() > deadline:
            print(f"only {publisher.get_subscription_count()} of {args.subscribers} subscriptions matched",
                  file=sys.stderr)
            return 1
        time.sleep(0.02)
    for k in range(args.count):
        publisher.publish(FingerSetpoint(mode="position", value=(args.value + k) * 1e-3))
        time.sleep(0.01)
    node.destroy_node()
    rclpy.shutdown()
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
