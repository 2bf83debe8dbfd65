"""Publishes simulated time on /clock, running ``rate`` times faster than the wall clock.

Nodes started with ``use_sim_time:=true`` follow it (`hems up --sim-time --rate R`).
Published every ``period_s`` of wall time (default 4 ms), so each tick advances simulated
time by ``rate * period_s``; the actuation units integrate in 1 ms steps whatever the tick.
"""

from __future__ import annotations

import time

from rclpy.node import Node
from rclpy.qos import QoSProfile, ReliabilityPolicy
from rosgraph_msgs.msg import Clock

from hems_ros.nodes.clock_time import to_msg
from hems_ros.nodes.params import PERIOD_LIMIT, Spec, declare, positive
from hems_ros.nodes.runner import run_node

PARAMETERS = [
    Spec("rate", 1.0, "simulated seconds per wall second", positive, True),
    Spec("period_s", 0.004, "wall-clock publishing period, s", PERIOD_LIMIT, True),
]


class SimClockNode(Node):
    """Simulated-time source for the graph."""

    def __init__(self, **node_kwargs) -> None:
        super().__init__("sim_clock", namespace="/hems", **node_kwargs)
        p = declare(self, PARAMETERS)
        self.rate = p["rate"]
        self.wall0 = time.monotonic()
        self.sim0 = 1.0  # time 0 means "no clock yet" to rclpy; start just after it
        self.pub = self.create_publisher(Clock, "/clock", QoSProfile(depth=10, reliability=ReliabilityPolicy.RELIABLE))
        self.create_timer(p["period_s"], self.tick)

    def tick(self) -> None:
        self.pub.publish(Clock(clock=to_msg(self.sim0 + self.rate * (time.monotonic() - self.wall0))))


def main() -> int:
    return run_node(SimClockNode)


if __name__ == "__main__":
    raise SystemExit(main())
