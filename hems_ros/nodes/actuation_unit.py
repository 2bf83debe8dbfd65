"""One HEMS actuation unit: SMA wire in its Bowden sheath, slider with pulley, tendon and
glove load, slider encoder (hems_ros.physics, integrated at 1 kHz of simulated time).

Subscribes
  /hems/<finger>/duty            hems_msgs/DutyCommand    best effort (on wall-clock time taken at
                                                          the ticks, see below)
  /hems/supervisor/status        hems_msgs/SupervisorStatus  best effort, every 20 ms (heating
                                                             only while ENABLED)
Publishes
  /hems/<finger>/encoder         hems_msgs/EncoderReading  best effort, every encoder_period_s:
                                                           the drive board's packet (encoder,
                                                           wire side, m; applied duty,
                                                           on-current and on-voltage)
  /hems/sim/<finger>/wire_tension hems_msgs/WireForce      best effort, same rate (simulation link
                                                           to the shoulder module)
  /hems/sim/<finger>/state       hems_msgs/ActuatorState   best effort, every state_period_s
                                                           (simulation truth)
  /diagnostics                   diagnostic_msgs/DiagnosticArray  1 Hz (latency, missed
                                                                  periods, watchdog)

Duty watchdog: no duty command for three control periods sets the duty to 0 and flags it.

On wall-clock time the unit does not wake for a duty command: it takes the commands at its
next tick, before integrating, each at the time the middleware received it. Nothing
observes the simulated plant between ticks, so the physics is the same as if the unit had
woken on arrival (a command answering the latest encoder sample takes effect from that
sample either way, hems_ros.graph.unit_driver), at one wake-up a period instead of two; the
latency in /diagnostics is measured to the reception. The supervisor's statuses (every 20 ms)
are taken at the ticks too, in the order the commands and they came, each from its own
reception: an ESTOP stops the heating from the moment it came. On sim time (/clock)
reception times are not in the node's clock, so commands are handled on arrival; with the
lockstep clock the answer and the statuses are taken at the steps, and the unit waits for
those the clock has made sure were sent, so a run's figures do not depend on the host's
pace. On wall-clock time the ticks also fall on the clock's grid at the shoulder module's phase
(hems_ros.graph.cadence.tick_delay).

The duty, encoder, tension and state topics carry serialized messages (hems_ros.ros.wire).
"""

from __future__ import annotations

import time
from collections.abc import Callable

from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus, KeyValue
from hems_msgs.msg import (
    ActuatorState,
    DutyCommand,
    EncoderReading,
    SupervisorStatus,
    WireForce,
)

from hems_ros.graph import names
from hems_ros.graph.cadence import Cadence, tick_delay
from hems_ros.graph.lockstep_clock import STALL_S
from hems_ros.graph.sensor_faults import ENCODER_FAULTS, FaultySensor
from hems_ros.graph.unit_driver import UnitDriver
from hems_ros.physics import ActuationUnit, load_params
from hems_ros.ros import qos
from hems_ros.ros.clock_time import seconds, stamp_now
from hems_ros.ros.grid_timer import create_grid_timer, until_next_call_s
from hems_ros.ros.lean_node import LeanNode
from hems_ros.ros.params import PERIOD_LIMIT, WINDOW_LIMIT, Spec, declare, one_of
from hems_ros.ros.runner import run_node
from hems_ros.ros.wire import codec, seconds_of, stamp

LOCKSTEP_POLL_S = 0.0002
ENCODER, TENSION, STATE = (codec(t) for t in (EncoderReading, WireForce, ActuatorState))

