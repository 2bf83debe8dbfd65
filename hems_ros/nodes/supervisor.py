"""The HEMS supervisor: state machine IDLE / ENABLED / DISABLED / FAULT / ESTOP
(hems_ros.graph.supervisor_logic) and the safety monitors of all six fingers.

Services (std_srvs/Trigger)   /hems/supervisor/{enable,disable,estop,reset}
Subscribes  /hems/<finger>/controller_status (best effort, heartbeat): also the controller's
            latest encoder and force readings; a stream counts as alive while those readings
            keep changing, so the supervisor need not take 1200 sensor messages a second;
            /hems/sim/<finger>/state (best effort, duty-watchdog flag, heating permission)
Publishes   /hems/supervisor/status  hems_msgs/SupervisorStatus  reliable, transient local; on
                                                                 change and every status_period_s
            /hems/supervisor/commands hems_msgs/CommandRecord   reliable, transient local: every
                                                                service call
            /hems/joint_states       sensor_msgs/JointState      reliable: tendon position (m) and
                                                                 tendon force (N, as effort)
            /diagnostics             diagnostic_msgs/DiagnosticArray  1 Hz, and at once when
                                     the graph becomes ready (key "ready": every stream
                                     enable needs is present; "not ready": what is missing)

Monitors: lost encoder or force streams and unit state reports (no new reading for lost_s,
default 400 ms; shorter gaps over stale_s, 50 ms, are counted in /diagnostics), controller
heartbeats (> heartbeat_timeout_s, default 400 ms), wire over-force (default 50 N), tendon
over-travel, a wire temperature estimated at max_wire_temperature_c (170 degC; the controllers cut
heating at 150 degC themselves), duty-watchdog flags held watchdog_hold_s (500 ms), and while
ENABLED a unit or controller that has not taken ENABLED within enable_grace_s (1 s). ``enable``
also waits for every unit's state and for its controller's commands to reach it (watchdog flag not
held). Heating is allowed only in ENABLED: the units and controllers drop every duty to 0 as soon
as they see any other state. FAULT and ESTOP latch until reset. The controller status and
state topics are taken serialized (hems_ros.ros.wire), at each check rather than on
arrival (a wake-up per message cost more than the message).
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable
from typing import Any

from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus, KeyValue
from hems_msgs.msg import ActuatorState, CommandRecord, ControllerStatus, SupervisorStatus
from sensor_msgs.msg import JointState
from std_srvs.srv import Trigger

from hems_ros.graph import names, transmission
from hems_ros.graph.cadence import Cadence, supervisor_check_delay
from hems_ros.graph.supervisor_logic import (
    GAP_FLOOR_KEY,
    GRACE_KEY,
    HEARD_KEY,
    LOSS_LIMIT_KEY,
    TAKE_KEY,
    MonitorLimits,
    State,
    SupervisorLogic,
    gap_entries,
    longest_take,
    quiet_entry,
)
from hems_ros.ros import qos
from hems_ros.ros.clock_time import seconds, stamp_now
from hems_ros.ros.grid_timer import create_grid_timer
from hems_ros.ros.lean_node import LeanNode
from hems_ros.ros.params import PERIOD_LIMIT, Spec, declare, positive
from hems_ros.ros.runner import run_node

_LIMITS = MonitorLimits()


def _fingers(value) -> str | None:
    unknown = [f for f in value if f not in names.FINGERS]
    if not value or unknown:
        return (
            f"must be a non-empty list of fingers from {', '.join(names.FINGERS)} "
            f"(unknown: {unknown})"
        )
    return None


PARAMETERS = [
    Spec(
        "fingers", list(names.FINGERS), "fingers to supervise (all six by default)", _fingers, True
    ),
    Spec(
        "stale_s",
        _LIMITS.stale_s,
        "an encoder or wire-force stream older than this is not ready for enable, "
        "and a gap longer than this while ENABLED is counted in /diagnostics, s",
        PERIOD_LIMIT,
        True,
    ),
    Spec(
        "lost_s",
        _LIMITS.lost_s,
        "an encoder or wire-force stream without a new reading for longer than this "
        "while ENABLED is lost: a fault (the units stop heating 3 control periods into any gap), s",
        PERIOD_LIMIT,
        True,
    ),
    Spec(
        "heartbeat_timeout_s",
        _LIMITS.heartbeat_timeout_s,
        "a controller heartbeat silent for longer is a fault, s",
        PERIOD_LIMIT,
        True,
    ),
    Spec(
        "watchdog_hold_s",
        _LIMITS.watchdog_hold_s,
        "a unit's duty-watchdog flag held this long while ENABLED "
        "is a fault (a lost controller; the unit itself stops heating after 3 control periods), s",
        PERIOD_LIMIT,
        True,
    ),
    Spec(
        "enable_grace_s",
        _LIMITS.enable_grace_s,
        "while ENABLED, a unit without heating permission or an "
        "inactive controller for longer than this is a fault, s",
        PERIOD_LIMIT,
        True,
    ),
    Spec(
        "quiet_s",
        _LIMITS.quiet_s,
        "every monitored stream silent at once for longer than this is the supervisor not "
        "hearing, not each stream lost: the rest of such a quiet, up to the loss limit, counts "
        "in no stream's silence (a graph silent as a whole faults a loss limit later), s",
        PERIOD_LIMIT,
        True,
    ),
    Spec("max_wire_force_n", _LIMITS.max_wire_force_n, "wire over-force limit, N", positive, True),
    Spec(
        "max_tendon_position_m",
        _LIMITS.max_tendon_position_m,
        "tendon over-travel limit, m",
        positive,
        True,
    ),
    Spec(
        "max_wire_speed_m_s",
        _LIMITS.max_wire_speed_m_s,
        "an encoder reading moving faster than this (on the "
        "unit's stamps) has jumped: a fault, m/s",
        PERIOD_LIMIT,
        True,
    ),
    Spec(
        "max_wire_temperature_c",
        _LIMITS.max_wire_temperature_c,
        "wire over-temperature limit on the "
        "controllers' estimates (from the drive board's readings), degC",
        positive,
        True,
    ),
    Spec(
        "check_period_s",
        0.02,
        "monitor period, s: the controller status and state messages are taken "
        "and judged at each check (the controllers' statuses, which carry their readings, "
        "come at 50 Hz)",
        PERIOD_LIMIT,
        True,
    ),
    Spec(
        "status_period_s",
        0.02,
        "status re-publishing period, s (also on every change; at the checks, so in whole "
        "check periods): the units stop heating when it is older than their "
        "supervisor_timeout_s (35 ms)",
        PERIOD_LIMIT,
        True,
    ),
    Spec(
        "joint_states_period_s",
        0.02,
        "joint_states publishing period, s (at the checks)",
        PERIOD_LIMIT,
        True,
    ),
]


class SupervisorNode(LeanNode):
    """Safety supervisor of the HEMS graph."""

    def __init__(self, **node_kwargs) -> None:
        super().__init__("supervisor", namespace=names.NAMESPACE, **node_kwargs)
        self.graph_ns = self.get_namespace()
        p = declare(self, PARAMETERS)
        self.fingers = tuple(p["fingers"])
        self.logic = SupervisorLogic(
            self.fingers,
            MonitorLimits(**{f.name: p[f.name] for f in dataclasses.fields(MonitorLimits)}),
        )
        self.position = {f: float("nan") for f in self.fingers}
        self.force = {f: float("nan") for f in self.fingers}
        self.published: tuple[State, int] | None = None
        self.status_pub = self.create_publisher(
            SupervisorStatus, names.supervisor_status_topic(self.graph_ns), qos.STATUS
        )
        self.joints_pub = self.create_publisher(
            JointState, names.joint_states_topic(self.graph_ns), qos.JOINT_STATES
        )
        self.diagnostics_pub = self.create_publisher(DiagnosticArray, names.DIAGNOSTICS_TOPIC, 10)
        self.commands_pub = self.create_publisher(
            CommandRecord, names.supervisor_commands_topic(self.graph_ns), qos.COMMAND_LOG
        )
        self.commands = 0
        # finger -> (sec, nanosec) of the latest reading in its controller's status
        self.encoder_stamps: dict[str, tuple[int, int] | None] = {f: None for f in self.fingers}
        self.force_stamps: dict[str, tuple[int, int] | None] = {f: None for f in self.fingers}
        # 420 messages a second, each of which woke the process; the monitors judge them at
        # the check anyway, so the check takes them. Only these: on sim time the node also
        # subscribes to /clock, and taken at the check, which the clock drives, it stopped
        # the clock and with it every check and periodic status (the units lost their heating
        # permission 0.5 s after ENABLED).
        self.monitored = []
        for finger in self.fingers:
            self.monitored.append(
                self.subscribe_serialized(
                    ControllerStatus,
                    names.topic(finger, "controller_status", self.graph_ns),
                    lambda m, t=None, f=finger: self.on_controller(f, m, t),
                    qos.CONTROLLER_STATUS,
                )
            )
            self.monitored.append(
                self.subscribe_serialized(
                    ActuatorState,
                    names.sim_topic(finger, "state", self.graph_ns),
                    lambda m, t=None, f=finger: self.on_state(f, m, t),
                    qos.SENSOR,
                )
            )
        self.poll(*self.monitored)
        for command in names.SUPERVISOR_SERVICES:
            self.create_service(
                Trigger,
                names.service(command, self.graph_ns),
                self._service(command),
            )
        create_grid_timer(
            self,
            p["check_period_s"],
            lambda now: supervisor_check_delay(p["check_period_s"], now),
            self.check,
        )
        self.status_cadence = Cadence(p["status_period_s"], p["check_period_s"])
        self.ready = False  # every stream present, as enable needs them (judged with the status)
        self.joints_cadence = Cadence(p["joint_states_period_s"], p["check_period_s"])
        self.create_timer(1.0, self.publish_diagnostics)
        self.publish_status()

    def on_controller(self, finger: str, message, received_s: float | None = None) -> None:
        now = seconds(self) if received_s is None else received_s
        self.logic.saw("heartbeat", finger, now)
        self.logic.sees_enabled(finger, "controller", message.active, now)
        self.logic.temperature(finger, message.wire_temperature_c)
        self.logic.controller_fault(finger, message.fault, message.active)
        # a reading counts as fresh when its stamp moved since the last status (receive-side
        # judgement: no clock comparison between hosts)
        encoder = (message.encoder_stamp_sec, message.encoder_stamp_nanosec)
        if encoder != (0, 0) and encoder != self.encoder_stamps[finger]:
            self.encoder_stamps[finger] = encoder
            self.position[finger] = message.wire_position
            self.logic.encoder(finger, message.wire_position, now, encoder[0] + encoder[1] * 1e-9)
        else:
            self.logic.unchanged("encoder", finger, now)
        force = (message.force_stamp_sec, message.force_stamp_nanosec)
        if force != (0, 0) and force != self.force_stamps[finger]:
            self.force_stamps[finger] = force
            self.force[finger] = message.wire_force
            self.logic.wire_force(finger, message.wire_force, now)
        else:
            self.logic.unchanged("wire_force", finger, now)
        self.publish_if_changed()

    def on_state(self, finger: str, message, received_s: float | None = None) -> None:
        now = seconds(self) if received_s is None else received_s
        self.logic.saw("unit state", finger, now)
        self.logic.watchdog(finger, message.watchdog_tripped, now)
        self.logic.sees_enabled(finger, "unit", message.heating_allowed, now)
        self.publish_if_changed()

    def _service(self, command: str) -> Callable[[Any, Any], Any]:
        """The callback of the Trigger service of ``command``."""
        return lambda request, response: self.on_command(command, response)

    def on_command(self, command: str, response: Trigger.Response) -> Trigger.Response:
        # judge enable and reset on every report received so far: the last check's view can
        # be a check period older, and a stream then near 50 ms old looked stale to an enable
        # that came right after a successful reset
        self.take_reports()
        response.success, response.message = self.logic.request(command, seconds(self))
        self.commands += 1
        record = CommandRecord(
            node="supervisor",
            command=command,
            value=float("nan"),
            accepted=response.success,
            detail=response.message,
            sequence=self.commands,
        )
        record.header.stamp = stamp_now(self)
        self.commands_pub.publish(record)
        # rclpy ties a severity to each logging call site, so the two levels need two calls
        if command == "estop" or not response.success:
            self.get_logger().warning(f"{command}: {response.message}")
        else:
            self.get_logger().info(f"{command}: {response.message}")
        self.publish_status()
        return response

    def take_reports(self) -> None:
        """Take the controller status and unit state messages received since the last take.

        On the wall clock each counts from when the middleware received it, in that order: a
        check that ran late (the process not scheduled for a while, on a busy host) then sees
        how the streams came, not how late it looked at them; its own delay is no stream's
        gap, and a quiet of every stream is told from one stream's silence. On sim time the
        reception's system-clock time is not the graph's time: taken now."""
        if self.wall_clock:
            self.drain_in_order(*self.monitored)
            return
        for subscription in self.monitored:
            self.drain(subscription)

    def check(self) -> None:
        self.take_reports()
        now = seconds(self)
        self.logic.check_streams(now)
        if self.status_cadence.due(now):
            self.publish_status()
            self.judge_readiness(now)
        else:
            self.publish_if_changed()
        if self.joints_cadence.due(now):
            self.publish_joint_states()

    def publish_if_changed(self) -> None:
        if self.published != (self.logic.state, len(self.logic.faults)):
            self.publish_status()

    def publish_status(self) -> None:
        logic = self.logic
        if self.published is None or self.published[0] != logic.state:
            text = f"state {logic.state.name}" + (
                f": {'; '.join(map(str, logic.faults))}" if logic.faults else ""
            )
            if logic.state in (State.FAULT, State.ESTOP):
                self.get_logger().error(text)
            else:
                self.get_logger().info(text)
        self.published = (logic.state, len(logic.faults))
        status = SupervisorStatus(
            state=int(logic.state),
            state_name=logic.state.name,
            faults=[str(f) for f in logic.faults],
            fault_fingers=sorted({f.finger for f in logic.faults if f.finger}),
        )
        status.header.stamp = stamp_now(self)
        self.status_pub.publish(status)

    def publish_joint_states(self) -> None:
        # velocity is unknown here and left NaN rather than empty: rclpy serializes an empty
        # float64 array with trailing padding that the rosbags reader rejects.
        joints = JointState(
            name=list(self.fingers),
            position=[transmission.tendon_position(self.position[f]) for f in self.fingers],
            velocity=[float("nan")] * len(self.fingers),
            effort=[transmission.tendon_force(self.force[f]) for f in self.fingers],
        )
        joints.header.stamp = stamp_now(self)
        self.joints_pub.publish(joints)

    def judge_readiness(self, now: float) -> None:
        """Publish the diagnostics at once when the graph becomes ready (every stream present):
        `hems up` and `hems enable` wait for that, not for the next 1 Hz ones. A stream that
        lapses for a moment on a busy host waits for those (they name it)."""
        ready = not self.logic.missing_streams(now)
        if ready and not self.ready:
            self.get_logger().info("ready: every stream present")
            self.publish_diagnostics()
        self.ready = ready

    def publish_diagnostics(self) -> None:
        state = self.logic.state
        level = {State.FAULT: DiagnosticStatus.ERROR, State.ESTOP: DiagnosticStatus.ERROR}.get(
            state, DiagnosticStatus.OK
        )
        missing = self.logic.missing_streams(seconds(self))
        takes = self.logic.enable_takes()
        quiet_key, quiet_value = quiet_entry(self.logic.quiets())
        status = DiagnosticStatus(
            level=level,
            name=names.diagnostic_name(self.graph_ns, "supervisor"),
            hardware_id="supervisor",
            message=state.name,
            values=[KeyValue(key="ready", value=str(not missing).lower())]
            + [KeyValue(key=HEARD_KEY, value=",".join(self.logic.heard_fingers(seconds(self))))]
            + [KeyValue(key="fault", value=str(f)) for f in self.logic.faults]
            + [KeyValue(key="not ready", value=m) for m in missing]
            + [KeyValue(key=k, value=v) for k, v in gap_entries(self.logic.gaps())]
            + [KeyValue(key=quiet_key, value=quiet_value)]
            + [KeyValue(key=GAP_FLOOR_KEY, value=f"{1e3 * self.logic.limits.stale_s:.0f}")]
            + [KeyValue(key=LOSS_LIMIT_KEY, value=f"{1e3 * self.logic.limits.loss_s:.0f}")]
            + ([KeyValue(key=TAKE_KEY, value=longest_take(takes))] if takes else [])
            + [KeyValue(key=GRACE_KEY, value=f"{1e3 * self.logic.limits.enable_grace_s:.0f}")],
        )
        array = DiagnosticArray(status=[status])
        array.header.stamp = stamp_now(self)
        self.diagnostics_pub.publish(array)


def main() -> int:
    return run_node(SupervisorNode)


if __name__ == "__main__":
    raise SystemExit(main())
