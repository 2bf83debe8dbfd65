"""One process of bench_graph_floor.py's skeleton graph: the graph's messages and nothing else.

Kept apart from the benchmark, whose imports (the graph client, the launcher) a node process
does not carry; rclpy and the messages are imported only once ``run_node`` has applied the
project's environment, as in the nodes. Usage: python benchmarks/skeleton_node.py ROLE NAME
TICK_S CHECK_S STATE_EVERY STATUS_EVERY (ROLE: unit, module, controller, supervisor; NAME: a
finger, a shoulder module or "supervisor"; the rates as the graph's configuration gives them,
bench_graph_floor.graph_rates).
"""

from __future__ import annotations

import sys
from collections.abc import Callable
from dataclasses import dataclass

from hems_ros.graph import names
from hems_ros.graph.cadence import supervisor_check_delay, tick_delay


@dataclass(frozen=True)
class Rates:
    tick_s: float  # a unit's tick (tick_period_s)
    check_s: float  # the supervisor's check (check_period_s)
    state_every: int  # ticks per unit state (state_period_s / tick_period_s)
    status_every: int  # controller steps per status (status_every)


def encoded(message_type) -> bytes:
    """A default message of the type, serialized once: the skeleton sends it as it is."""
    from rclpy.serialization import serialize_message

    return serialize_message(message_type())


def subscribe(node, message_type, topic: str, profile, callback=None):
    """A raw subscription whose callback does nothing unless given one."""
    return node.create_subscription(
        message_type, topic, callback or (lambda *taken: None), profile, raw=True
    )


def build_unit(node, finger: str, rates: Rates) -> None:
    """Ticks on its pair's grid: takes duty commands and statuses, sends an encoder reading and
    a wire tension, and its state every ``state_every`` ticks."""
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
        if ticks[0] % rates.state_every == 0:
            state.publish(messages[ActuatorState])

    create_grid_timer(node, rates.tick_s, lambda now: tick_delay(finger, rates.tick_s, now), tick)


def build_module(node, module: str, _rates: Rates) -> None:
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


def build_controller(node, finger: str, rates: Rates) -> None:
    """Wakes on its encoder readings: takes force readings and statuses, sends a duty command,
    and its status every ``status_every`` steps."""
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
        if steps[0] % rates.status_every == 0:
            status.publish(messages[ControllerStatus])

    subscribe(node, EncoderReading, names.topic(finger, "encoder"), qos.SENSOR, step)


def build_supervisor(node, _name: str, rates: Rates) -> None:
    """Every ``check_s`` at the supervisor's phase: takes the controllers' statuses and units'
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

    create_grid_timer(
        node, rates.check_s, lambda now: supervisor_check_delay(rates.check_s, now), check
    )


BUILDERS: dict[str, Callable[..., None]] = {
    "unit": build_unit,
    "module": build_module,
    "controller": build_controller,
    "supervisor": build_supervisor,
}


def skeleton_node(role: str, name: str, rates: Rates):
    """The node class of one skeleton process."""
    from hems_ros.ros.lean_node import LeanNode

    class Skeleton(LeanNode):
        def __init__(self, **kwargs) -> None:
            super().__init__(f"skeleton_{role}_{name}", **kwargs)
            BUILDERS[role](self, name, rates)
            print("ready", flush=True)  # the benchmark measures once all sixteen are

    return Skeleton


if __name__ == "__main__":
    from hems_ros.ros.runner import run_node

    role, name, tick_s, check_s, state_every, status_every = sys.argv[1:7]
    if role not in BUILDERS:
        sys.exit(f"skeleton_node: role {role!r}: expected one of {', '.join(BUILDERS)}")
    rates = Rates(float(tick_s), float(check_s), int(state_every), int(status_every))
    sys.exit(run_node(skeleton_node(role, name, rates), [sys.argv[0]]))
