"""Answers DDS round-trip probes: a middleware check between processes or hosts.

Subscribes ``/hems/ping/request`` (hems_msgs/DutyCommand) and answers each request on
``/hems/ping/reply`` (hems_msgs/EncoderReading) with the same sequence number, the duty
mapped to counts (``round(duty_percent * 1000)``) and position (``duty_percent * 1e-3`` m),
so the caller can check that field values crossed the wire intact both ways.
"""

from __future__ import annotations

from hems_msgs.msg import DutyCommand, EncoderReading
from rclpy.node import Node
from rclpy.qos import QoSProfile, ReliabilityPolicy

from hems_ros.ros.runner import run_node

REQUEST_TOPIC = "/hems/ping/request"
REPLY_TOPIC = "/hems/ping/reply"
PING_QOS = QoSProfile(depth=100, reliability=ReliabilityPolicy.RELIABLE)
COUNTS_PER_PERCENT = 1000
METRES_PER_PERCENT = 1e-3


class PingResponder(Node):
    def __init__(self, **node_kwargs) -> None:
        super().__init__("ping_responder", namespace="/hems", **node_kwargs)
        self._reply = self.create_publisher(EncoderReading, REPLY_TOPIC, PING_QOS)
        self.create_subscription(DutyCommand, REQUEST_TOPIC, self._answer, PING_QOS)

    def _answer(self, request: DutyCommand) -> None:
        reply = EncoderReading()
        reply.header.stamp = request.header.stamp
        reply.finger = request.finger
        reply.counts = round(request.duty_percent * COUNTS_PER_PERCENT)
        reply.position = request.duty_percent * METRES_PER_PERCENT
        reply.resolution = METRES_PER_PERCENT / COUNTS_PER_PERCENT
        reply.sequence = request.sequence
        self._reply.publish(reply)


def main() -> int:
    return run_node(PingResponder)


if __name__ == "__main__":
    raise SystemExit(main())
