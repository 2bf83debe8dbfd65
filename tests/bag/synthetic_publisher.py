"""Synthetic graph-like publishers for the bag tests (runs as its own process).

Publishes ``--count`` messages on each stream at ``--rate`` Hz, with field values derived
from the sequence number (see ``expected_values``), after every publisher has matched a
subscriber; a transient-local SupervisorStatus is published once at start-up. Prints one
JSON line with the per-topic counts when done.
"""

from __future__ import annotations

import argparse
import json
import sys
import time

STREAMS = {  # topic: (type, reliable)
    "/hems/test/encoder": ("hems_msgs/msg/EncoderReading", False),
    "/hems/test/wire_force": ("hems_msgs/msg/WireForce", False),
    "/hems/test/duty": ("hems_msgs/msg/DutyCommand", True),
    "/hems/joint_states": ("sensor_msgs/msg/JointState", True),
}
STATUS_TOPIC = "/hems/supervisor/status"


def expected_values(topic: str, sequence: int) -> dict[str, float]:
    """Field values of message ``sequence`` on ``topic`` (shared with the tests)."""
    if topic.endswith("encoder"):
        return {"counts": sequence, "position": sequence * 1e-5, "sequence": sequence}
    if topic.endswith("wire_force"):
        return {"force": 0.25 * sequence, "saturated": sequence % 2 == 1, "sequence": sequence}
    if topic.endswith("duty"):
        return {"duty_percent": (sequence * 7.3) % 100.0, "sequence": sequence}
    return {"header.stamp.sec": sequence}


def build(topic: str, sequence: int):
    from hems_msgs.msg import DutyCommand, EncoderReading, WireForce
    from sensor_msgs.msg import JointState

    values = expected_values(topic, sequence)
    if topic.endswith("encoder"):
        return EncoderReading(
            finger="index",
            counts=values["counts"],
            position=values["position"],
            resolution=1e-5,
            sequence=sequence,
        )
    if topic.endswith("wire_force"):
        return WireForce(
            finger="index", force=values["force"], saturated=values["saturated"], sequence=sequence
        )
    if topic.endswith("duty"):
        return DutyCommand(finger="index", duty_percent=values["duty_percent"], sequence=sequence)
    message = JointState(name=["index", "middle"], position=[sequence * 1e-3, -sequence * 1e-3])
    message.header.stamp.sec = sequence
    return message


def main() -> int:
    parser = argparse.ArgumentParser()
    parser.add_argument("--count", type=int, default=1000)
    parser.add_argument("--rate", type=float, default=500.0)
    parser.add_argument("--linger", type=float, default=1.0)
    parser.add_argument("--timeout", type=float, default=20.0)
    args = parser.parse_args()

    import rclpy
    from hems_msgs.msg import SupervisorStatus
    from rclpy.node import Node
    from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy

    from hems_ros.ros.wire import message_class

    rclpy.init()
    node = Node("synthetic_publisher")
    latched = QoSProfile(
        depth=1, reliability=ReliabilityPolicy.RELIABLE, durability=DurabilityPolicy.TRANSIENT_LOCAL
    )
    status_publisher = node.create_publisher(SupervisorStatus, STATUS_TOPIC, latched)
    status_publisher.publish(SupervisorStatus(state=1, state_name="ENABLED", faults=["none"]))
    publishers = {
        topic: node.create_publisher(
            message_class(type_name),
            topic,
            QoSProfile(
                depth=100,
                reliability=ReliabilityPolicy.RELIABLE
                if reliable
                else ReliabilityPolicy.BEST_EFFORT,
            ),
        )
        for topic, (type_name, reliable) in STREAMS.items()
    }
    deadline = time.monotonic() + args.timeout
    while any(p.get_subscription_count() == 0 for p in publishers.values()):
        if time.monotonic() > deadline:
            print("synthetic_publisher: no subscriber matched", file=sys.stderr)
            return 1
        time.sleep(0.02)
    time.sleep(0.3)  # matched on our side: give the subscriber's side the same chance
    period = 1.0 / args.rate
    start = time.monotonic()
    for sequence in range(args.count):
        for topic, publisher in publishers.items():
            publisher.publish(build(topic, sequence))
        delay = start + (sequence + 1) * period - time.monotonic()
        if delay > 0:
            time.sleep(delay)
    time.sleep(args.linger)
    print(
        json.dumps({"published": {topic: args.count for topic in publishers} | {STATUS_TOPIC: 1}}),
        flush=True,
    )
    node.destroy_node()
    rclpy.try_shutdown()
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
