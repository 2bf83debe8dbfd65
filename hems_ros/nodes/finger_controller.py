"""One finger's controller: BPID (default), PID or PI-PD in position or force mode
(hems_ros.control), Ts = 10 ms.

Setpoints are tendon side (what moves the finger); the encoder and force readings are wire
side (what the hardware measures); the controller converts through the pulley ratio.

Subscribes
  /hems/<finger>/setpoint    hems_msgs/FingerSetpoint   reliable   (mode position [m] | force [N],
                                                                   tendon side)
  /hems/<finger>/encoder     hems_msgs/EncoderReading   best effort (position-mode feedback;
                                                        the drive board's readings in the same
                                                        packet feed the wire temperature
                                                        estimate, hems_ros.graph.thermal_guard)
  /hems/<finger>/wire_force  hems_msgs/WireForce        best effort (force-mode feedback)
  /hems/supervisor/status    hems_msgs/SupervisorStatus best effort (computes duty only
                             while ENABLED;
                             read at every status_every-th step; the units stop heating on a
                             state change themselves)
Publishes
  /hems/<finger>/duty              hems_msgs/DutyCommand      best effort, one per feedback sample
  /hems/<finger>/commands          hems_msgs/CommandRecord    reliable, transient local: every
                                                              setpoint received
  /hems/<finger>/controller_status hems_msgs/ControllerStatus best effort, with every
  status_every-th duty
                                   and at once when mode, setpoint, activity or fault change
                                   (heartbeat; carries the latest encoder and force readings), and
                                   every idle_status_period_s while no feedback arrives

Gains per mode: ``gains.*`` in position mode (default Table 5.1) and ``force_gains.*`` in
force mode (default for BPID the chapter 6 force set, hems_ros.control.FORCE_MODE_BPID;
Table 5.1 for PID and PI-PD); a setpoint of the other mode switches both, without a jump
in duty.

An invalid setpoint (non-finite, outside the tendon stroke or force range, unknown mode) is
rejected with a logged error and counted in the status; the last valid setpoint stays.
Outside ENABLED, after a controller fault (non-finite input), or while the other mode's
readings lag the feedback by more than ``feedback_lag_s`` (on the unit's stamps), or while
the wire temperature estimated from the drive board's readings is at ``cut_temperature_c``
(until it is back below ``resume_temperature_c``), the duty sent is 0.
The encoder, force, duty and status topics carry serialized messages (hems_ros.ros.wire).
"""

from __future__ import annotations

from hems_msgs.msg import (
    CommandRecord,
    ControllerStatus,
    DutyCommand,
    EncoderReading,
    FingerSetpoint,
    SupervisorStatus,
    WireForce,
)

from hems_ros.graph import names
from hems_ros.graph.setpoints import SetpointError
from hems_ros.nodes.finger_controller_parameters import PARAMETERS, declare_loop
from hems_ros.ros import qos
from hems_ros.ros.clock_time import now_ns, stamp_now
from hems_ros.ros.grid_timer import until_next_call_s
from hems_ros.ros.lean_node import LeanNode
from hems_ros.ros.runner import run_node
from hems_ros.ros.wire import codec, stamp_ns

# PARAMETERS: the node's --help lists them (hems_ros.ros.runner.node_help)
__all__ = ["PARAMETERS", "FingerControllerNode", "main"]

DUTY, STATUS = codec(DutyCommand), codec(ControllerStatus)


