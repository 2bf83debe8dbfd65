"""Publishes simulated time on /clock for the nodes started with ``use_sim_time:=true``
(`hems up --sim-time --rate R`).

Lockstep (the default): the clock takes its next 10 ms step only when every finger's unit,
shoulder module and controller have done their part of the current one and the supervisor
keeps up (hems_ros.graph.lockstep_clock), so a run's figures do not depend on the host or the
layout; ``rate`` caps the pace (simulated s per wall s; 0 runs as fast as the graph answers).
With ``lockstep:=false`` it is a plain clock: every ``period_s`` of wall time it moves on by
``rate * period_s``, whether the nodes keep up or not.

Subscribes (lockstep)  /hems/<finger>/encoder, /hems/<finger>/wire_force, /hems/<finger>/duty,
                       /hems/supervisor/status
Publishes              /clock  rosgraph_msgs/Clock  reliable
"""

from __future__ import annotations

import time

from hems_msgs.msg import DutyCommand, EncoderReading, SupervisorStatus, WireForce
from rclpy.qos import QoSProfile, ReliabilityPolicy
from rosgraph_msgs.msg import Clock

from hems_ros.graph import names
from hems_ros.graph.lockstep_clock import STALL_S, LockstepClock
from hems_ros.ros import qos
from hems_ros.ros.clock_time import from_msg, to_msg
from hems_ros.ros.lean_node import LeanNode
from hems_ros.ros.params import PERIOD_LIMIT, Spec, declare, non_negative
from hems_ros.ros.runner import run_node
from hems_ros.ros.wire import seconds_of


def _fingers(value) -> str | None:
    unknown = [f for f in str(value).split(",") if f and f not in names.FINGERS]
    return f"unknown fingers {unknown} (known: {', '.join(names.FINGERS)})" if unknown else None


PARAMETERS = [
    Spec(
        "rate",
        1.0,
        "simulated seconds per wall second; with lockstep the most, and 0 runs as fast as the "
        "graph answers",
        non_negative,
        True,
    ),
    Spec(
        "lockstep",
        True,
        "advance only when every finger's unit, shoulder module and controller have answered "
        "the current step",
        None,
        True,
    ),
    Spec(
        "fingers",
        ",".join(names.FINGERS),
        "comma-separated fingers the lockstep waits for",
        _fingers,
        True,
    ),
    Spec(
        "step_s",
        0.01,
        "lockstep: simulated time per step, s (the encoder period)",
        PERIOD_LIMIT,
        True,
    ),
    Spec(
        "stall_s",
        STALL_S,
        "lockstep: a finger that has not answered for this long (wall clock, s) is left out "
        "until it answers again (a stopped controller; a busy host only slows the clock down)",
        PERIOD_LIMIT,
        True,
    ),
    Spec(
        "period_s",
        0.004,
        "wall-clock publishing period, s (without lockstep; with it, how often the pace "
        "is checked)",
        PERIOD_LIMIT,
        True,
    ),
]


class SimClockNode(LeanNode):
    """Simulated-time source for the graph."""

    def __init__(self, **node_kwargs) -> None:
        super().__init__("sim_clock", namespace="/hems", **node_kwargs)
        self.graph_ns = self.get_namespace()
        p = declare(self, PARAMETERS)
        self.rate = p["rate"]
        self.wall0 = time.monotonic()
        self.sim0 = 1.0  # time 0 means "no clock yet" to rclpy; start just after it
        self.pub = self.create_publisher(
            Clock, "/clock", QoSProfile(depth=10, reliability=ReliabilityPolicy.RELIABLE)
        )
        self.lockstep: LockstepClock | None = None
        if p["lockstep"]:
            fingers = tuple(f for f in p["fingers"].split(",") if f)
            lockstep = LockstepClock(
                fingers, start_s=self.sim0, step_s=p["step_s"], rate=self.rate, stall_s=p["stall_s"]
            )
            self.lockstep = lockstep
            for finger in fingers:
                self.subscribe_serialized(
                    EncoderReading,
                    names.topic(finger, "encoder", self.graph_ns),
                    lambda m, f=finger: self._saw(lockstep.encoder, f, m),
                    qos.SENSOR,
                )
                self.subscribe_serialized(
                    WireForce,
                    names.topic(finger, "wire_force", self.graph_ns),
                    lambda m, f=finger: self._saw(lockstep.force, f, m),
                    qos.SENSOR,
                )
                self.subscribe_serialized(
                    DutyCommand,
                    names.topic(finger, "duty", self.graph_ns),
                    lambda m, f=finger: self._answer(f, m),
                    qos.DUTY,
                )
            self.create_subscription(
                SupervisorStatus,
                names.supervisor_status_topic(self.graph_ns),
                self._on_supervisor_status,
                qos.STATUS,
            )
            self.pub.publish(Clock(clock=to_msg(self.sim0)))
            self.create_timer(p["period_s"], self._advance)
            self.create_timer(5.0, self._report_stalls)
            self._stalls_reported = 0
        else:
            self.create_timer(p["period_s"], self.tick)

    def tick(self) -> None:
        self.pub.publish(
            Clock(clock=to_msg(self.sim0 + self.rate * (time.monotonic() - self.wall0)))
        )

    @property
    def _lockstep_clock(self) -> LockstepClock:
        """The lockstep clock: the callbacks that use it are only set up with lockstep on."""
        assert self.lockstep is not None
        return self.lockstep

    def _on_supervisor_status(self, message) -> None:
        self._lockstep_clock.supervisor(from_msg(message.header.stamp))
        self._advance()

    def _saw(self, record, finger: str, message) -> None:
        record(finger, seconds_of(message.header_stamp_sec, message.header_stamp_nanosec))
        self._advance()

    def _answer(self, finger: str, message) -> None:
        self._lockstep_clock.duty(
            finger, seconds_of(message.measurement_stamp_sec, message.measurement_stamp_nanosec)
        )
        self._advance()

    def _advance(self, _=None) -> None:
        now = self._lockstep_clock.try_advance(time.monotonic())
        if now is not None:
            self.pub.publish(Clock(clock=to_msg(now)))

    def _report_stalls(self) -> None:
        clock = self._lockstep_clock
        if clock.stalls > self._stalls_reported:
            self._stalls_reported = clock.stalls
            self.get_logger().warning(
                f"lockstep: {clock.stalls} steps advanced without every answer "
                f"(taking part now: {', '.join(clock.joined) or 'none'})"
            )


def main() -> int:
    return run_node(SimClockNode)


if __name__ == "__main__":
    raise SystemExit(main())