PARAMETERS = [
    Spec(
        "finger",
        "index",
        "finger this unit drives: " + ", ".join(names.FINGERS),
        one_of(*names.FINGERS),
        True,
    ),
    Spec(
        "physics_config",
        "ch6_hems_index",
        "physics parameter set: a name in config/physics/ or a YAML path",
        None,
        True,
    ),
    Spec("physics_dt_s", 0.001, "physics integration step, s (1 kHz default)", PERIOD_LIMIT, True),
    Spec(
        "tick_period_s",
        0.01,
        "period of the integration and encoder-publishing timer, s "
        "(duty commands are taken at the ticks, at their reception times)",
        PERIOD_LIMIT,
        True,
    ),
    Spec(
        "encoder_period_s",
        0.01,
        "encoder and wire-tension publishing period, s (100 Hz)",
        PERIOD_LIMIT,
        True,
    ),
    Spec(
        "state_period_s",
        0.05,
        "simulation-truth state publishing period, s (20 Hz; on the tick, so in whole "
        "tick periods)",
        PERIOD_LIMIT,
        True,
    ),
    Spec(
        "control_period_s",
        0.01,
        "controller period Ts, s; the watchdog trips after three",
        PERIOD_LIMIT,
        True,
    ),
    Spec("require_supervisor", True, "heat only while the supervisor reports ENABLED", None, True),
    Spec(
        "supervisor_timeout_s",
        0.035,
        "supervisor status older than this withdraws heating permission, s: the supervisor "
        "sends one every 20 ms, so a stopped or killed one stops the heating within this",
        PERIOD_LIMIT,
        True,
    ),
    Spec(
        "latency_window_s",
        60.0,
        "the latency figures in /diagnostics cover the duty commands of the last "
        "this many seconds",
        WINDOW_LIMIT,
        True,
    ),
    Spec(
        "lockstep",
        False,
        "on sim time from the lockstep clock (hems up --sim-time): take the controller's answer "
        "to the latest sample before each step, since the clock moved on only after it was sent; "
        "waited for as long as the clock waits for it (5 s of wall time), from the controller's "
        "first answer on",
        None,
        True,
    ),
    Spec(
        "sensor_fault",
        "",
        "encoder fault injected from now on, for fault tests: '' (none), stuck_encoder "
        "(fresh samples, frozen reading), encoder_jump (+5 mm), nan_encoder (NaN position); "
        "settable while running",
        one_of(*ENCODER_FAULTS),
    ),
]