class FingerControllerNode(LeanNode):
    """Per-finger BPID/PID/PI-PD controller: the middleware around a FingerLoop."""

    def __init__(self, **node_kwargs) -> None:
        super().__init__("finger_controller", namespace=names.NAMESPACE, **node_kwargs)
        self.graph_ns = self.get_namespace()
        p, self.loop = declare_loop(self)
        self.finger = p["finger"]
        self.sequence = 0
        self.status_sequence = 0
        self.status_every = p["status_every"]
        self._steps_since_status = 0
        self._reported: tuple | None = None
        self.duty_pub = self.create_publisher(
            DutyCommand, names.topic(self.finger, "duty", self.graph_ns), qos.DUTY
        )
        self.status_pub = self.create_publisher(
            ControllerStatus,
            names.topic(self.finger, "controller_status", self.graph_ns),
            qos.CONTROLLER_STATUS,
        )
        self.commands_pub = self.create_publisher(
            CommandRecord, names.topic(self.finger, "commands", self.graph_ns), qos.COMMAND_LOG
        )
        self.commands = 0
        self.create_subscription(
            FingerSetpoint,
            names.topic(self.finger, "setpoint", self.graph_ns),
            self.on_setpoint,
            qos.COMMAND,
        )
        self.feedback = {
            "position": self.subscribe_serialized(
                EncoderReading,
                names.topic(self.finger, "encoder", self.graph_ns),
                self.on_encoder,
                qos.SENSOR,
            ),
            "force": self.subscribe_serialized(
                WireForce,
                names.topic(self.finger, "wire_force", self.graph_ns),
                self.on_force,
                qos.SENSOR,
            ),
        }
        self.supervisor_sub = self.subscribe_serialized(
            SupervisorStatus,
            names.supervisor_status_topic(self.graph_ns),
            self.on_supervisor,
            qos.STATUS,
        )
        self._poll_other_feedback()
        # pushed back by the control steps, so it fires only while no feedback comes: a
        # wake-up of a sleeping process costs more than the status it would send
        self.idle_timer = self.create_timer(p["idle_status_period_s"], self.on_idle)
        self.idle_push_s = p["idle_status_period_s"] / 2

    def _other_feedback(self):
        return self.feedback[self.loop.other_mode]

    def _poll_other_feedback(self) -> None:
        """The stream of the other mode only feeds the status: taken when a status goes out
        (every status_every-th control step, or the idle status), instead of waking the node
        100 times a second on its own. The supervisor's status is taken at the same steps:
        it reaches the six controllers and the six units together every 20 ms, and waking
        for it made most of the loop's latency tail; the units stop heating from its arrival
        themselves, so a controller learning a state change up to status_every periods later
        changes no applied duty."""
        self.poll(self._other_feedback(), self.supervisor_sub)

    # inputs -------------------------------------------------------------------
    def on_setpoint(self, message: FingerSetpoint) -> None:
        if message.mode != self.loop.setpoint.mode and message.mode in self.feedback:
            # a switch carries the output over from that mode's latest reading
            self.drain(self.feedback[message.mode])
        try:
            setpoint = self.loop.set_point(message.mode, message.value)
        except SetpointError as error:
            kept = self.loop.setpoint
            self.get_logger().error(
                f"{self.finger}: setpoint rejected: {error}; keeping {kept.mode} {kept.value:g}"
            )
            self.record(message, False, str(error))
            self.publish_status()
            return
        self.record(message, True, "")
        self._poll_other_feedback()
        self.get_logger().info(f"{self.finger}: setpoint {setpoint.mode} {setpoint.value:g}")

    def record(self, message: FingerSetpoint, accepted: bool, detail: str) -> None:
        """The setpoint as received, on /hems/<finger>/commands (hems_msgs/CommandRecord)."""
        self.commands += 1
        record = CommandRecord(
            node=self.get_name(),
            command=str(message.mode),
            value=float(message.value),
            accepted=accepted,
            detail=detail,
            sequence=self.commands,
        )
        record.header.stamp = stamp_now(self)
        self.commands_pub.publish(record)

    def on_supervisor(self, message) -> None:
        self.loop.supervisor(message.state == SupervisorStatus.ENABLED)

    def on_encoder(self, message) -> None:
        """The unit's packet: the encoder reading, and the drive's measurement over the period
        that ended, which the thermal guard takes before any duty is computed from it."""
        self.loop.guard.reading(message.duty_percent, message.on_current, message.on_voltage)
        stamp = (message.header_stamp_sec, message.header_stamp_nanosec)
        if self.loop.reading("position", message.position, stamp):
            self.control(stamp)

    def on_force(self, message) -> None:
        stamp = (message.header_stamp_sec, message.header_stamp_nanosec)
        if self.loop.reading("force", message.force, stamp):
            self.control(stamp)

    # control ------------------------------------------------------------------
    def on_idle(self) -> None:
        self.drain(self.supervisor_sub)
        self.publish_status()

    def control(self, measurement_stamp: tuple[int, int]) -> None:
        self._steps_since_status += 1
        status_due = self._steps_since_status >= self.status_every
        if status_due:
            self.drain(self.supervisor_sub)
        if self.loop.setpoint.mode == "force":
            # the unit's packets, polled in force mode, still feed the thermal guard every step
            self.drain(self.feedback["position"])
        duty = self.loop.step(self.loop.enabled and self._other_fresh(measurement_stamp))
        self.sequence += 1
        sec, nanosec = stamp_ns(now_ns(self))
        self.duty_pub.publish(
            DUTY.encode(
                DUTY.fields(
                    header_stamp_sec=sec,
                    header_stamp_nanosec=nanosec,
                    header_frame_id="",
                    finger=self.finger,
                    duty_percent=duty,
                    measurement_stamp_sec=measurement_stamp[0],
                    measurement_stamp_nanosec=measurement_stamp[1],
                    sequence=self.sequence,
                )
            )
        )
        # a reset wakes the node's wait set (rcl's timer guard condition): once per half
        # period, not at every step, where it cost a second pass of the spin loop
        if until_next_call_s(self.idle_timer) < self.idle_push_s:
            self.idle_timer.reset()
        if status_due or self.loop.status_key() != self._reported:
            self.publish_status()

    def _other_fresh(self, measurement_stamp: tuple[int, int]) -> bool:
        """The other mode's stream is polled at the statuses: when its latest reading looks
        stale, take what came meanwhile before deciding."""
        if self.loop.other_fresh(measurement_stamp):
            return True
        self.drain(self._other_feedback())
        return self.loop.other_fresh(measurement_stamp)

    def publish_status(self) -> None:
        self.drain(self._other_feedback())
        self.status_sequence += 1
        self._steps_since_status = 0
        self._reported = self.loop.status_key()
        sec, nanosec = stamp_ns(now_ns(self))
        self.status_pub.publish(
            STATUS.encode(
                STATUS.fields(
                    header_stamp_sec=sec,
                    header_stamp_nanosec=nanosec,
                    header_frame_id="",
                    finger=self.finger,
                    sequence=self.status_sequence,
                    **self.loop.status_fields(),
                )
            )
        )


def main() -> int:
    return run_node(FingerControllerNode)


if __name__ == "__main__":
    raise SystemExit(main())
