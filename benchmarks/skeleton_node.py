"""One process of bench_graph_floor.py's skeleton graph: the graph's messages and nothing else.

Kept apart from the benchmark, whose imports (the graph client, the launcher) a node process
does not carry. Usage: python benchmarks/skeleton_node.py ROLE NAME (ROLE: unit, module,
controller, supervisor; NAME: a finger, a shoulder module or "supervisor").
"""

from __future__ import annotations

import sys

from hems_ros.graph import names
from hems_ros.graph.cadence import supervisor_check_delay, tick_delay

TICK_S, CHECK_S = 0.01, 0.02
STATE_EVERY, STATUS_EVERY = 5, 2  # ticks per unit state (20 Hz), steps per controller status
ROLES = ("unit", "module", "controller", "supervisor")


def skeleton_node(role: str, name: str):
    """The node of one skeleton process (imports rclpy: only in the child processes)."""
    from hems_msgs.msg import (
        ActuatorState,
        ControllerStatus,
        DutyCommand,
        EncoderReading,
        SupervisorStatus,
        WireForce,
    )
    from rclpy.serialization import serialize_message

    from hems_ros.ros import qos
    from hems_ros.ros.grid_timer import create_grid_timer
    from hems_ros.ros.lean_node import LeanNode

    def encoded(message_type) -> bytes:
        return serialize_message(message_type())

    class Skeleton(LeanNode):
        def __init__(self, **kwargs) -> None:
            super().__init__(f"skeleton_{role}_{name}", **kwargs)
            self.count = 0
            getattr(self, f"build_{role}")()
            print("ready", flush=True)  # the parent measures once all sixteen are

        def sub(self, message_type, topic: str, profile, callback=None):
            return self.create_subscription(
                message_type, topic, callback or (lambda *taken: None), profile, raw=True
            )

        def build_unit(self) -> None:
            self.encoder = self.create_publisher(
                EncoderReading, names.topic(name, "encoder"), qos.SENSOR
            )
            self.tension = self.create_publisher(
                WireForce, names.sim_topic(name, "wire_tension"), qos.SENSOR
            )
            self.state = self.create_publisher(
                ActuatorState, names.sim_topic(name, "state"), qos.SENSOR
            )
            self.inputs = (
                self.sub(DutyCommand, names.topic(name, "duty"), qos.DUTY),
                self.sub(SupervisorStatus, names.supervisor_status_topic(), qos.STATUS_EACH),
            )
            self.poll(*self.inputs)
            self.bytes = {t: encoded(t) for t in (EncoderReading, WireForce, ActuatorState)}
            create_grid_timer(self, TICK_S, lambda now: tick_delay(name, TICK_S, now), self.tick)

        def tick(self) -> None:
            self.drain_in_order(*self.inputs)
            self.encoder.publish(self.bytes[EncoderReading])
            self.tension.publish(self.bytes[WireForce])
            self.count += 1
            if self.count % STATE_EVERY == 0:
                self.state.publish(self.bytes[ActuatorState])

        def build_module(self) -> None:
            force = encoded(WireForce)
            for finger in names.MODULES[name]:
                publisher = self.create_publisher(
                    WireForce, names.topic(finger, "wire_force"), qos.SENSOR
                )
                self.sub(
                    WireForce,
                    names.sim_topic(finger, "wire_tension"),
                    qos.SENSOR,
                    lambda data, p=publisher: p.publish(force),
                )

        def build_controller(self) -> None:
            self.duty = self.create_publisher(DutyCommand, names.topic(name, "duty"), qos.DUTY)
            self.status = self.create_publisher(
                ControllerStatus, names.topic(name, "controller_status"), qos.CONTROLLER_STATUS
            )
            self.inputs = (
                self.sub(WireForce, names.topic(name, "wire_force"), qos.SENSOR),
                self.sub(SupervisorStatus, names.supervisor_status_topic(), qos.STATUS),
            )
            self.poll(*self.inputs)
            self.bytes = {t: encoded(t) for t in (DutyCommand, ControllerStatus)}
            self.sub(EncoderReading, names.topic(name, "encoder"), qos.SENSOR, self.step)

        def step(self, data: bytes) -> None:
            for subscription in self.inputs:
                self.drain(subscription)
            self.duty.publish(self.bytes[DutyCommand])
            self.count += 1
            if self.count % STATUS_EVERY == 0:
                self.status.publish(self.bytes[ControllerStatus])

        def build_supervisor(self) -> None:
            self.reports = [
                self.sub(kind, topic, qos.SENSOR)
                for finger in names.FINGERS
                for kind, topic in (
                    (ControllerStatus, names.topic(finger, "controller_status")),
                    (ActuatorState, names.sim_topic(finger, "state")),
                )
            ]
            self.poll(*self.reports)
            self.status = self.create_publisher(
                SupervisorStatus, names.supervisor_status_topic(), qos.STATUS
            )
            self.status_bytes = encoded(SupervisorStatus)
            create_grid_timer(
                self, CHECK_S, lambda now: supervisor_check_delay(CHECK_S, now), self.check
            )

        def check(self) -> None:
            self.drain_in_order(*self.reports)
            self.status.publish(self.status_bytes)

    return Skeleton


if __name__ == "__main__":
    from hems_ros.ros.runner import run_node

    role, name = sys.argv[1:3]
    if role not in ROLES:
        sys.exit(f"skeleton_node: role {role!r}: expected one of {', '.join(ROLES)}")
    sys.exit(run_node(skeleton_node(role, name), [sys.argv[0]]))