class ActuationUnitNode(LeanNode):
    """Simulated HEMS actuation unit."""

    def __init__(self, **node_kwargs) -> None:
        super().__init__("actuation_unit", namespace=names.NAMESPACE, **node_kwargs)
        self.graph_ns = self.get_namespace()
        p = self.params = declare(self, PARAMETERS)
        self.finger = p["finger"]
        try:
            physics = load_params(p["physics_config"])
        except (OSError, ValueError) as error:
            raise ValueError(
                f"parameter 'physics_config' = {p['physics_config']!r}: {error}"
            ) from None
        # the shoulder module measures this unit's wire tension with its own noisy sensor; the
        # model's sensor reading is not published here, and noiseless it costs no draws
        physics = physics.replace({"force_sensor.noise_std_n": 0.0})
        tick = create_grid_timer(
            self,
            p["tick_period_s"],
            lambda now: tick_delay(self.finger, p["tick_period_s"], now),
            self.on_tick,
        )
        # The physics starts one period before the first tick, so encoder samples fall due on
        # the ticks and go out at once; a grid shifted from the timer's held each sample back
        # for up to a period, and the duties answering it often came after the next one.
        start_s = seconds(self) + until_next_call_s(tick) - p["tick_period_s"]
        self.driver = UnitDriver(
            ActuationUnit(physics, dt=p["physics_dt_s"]),
            start_time_s=start_s,
            sample_period_s=p["encoder_period_s"],
            watchdog_timeout_s=3 * p["control_period_s"],
            permission_timeout_s=p["supervisor_timeout_s"],
            require_permission=p["require_supervisor"],
            latency_window_s=p["latency_window_s"],
        )
        self.resolution = physics.encoder.resolution_m
        self.sequence = 0
        self.state_sequence = 0
        self.encoder_pub = self.create_publisher(
            EncoderReading, names.topic(self.finger, "encoder", self.graph_ns), qos.SENSOR
        )
        self.encoder_sensor = FaultySensor()
        self.tension_pub = self.create_publisher(
            WireForce, names.sim_topic(self.finger, "wire_tension", self.graph_ns), qos.SENSOR
        )
        self.state_pub = self.create_publisher(
            ActuatorState, names.sim_topic(self.finger, "state", self.graph_ns), qos.SENSOR
        )
        self.diagnostics_pub = self.create_publisher(DiagnosticArray, names.DIAGNOSTICS_TOPIC, 10)
        self.duty_sub = self.subscribe_serialized(
            DutyCommand,
            names.topic(self.finger, "duty", self.graph_ns),
            self.on_duty,
            qos.DUTY,
            on_unreadable=self.on_unreadable_duty,
        )
        # lockstep: answers are taken at the steps, each as if received at its sample
        self.lockstep = p["lockstep"] and not self.wall_clock
        # a finger takes part from its controller's first answer, as on the clock
        self.answering = False
        self.supervisor_keeps_up = True
        self.supervisor_sub = self.subscribe_serialized(
            SupervisorStatus,
            names.supervisor_status_topic(self.graph_ns),
            self.on_supervisor,
            qos.STATUS_EACH,
        )
        # On the wall clock the unit wakes only for its ticks: what came since the last one is
        # taken there, in the order it came, each from its reception time (a status's 10 Hz
        # wake-up of six units cost as much as a tenth of their ticks)
        if self.wall_clock or self.lockstep:
            self.poll(self.duty_sub, self.supervisor_sub)
        self.state_cadence = Cadence(p["state_period_s"], p["tick_period_s"])
        self.create_timer(1.0, self.publish_diagnostics)
        self.get_logger().info(f"{self.finger}: physics '{physics.name}', dt {p['physics_dt_s']} s")

    def on_duty(self, message, received_s: float | None = None) -> None:
        now = seconds(self) if received_s is None else received_s
        measured = seconds_of(message.measurement_stamp_sec, message.measurement_stamp_nanosec)
        # up to the arrival with the old duty (publishing a sample that fell due); the new one
        # acts from the sample it answers, or from the arrival if it came late, when the
        # physics next advances (nothing observes the plant in between)
        if not self.driver.will_rewind(message.duty_percent, measured, now):
            self.advance_to(now)
        try:
            self.driver.command(message.duty_percent, now, measured)
        except ValueError as error:
            self.get_logger().error(f"{self.finger}: {error}; applying 0 %")

    def on_unreadable_duty(self, received_s: float | None = None) -> None:
        self.advance_to(seconds(self) if received_s is None else received_s)
        self.driver.reject()

    def on_supervisor(self, message, received_s: float | None = None) -> None:
        """A status as it came (``received_s`` None: now; in lockstep its own stamp), or as
        taken at a tick with the time it came, after the commands that came before it."""
        if received_s is not None:
            now = received_s
        elif self.lockstep:
            now = seconds_of(message.header_stamp_sec, message.header_stamp_nanosec)
        else:
            now = seconds(self)
        enabled = message.state == SupervisorStatus.ENABLED
        if enabled and self.driver.permitted(now):
            # the periodic ENABLED that keeps the permission alive: allowed without a break
            # from the last step to now, so it only moves the lapse time on
            self.driver.permit_heating(True, now)
            return
        if not enabled and self.driver.permission_s is None:
            return  # the periodic status of a graph not enabled: nothing was allowed
        # commands that came before this status act first, and the plant runs with the old
        # permission up to it: taken at the next tick instead, a command answering the latest
        # sample would integrate again from that sample under the new permission, and stop
        # (or start) the heating before the status came
        if self.wall_clock and received_s is None:
            self.drain(self.duty_sub, with_reception_time=True)
        self.advance_to(now)
        was_allowed = self.driver.permitted(now)
        self.driver.permit_heating(enabled, now)
        if was_allowed != self.driver.permitted(now):
            # the moment heating stopped, for the record; the moment it was allowed, for the
            # supervisor, which faults a unit that has not taken its ENABLED
            self.publish_state()

    def on_tick(self) -> None:
        now = seconds(self)
        if self.wall_clock:
            self.drain_in_order(self.duty_sub, self.supervisor_sub)
        elif self.lockstep:
            self.take_answer()
            self.take_statuses(now)
        self.advance_to(now)
        if self.state_cadence.due(now):
            self.publish_state()

    def take_answer(self) -> None:
        """Lockstep: the clock took this step only after the controller had answered the
        latest sample, so the answer is here or on its way; it acts from its sample, as the
        board's would. A busy host only delays it, so it is waited for as long as the clock
        waits; a controller that stopped answering is not waited for again until it answers."""
        at = self.driver.time_s
        self.answering = self._wait_for(
            lambda: self.drain(self.duty_sub, at=at),
            lambda: self.driver.latest_sample_answered,
            self.answering,
        )

    def take_statuses(self, now: float) -> None:
        """Lockstep: the supervisor's statuses, each from its own stamp. The clock moves on only
        while the supervisor's latest status is at most 20 ms old (``SUPERVISOR_LAG_S``), so a
        status within the heating permission's timeout of ``now`` has been sent: it is waited
        for, and a slow host does not pause the heating (it gave other figures at every rate).
        One that does not come within the clock's stall time (a stopped supervisor) is not
        waited for again until one comes; the permission lapses meanwhile."""
        self.supervisor_keeps_up = self._wait_for(
            lambda: self.drain(self.supervisor_sub),
            lambda: not self.driver.permission_lapses_by(now),
            self.supervisor_keeps_up,
        )

    @staticmethod
    def _wait_for(take: Callable[[], None], arrived: Callable[[], bool], waiting: bool) -> bool:
        """Take messages until ``arrived`` (True), for up to the clock's stall time if
        ``waiting``, else once (False unless it arrived)."""
        deadline = time.monotonic() + STALL_S
        while True:
            take()
            if arrived():
                return True
            if not waiting or time.monotonic() >= deadline:
                return False
            time.sleep(LOCKSTEP_POLL_S)

    def advance_to(self, now: float) -> None:
        """Integrate the physics up to ``now``; publish the encoder samples that fell due."""
        was_tripped = self.driver.watchdog_tripped
        samples = self.driver.advance(now)
        if self.driver.watchdog_tripped != was_tripped:
            self.publish_state()
        for sample in samples:
            self.sequence += 1
            sec, nanosec = stamp(sample.time_s)
            counts, position = self.encoder_reading(sample)
            self.encoder_pub.publish(
                ENCODER.encode(
                    ENCODER.fields(
                        header_stamp_sec=sec,
                        header_stamp_nanosec=nanosec,
                        header_frame_id="",
                        finger=self.finger,
                        counts=counts,
                        position=position,
                        resolution=self.resolution,
                        duty_percent=sample.duty_percent,
                        on_current=sample.on_current_a,
                        on_voltage=sample.on_voltage_v,
                        sequence=self.sequence,
                    )
                )
            )
            self.tension_pub.publish(
                TENSION.encode(
                    TENSION.fields(
                        header_stamp_sec=sec,
                        header_stamp_nanosec=nanosec,
                        header_frame_id="",
                        finger=self.finger,
                        force=sample.wire_force_n,
                        saturated=False,
                        over_force=False,
                        sequence=self.sequence,
                    )
                )
            )

    def encoder_reading(self, sample) -> tuple[int, float]:
        """(counts, position m) the encoder reports, with the injected fault if one is set
        (``ros2 param set ... sensor_fault stuck_encoder``)."""
        return self.encoder_sensor.encoder(
            self.params["sensor_fault"],
            sample.encoder_counts,
            sample.encoder_position_m,
            self.resolution,
        )

    def publish_state(self) -> None:
        r = self.driver.last_result
        if r is None:
            return
        self.state_sequence += 1
        at = max(self.driver.time_s, seconds(self))
        sec, nanosec = stamp(at)
        self.state_pub.publish(
            STATE.encode(
                STATE.fields(
                    header_stamp_sec=sec,
                    header_stamp_nanosec=nanosec,
                    header_frame_id="",
                    finger=self.finger,
                    duty_percent=self.driver.applied_duty,
                    watchdog_tripped=self.driver.watchdog_tripped,
                    heating_allowed=self.driver.permitted(at),
                    wire_temperature_c=r.wire_temperature_c,
                    martensite_fraction=r.martensite_fraction,
                    resistance=r.resistance_ohm,
                    current=r.current_a,
                    electrical_power=r.electrical_power_w,
                    electrical_energy=r.energy_joule_j,
                    stress=r.stress_pa,
                    strain=r.strain,
                    sheath_temperature_c=r.sheath_temperature_c,
                    slider_position=r.slider_position_m,
                    slider_velocity=r.slider_velocity_m_s,
                    tendon_position=r.tendon_position_m,
                    tendon_force=r.tendon_force_n,
                    wire_force=r.wire_force_n,
                    sequence=self.state_sequence,
                )
            )
        )

    def publish_diagnostics(self) -> None:
        d = self.driver
        p50, p99, worst = d.latency_percentiles()
        values = {
            "applied_duty_percent": d.applied_duty,
            "watchdog_tripped": d.watchdog_tripped,
            "duty_commands": d.commands,
            "rejected_commands": d.rejected_commands,
            "missed_control_periods": d.missed_periods,
            "late_commands": d.late_commands,
            "supervisor_status_lapses": d.permission_lapses,
            "latency_p50_s": p50,
            "latency_p99_s": p99,
            "latency_max_s": worst,
            "latency_window_s": d.latency_window_s,
            "simulated_time_s": d.unit.time,
        }
        status = DiagnosticStatus(
            level=DiagnosticStatus.WARN if d.watchdog_tripped else DiagnosticStatus.OK,
            name=names.diagnostic_name(self.graph_ns, "actuation_unit", self.finger),
            hardware_id=f"actuation_unit_{self.finger}",
            message="duty watchdog tripped: duty 0" if d.watchdog_tripped else "running",
            values=[KeyValue(key=k, value=str(v)) for k, v in values.items()],
        )
        array = DiagnosticArray(status=[status])
        array.header.stamp = stamp_now(self)
        self.diagnostics_pub.publish(array)


def main() -> int:
    return run_node(ActuationUnitNode)


if __name__ == "__main__":
    raise SystemExit(main())
