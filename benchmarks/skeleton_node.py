"""One process of bench_graph_floor.py's skeleton graph: the graph's messages and nothing else.

Kept apart from the benchmark, whose imports (the graph client, the launcher) a node process
does not carry; rclpy and the messages are imported only once ``run_node`` has applied the
project's environment, as in the nodes. Usage: python benchmarks/skeleton_node.py ROLE NAME
(ROLE: unit, module, controller, supervisor; NAME: a finger, a shoulder module or "supervisor").
"""

from __future__ import annotations

import sys
from collections.abc import Callable

from hems_ros.graph import names
from hems_ros.graph.cadence import supervisor_check_delay, tick_delay

TICK_S, CHECK_S = 0.01, 0.02
STATE_EVERY, STATUS_EVERY = 5, 2  # ticks per unit state (20 Hz), steps per controller status


def encoded(message_type) -> bytes:
    """A default message of the type, serialized once: the skeleton sends it as it is."""
    from rclpy.serialization import serialize_message

    return serialize_message(message_type())


def subscribe(node, message_type, topic: str, profile, callback=None):
    """A raw subscription whose callback does nothing unless given one."""
    return node.create_subscription(
        message_type, topic, callback or (lambda *taken: None), profile, raw=True
    )


def build_unit(node, finger: str) -> None:
    """Ticks on its pair's grid: takes duty commands and statuses, sends an encoder reading and
    a wire tension, and its state every STATE_EVERY ticks."""
    from hems_msgs.msg import (
        ActuatorState,
        DutyCommand,
        EncoderReading,
        SupervisorStatus,
        WireForce,
    )

    from hems_ros.ros import qos
    from hems_ros.ros.grid_timer import create_grid_timer

    encoder = node.create_publisher(EncoderReading, names.topic(finger, "encoder"), qos.SENSOR)
    tension = node.create_publisher(WireForce, names.sim_topic(finger, "wire_tension"), qos.SENSOR)
    state = node.create_publisher(ActuatorState, names.sim_topic(finger, "state"), qos.SENSOR)
    inputs = (
        subscribe(node, DutyCommand, names.topic(finger, "duty"), qos.DUTY),
        subscribe(node, SupervisorStatus, names.supervisor_status_topic(), qos.STATUS_EACH),
    )
    node.poll(*inputs)
    messages = {t: encoded(t) for t in (EncoderReading, WireForce, ActuatorState)}
    ticks = [0]

    def tick() -> None:
        node.drain_in_order(*inputs)
        encoder.publish(messages[EncoderReading])
        tension.publish(messages[WireForce])
        ticks[0] += 1
        if ticks[0] % STATE_EVERY == 0:
            state.publish(messages[ActuatorState])

    create_grid_timer(node, TICK_S, lambda now: tick_delay(finger, TICK_S, now), tick)


def build_module(node, module: str) -> None:
    """Wakes on each of its units' tensions and sends that finger's force reading."""
    from hems_msgs.msg import WireForce

    from hems_ros.ros import qos

    force = encoded(WireForce)
    for finger in names.MODULES[module]:
        publisher = node.create_publisher(WireForce, names.topic(finger, "wire_force"), qos.SENSOR)
        subscribe(
            node,
            WireForce,
            names.sim_topic(finger, "wire_tension"),
            qos.SENSOR,
            lambda data, p=publisher: p.publish(force),
        )


def build_controller(node, finger: str) -> None:
    """Wakes on its encoder readings: takes force readings and statuses, sends a duty command,
    and its status every STATUS_EVERY steps."""
    from hems_msgs.msg import (
        ControllerStatus,
        DutyCommand,
        EncoderReading,
        SupervisorStatus,
        WireForce,
    )

    from hems_ros.ros import qos

    duty = node.create_publisher(DutyCommand, names.topic(finger, "duty"), qos.DUTY)
    status = node.create_publisher(
        ControllerStatus, names.topic(finger, "controller_status"), qos.CONTROLLER_STATUS
    )
    inputs = (
        subscribe(node, WireForce, names.topic(finger, "wire_force"), qos.SENSOR),
        subscribe(node, SupervisorStatus, names.supervisor_status_topic(), qos.STATUS),
    )
    node.poll(*inputs)
    messages = {t: encoded(t) for t in (DutyCommand, ControllerStatus)}
    steps = [0]

    def step(data: bytes) -> None:
        for subscription in inputs:
            node.drain(subscription)
        duty.publish(messages[DutyCommand])
        steps[0] += 1
        if steps[0] % STATUS_EVERY == 0:
            status.publish(messages[ControllerStatus])

    subscribe(node, EncoderReading, names.topic(finger, "encoder"), qos.SENSOR, step)


def build_supervisor(node, _name: str) -> None:
    """Every CHECK_S at the supervisor's phase: takes the controllers' statuses and units'
    states, sends its status."""
    from hems_msgs.msg import ActuatorState, ControllerStatus, SupervisorStatus

    from hems_ros.ros import qos
    from hems_ros.ros.grid_timer import create_grid_timer

    reports = [
        subscribe(node, kind, topic, qos.SENSOR)
        for finger in names.FINGERS
        for kind, topic in (
            (ControllerStatus, names.topic(finger, "controller_status")),
            (ActuatorState, names.sim_topic(finger, "state")),
        )
    ]
    node.poll(*reports)
    status = node.create_publisher(SupervisorStatus, names.supervisor_status_topic(), qos.STATUS)
    message = encoded(SupervisorStatus)

    def check() -> None:
        node.drain_in_order(*reports)
        status.publish(message)

    create_grid_timer(node, CHECK_S, lambda now: supervisor_check_delay(CHECK_S, now), check)


BUILDERS: dict[str, Callable[..., None]] = {
    "unit": build_unit,
    "module": build_module,
    "controller": build_controller,
    "supervisor": build_supervisor,
}


def skeleton_node(role: str, name: str):
    """The node class of one skeleton process."""
    from hems_ros.ros.lean_node import LeanNode

    class Skeleton(LeanNode):
        def __init__(self, **kwargs) -> None:
            super().__init__(f"skeleton_{role}_{name}", **kwargs)
            BUILDERS[role](self, name)
            print("ready", flush=True)  # the benchmark measures once all sixteen are

    return Skeleton


if __name__ == "__main__":
    from hems_ros.ros.runner import run_node

    role, name = sys.argv[1:3]
    if role not in BUILDERS:
        sys.exit(f"skeleton_node: role {role!r}: expected one of {', '.join(BUILDERS)}")
    sys.exit(run_node(skeleton_node(role, name), [sys.argv[0]]))
