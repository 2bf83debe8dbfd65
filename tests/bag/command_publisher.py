"""A short-lived setpoint publisher for the recorder tests (runs as its own process).

Waits until ``--subscribers`` subscriptions have matched its publisher on ``--topic``,
publishes ``--count`` FingerSetpoint messages (value = ``--value`` + k mm, 100 Hz; with
``--until-taken`` each again until the controller status shows it), and exits at once (or
after ``--linger`` s), as `ros2 topic pub --once` does. ``--best-effort``
publishes best effort instead of reliable, ``--latched`` transient local.
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
    parser.add_argument("--latched", action="store_true", help="transient local")
    parser.add_argument(
        "--linger", type=float, default=0.0, help="seconds to stay after publishing"
    )
    parser.add_argument(
        "--until-taken",
        action="store_true",
        help="publish each value at 100 Hz until the controller status shows it (as a user "
        "running `ros2 topic pub -r 100` until the finger moves), 10 s at most",
    )
    args = parser.parse_args()

    import rclpy
    from hems_msgs.msg import FingerSetpoint
    from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy

    rclpy.init()
    node = rclpy.create_node("command_publisher")
    reliability = ReliabilityPolicy.BEST_EFFORT if args.best_effort else ReliabilityPolicy.RELIABLE
    durability = DurabilityPolicy.TRANSIENT_LOCAL if args.latched else DurabilityPolicy.VOLATILE
    publisher = node.create_publisher(
        FingerSetpoint,
        args.topic,
        QoSProfile(depth=10, reliability=reliability, durability=durability),
    )
    deadline = time.monotonic() + 30.0
    while publisher.get_subscription_count() < args.subscribers:
        if time.monotonic() > deadline:
            print(
                f"only {publisher.get_subscription_count()} of {args.subscribers} "
                f"subscriptions matched",
                file=sys.stderr,
            )
            return 1
        time.sleep(0.02)
    shown = []
    if args.until_taken:
        from hems_msgs.msg import ControllerStatus

        from hems_ros.ros import qos

        node.create_subscription(
            ControllerStatus,
            args.topic.rsplit("/", 1)[0] + "/controller_status",
            lambda m: shown.append(m.setpoint),
            qos.CONTROLLER_STATUS,
        )
    for k in range(args.count):
        value = (args.value + k) * 1e-3
        until = time.monotonic() + 10.0
        while True:
            publisher.publish(FingerSetpoint(mode="position", value=value))
            rclpy.spin_once(node, timeout_sec=0.01)
            if not args.until_taken or value in shown[-5:] or time.monotonic() > until:
                break
    taken = "" if not args.until_taken else f", taken: {value in shown}"
    print(f"command_publisher: published {args.count}{taken}", flush=True)
    until = time.monotonic() + args.linger
    while (
        rclpy.ok() and time.monotonic() < until
    ):  # SIGTERM shuts the context down (rclpy's handler)
        time.sleep(0.05)
    node.destroy_node()
    rclpy.try_shutdown()
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
