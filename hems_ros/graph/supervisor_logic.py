"""The supervisor's state machine and stream monitors (plain Python, no ROS).

States: IDLE -> ENABLED <-> DISABLED; any monitored fault latches FAULT, ``estop`` latches
ESTOP; both stay until ``reset``, which is refused while a fault condition persists.
Heating is allowed only in ENABLED, so every other state means zero duty.

Monitors (per finger, on the receive times of the streams, in the node's clock): wire force
at or above ``max_wire_force_n``, tendon travel beyond ``max_tendon_position_m`` and a wire
temperature estimated at or above ``max_wire_temperature_c`` fault in any state; while ENABLED, an
encoder or wire-force stream without a new reading for longer than ``lost_s`` (a lost stream), a
controller heartbeat silent for longer than ``heartbeat_timeout_s``, and the actuation unit's
duty-watchdog flag held for ``watchdog_hold_s`` fault too. Outside ENABLED nothing heats, so a
silent stream (a node starting or restarting) only blocks ``enable`` and ``reset`` until it is back.

A gap longer than ``stale_s`` but shorter than a loss is counted, not latched
(:meth:`SupervisorLogic.gaps`): a host that is busy for a moment (a command-line tool
joining the domain, a garbage collection) delays streams by tens of milliseconds, and
heating is already safe through it without the supervisor. A controller computes a duty
only for a new reading, so no reading means no command, and the unit's duty watchdog is
at 0 % three control periods after the last one; a controller in position mode whose force
readings fall behind its encoder (or in force mode, the reverse) sends 0 % itself
(finger_controller). What the supervisor adds is the latch for a loss that persists.

``enable`` and ``reset`` also wait for every unit's state report, and for its controller's
commands (0 % before ENABLED) to reach it: a watchdog flag up since the unit started, or
for ``watchdog_hold_s``, refuses them (:meth:`SupervisorLogic.watchdog`). Encoder readings and a
controller heartbeat do not show that path; right after start-up a unit whose duty reader
had not yet matched its controller's writer was enabled, its watchdog flag stayed up and
latched FAULT some 100 ms later (about one ``make demo`` in five).

A unit heats, and a controller computes duty, only once it has taken the ENABLED status
itself. One that has not (its status reader unmatched) leaves its finger cold while the
rest of the graph looks healthy, so ENABLED also faults a unit reporting no heating
permission, or a controller reporting itself inactive, for ``enable_grace_s``.

The encoder and force readings reach the supervisor inside the controller's reports
(:meth:`SupervisorLogic.unchanged`), so a sensor stream is judged when a report comes: a
report whose reading has not moved for longer than ``stale_s`` faults that stream. While
no report comes the supervisor cannot tell a silent sensor from a late controller, and the
controller heartbeat judges; blaming the sensor there made every controller stall of some
40 ms on a busy host a "stale encoder" FAULT, while the encoder was running.

A silence of every monitored stream at once is not each node's loss: one process or one
thread held up the whole graph's traffic to the supervisor (its own stall, or a newcomer's
discovery on a busy host). Such a quiet beyond ``quiet_s`` is counted apart
(:meth:`SupervisorLogic.quiets`) and, up to one loss limit, in no stream's silence.
"""

from __future__ import annotations

import math
from collections.abc import Iterable
from dataclasses import dataclass, field
from enum import IntEnum

from hems_ros.graph.transmission import tendon_position

STREAMS = ("encoder", "wire_force", "heartbeat", "unit state")


class State(IntEnum):
    IDLE = 0
    ENABLED = 1
    DISABLED = 2
    FAULT = 3
    ESTOP = 4


@dataclass(frozen=True)
class MonitorLimits:
    # a sensor stream older than this is not ready for ``enable``, and a gap longer than this
    # is counted as a transient gap
    stale_s: float = 0.05
    # a sensor stream without a new reading for this long while ENABLED is lost: FAULT. The
    # units are at 0 % duty 30 ms into any gap (module docstring), so this only decides when
    # the loss is named: with the checks (20 ms) and the status that carries the FAULT, within
    # 0.5 s of the loss. Command-line joins delay single streams of the separate-process graph
    # by up to some 390 ms on the two-core host (docs/reliability.md)
    lost_s: float = 0.4
    max_wire_force_n: float = 50.0
    max_tendon_position_m: float = 0.056
    # a controller's wire-temperature estimate (from the drive board's readings) this high: the
    # controller's own cut-off (150 degC by default) did not hold the wire
    max_wire_temperature_c: float = 170.0
    # no wire moves this fast: the model's fastest contraction is about 35 mm/s at full duty
    # (docs/experiments.md); a reading that does has jumped (a slipped encoder, a bad count)
    max_wire_speed_m_s: float = 0.2
    # A lost controller is already caught within 30 ms by each unit's duty watchdog; the
    # heartbeat only has to name it, so it tolerates the scheduling hiccups of a busy host,
    # as long as the watchdog flag does (watchdog_hold_s). At 200 ms it latched FAULT in one
    # `make demo` of fifteen: two controllers silent 200 ms together just after ENABLED on the
    # two-core host, both running again within 10 ms of the fault.
    heartbeat_timeout_s: float = 0.4
    # The unit's own watchdog has already set its duty to 0 after 30 ms; the flag held this
    # long means a duty path that does not deliver (a dead controller is named by its
    # heartbeat too). Shorter holds latched FAULT on a live graph just after start-up: at
    # 50 ms for controllers held up 54-101 ms by the busy host (8 of 20 starts,
    # benchmarks/bench_graph_startup.py), at 200 ms once in 10 starts for 210 ms without
    # commands: about as long as a reliable reader held later samples back behind a lost
    # one until its repair (why the controller status and the duty commands are best
    # effort, ros/qos.py), the likely cause, not confirmed.
    watchdog_hold_s: float = 0.5
    # Units and controllers take a new state from the status that follows it (20 ms) and say
    # so in their next report: two deliveries, each of which the stream checks let be late by
    # up to lost_s (400 ms) before they fault. Judged no more strictly, the grace is at least
    # 2 x 400 ms plus the two periods; a finger that has not taken ENABLED is cold, so a longer
    # grace only names it later. At 0.5 s it latched FAULT once beside the full test suite
    # (502 ms); with both cores busy the longest take was 91 ms (docs/reliability.md).
    enable_grace_s: float = 1.0
    # Every monitored stream silent at once for longer than this is the supervisor not
    # hearing (its process or its reception held up: a join's discovery on a busy host), not
    # each stream lost: such a quiet beyond it, up to loss_s, is not counted in any stream's
    # silence. Above the slowest report period a live graph keeps (a controller without new
    # readings reports every 100 ms), so one lost stream of a one-finger graph still faults on
    # time; a graph silent as a whole faults after loss_s more.
    quiet_s: float = 0.15

    def timeout(self, stream: str) -> float:
        """How old a stream's last message may be for ``enable``: the unit state comes at 20 Hz
        and, like the heartbeat, is not judged to the tens of milliseconds."""
        return self.stale_s if stream in ("encoder", "wire_force") else self.heartbeat_timeout_s

    @property
    def loss_s(self) -> float:
        """The shortest silence of a stream that faults (lost_s, heartbeat_timeout_s)."""
        return min(self.lost_s, self.heartbeat_timeout_s)

    def gap_s(self, stream: str) -> float:
        """A silence longer than this is counted as a gap: ``stale_s``, and for the unit state,
        which comes every 50 ms (the units' ``state_period_s``), twice that."""
        return 2 * self.stale_s if stream == "unit state" else self.stale_s

    def __post_init__(self) -> None:
        for name in (
            "stale_s",
            "lost_s",
            "max_wire_force_n",
            "max_tendon_position_m",
            "max_wire_temperature_c",
            "max_wire_speed_m_s",
            "heartbeat_timeout_s",
            "watchdog_hold_s",
            "enable_grace_s",
            "quiet_s",
        ):
            value = getattr(self, name)
            if not (math.isfinite(value) and value > 0):
                raise ValueError(f"{name} = {value!r}: must be a finite value > 0")


@dataclass
class Fault:
    finger: str
    kind: str  # one fault per finger and kind is kept: the first occurrence
    text: str

    def __str__(self) -> str:
        return f"{self.finger}: {self.text}" if self.finger else self.text


@dataclass
class SupervisorLogic:
    fingers: tuple[str, ...]
    limits: MonitorLimits = field(default_factory=MonitorLimits)
    state: State = State.IDLE
    faults: list[Fault] = field(default_factory=list)

    def __post_init__(self) -> None:
        self._last_seen: dict[tuple[str, str], float] = {}
        self._enabled_at = float("inf")
        self._last_check: float | None = None
        # silences are judged from here at the earliest: the end of the supervisor's latest
        # stall of half a loss limit or more (check_streams)
        self._listening_since = -math.inf
        # the supervisor's own quiets (quiet_s): the latest reception of any monitored stream,
        # the quiet excused so far in total, and that total at each stream's last message, at
        # the enable and at the resume (where a silence may begin)
        self._heard_at: float | None = None
        self._excused = 0.0
        self._excused_at_seen: dict[tuple[str, str], float] = {}
        self._excused_at_enable = 0.0
        self._excused_at_resume = 0.0
        self._quiets: list[float] = [0, 0.0]
        # (finger, condition) -> receive time of the first report of a condition that has held
        # since: a unit's watchdog trip (-inf while the unit has not yet reported its commands
        # arriving), a unit or controller not having taken ENABLED
        self._since: dict[tuple[str, str], float] = {}
        self._duty_seen: set[str] = set()
        # (finger, stream) -> [number of gaps longer than stale_s while ENABLED, longest s]
        self._gaps: dict[tuple[str, str], list[float]] = {}
        # (finger, component) -> the longest time from an enable to its first report of having
        # taken ENABLED; those that have reported so since the latest enable
        self._takes: dict[tuple[str, str], float] = {}
        self._taken: set[tuple[str, str]] = set()
        # finger -> (stamp s, wire position m) of the latest encoder reading
        self._readings: dict[str, tuple[float, float]] = {}

    # observations -------------------------------------------------------------
    def saw(self, stream: str, finger: str, now: float) -> None:
        """A message of ``stream`` from ``finger`` received at ``now``; messages are taken in
        the order they were received."""
        self._hear(now)
        silence = self._silence(stream, finger, now)
        if self.state == State.ENABLED and silence > self.limits.gap_s(stream):
            gap = self._gaps.setdefault((finger, stream), [0, 0.0])
            gap[0] += 1
            gap[1] = max(gap[1], silence)
        self._last_seen[(stream, finger)] = now
        self._excused_at_seen[(stream, finger)] = self._excused

    def _hear(self, now: float) -> None:
        if self._heard_at is not None and now > self._heard_at:
            quiet = now - self._heard_at
            self._excused += self._excuse(quiet)
            if self.state == State.ENABLED and quiet > self.limits.quiet_s:
                self._quiets[0] += 1
                self._quiets[1] = max(self._quiets[1], quiet)
        self._heard_at = now if self._heard_at is None else max(self._heard_at, now)

    def _excuse(self, quiet: float) -> float:
        """The part of a quiet of every stream that counts in no stream's silence."""
        return min(max(0.0, quiet - self.limits.quiet_s), self.limits.loss_s)

    def _excused_by(self, now: float) -> float:
        ongoing = 0.0 if self._heard_at is None else self._excuse(now - self._heard_at)
        return self._excused + ongoing

    def _silence(self, stream: str, finger: str, now: float) -> float:
        """How long ``stream`` of ``finger`` has been silent by ``now`` while ENABLED and while
        the supervisor was listening and hearing other streams (0 if never seen)."""
        seen = self._last_seen.get((stream, finger))
        if seen is None:
            return 0.0
        since, excused = seen, self._excused_at_seen[(stream, finger)]
        if self._enabled_at > since:
            since, excused = self._enabled_at, self._excused_at_enable
        if self._listening_since > since:
            since, excused = self._listening_since, self._excused_at_resume
        return now - since - (self._excused_by(now) - excused)

    def unchanged(self, stream: str, finger: str, now: float) -> None:
        """A controller reported the same ``stream`` reading ("encoder" or "wire_force") as
        before (a new one goes to :meth:`encoder` or :meth:`wire_force`): while ENABLED, a
        reading unchanged for longer than ``lost_s`` faults the stream."""
        silence = self._silence(stream, finger, now)
        if self.state == State.ENABLED and silence > self.limits.lost_s:
            self._fault(
                finger, stream, f"{stream} lost ({1e3 * silence:.0f} ms without a new reading)"
            )

    def gaps(self) -> dict[tuple[str, str], tuple[int, float]]:
        """Gaps of every stream (sensor readings, heartbeats, unit states) longer than
        :meth:`MonitorLimits.gap_s` and shorter than a loss, while ENABLED, by (finger,
        stream): (count, longest s). Transient: counted for the diagnostics, and the margin
        the loss limits keep over them (docs/reliability.md)."""
        return {key: (int(count), longest) for key, (count, longest) in self._gaps.items()}

    def quiets(self) -> tuple[int, float]:
        """The supervisor's own quiets while ENABLED: every monitored stream silent at once for
        longer than ``quiet_s``, (count, longest s). What a quiet lasts beyond ``quiet_s`` (up
        to ``loss_s``) is in no stream's gap (:meth:`gaps`)."""
        return int(self._quiets[0]), self._quiets[1]

    def enable_takes(self) -> dict[tuple[str, str], float]:
        """By (finger, "unit" or "controller"): the longest time, over the enables so far, from
        an enable to the first report of having taken ENABLED. The margin ``enable_grace_s``
        keeps over them (docs/reliability.md)."""
        return dict(self._takes)

    def wire_force(self, finger: str, force_n: float, now: float) -> None:
        self.saw("wire_force", finger, now)
        if not math.isfinite(force_n):
            self._fault(finger, "wire_force", f"wire_force reading {force_n} (a failed sensor)")
        elif force_n >= self.limits.max_wire_force_n:
            self._fault(
                finger,
                "over-force",
                f"wire over-force {force_n:.1f} N (limit {self.limits.max_wire_force_n:g} N)",
            )

    def controller_fault(self, finger: str, fault: str, active: bool) -> None:
        """A controller that reports a fault (a non-finite input) while active sends 0 % until
        its next enable clears it: the finger is lost to control, which the graph must show.
        An inactive controller heats nothing and reports the fault it tripped on until that
        enable: latched again after a reset, it would refuse the enable that clears it."""
        if fault and active:
            self._fault(finger, "controller", f"controller fault: {fault}")

    def temperature(self, finger: str, celsius: float) -> None:
        """A controller's wire-temperature estimate: at or above ``max_wire_temperature_c`` it
        faults in any state (a NaN estimate, none yet, says nothing)."""
        if celsius >= self.limits.max_wire_temperature_c:
            self._fault(
                finger,
                "over-temperature",
                f"wire over-temperature {celsius:.0f} degC estimated "
                f"(limit {self.limits.max_wire_temperature_c:g} degC)",
            )

    def encoder(
        self, finger: str, wire_position_m: float, now: float, stamp_s: float | None = None
    ) -> None:
        """A new encoder reading, received at ``now``; ``stamp_s`` its sample's stamp (the unit's
        clock), which judges how fast the reading moved without the host's timing."""
        self.saw("encoder", finger, now)
        if not math.isfinite(wire_position_m):
            self._fault(finger, "encoder", f"encoder reading {wire_position_m} (a failed sensor)")
            return
        travel = tendon_position(wire_position_m)
        if travel > self.limits.max_tendon_position_m:
            self._fault(
                finger,
                "over-travel",
                f"tendon over-travel {1e3 * travel:.1f} mm "
                f"(limit {1e3 * self.limits.max_tendon_position_m:g} mm)",
            )
        last = self._readings.get(finger)
        if stamp_s is not None:
            self._readings[finger] = (stamp_s, wire_position_m)
        if last is not None and stamp_s is not None and stamp_s > last[0]:
            speed = abs(wire_position_m - last[1]) / (stamp_s - last[0])
            if speed > self.limits.max_wire_speed_m_s:
                self._fault(
                    finger,
                    "encoder jump",
                    f"encoder jump {1e3 * (wire_position_m - last[1]):+.1f} mm in "
                    f"{1e3 * (stamp_s - last[0]):.0f} ms (faster than "
                    f"{1e3 * self.limits.max_wire_speed_m_s:g} mm/s)",
                )

    def _held(
        self, finger: str, condition: str, holding: bool, now: float, start: float | None = None
    ) -> float:
        """How long ``condition`` has held for ``finger`` by the report received at ``now``
        (0 when this report ends it); ``start``: when it began, if not at this report."""
        key = (finger, condition)
        if not holding:
            self._since.pop(key, None)
            return 0.0
        since = self._since.setdefault(key, now if start is None else start)
        # while ENABLED only the time since enabling counts (a condition left from an earlier
        # ENABLED, or from before this one, starts again at the enable)
        return now - (max(since, self._enabled_at) if self.state == State.ENABLED else since)

    def watchdog(self, finger: str, tripped: bool, now: float) -> None:
        """A unit's watchdog flag, received at ``now``.

        The unit already forced its duty to 0 when the flag rose; the supervisor latches a
        FAULT when the flag has stayed up for ``watchdog_hold_s`` while ENABLED (a lost controller),
        not for a single late command. Time up before enabling does not count.
        ``enable`` and ``reset`` are refused while the flag has been up for ``watchdog_hold_s``, or
        since the unit started: a single late command does not hold them up either.
        """
        held = self._held(
            finger, "watchdog", tripped, now, None if finger in self._duty_seen else -math.inf
        )
        if not tripped:
            self._duty_seen.add(finger)
        elif self.state == State.ENABLED and held >= self.limits.watchdog_hold_s:
            self._fault(
                finger,
                "watchdog",
                f"duty watchdog tripped for {1e3 * held:.0f} ms: no duty commands",
            )

    def sees_enabled(self, finger: str, component: str, enabled: bool, now: float) -> None:
        """A report of ``component`` ("unit" or "controller") of ``finger``, received at ``now``:
        whether it has taken the ENABLED status (the unit's heating permission, the controller's
        ``active``). While ENABLED, reports saying no for ``enable_grace_s`` latch FAULT."""
        condition = f"{component} not enabled"
        key = (finger, component)
        # a report received before the enable (taken from the queue after it) tells nothing
        first_since_enable = key not in self._taken and now >= self._enabled_at
        if enabled and self.state == State.ENABLED and first_since_enable:
            self._taken.add(key)
            self._takes[key] = max(now - self._enabled_at, self._takes.get(key, 0.0))
        held = self._held(finger, condition, not enabled and self.state == State.ENABLED, now)
        if held >= self.limits.enable_grace_s:
            consequence = "it does not heat" if component == "unit" else "it sends 0 % duty"
            self._fault(
                finger,
                condition,
                f"{component} has not taken ENABLED for {1e3 * held:.0f} ms: {consequence}",
            )

    def check_streams(self, now: float) -> None:
        """While ENABLED, fault every controller heartbeat silent for longer than its timeout,
        and every unit whose state reports stopped for longer than ``lost_s`` (a lost unit stops
        its encoder too, but its controller then reports only at its idle period; the sensor
        streams themselves are judged by :meth:`unchanged`).

        When this check itself comes late (the supervisor was not scheduled for a while),
        the messages that arrived meanwhile are still queued and every stream would look
        stale at once; such a check only re-arms, and the next on-time one judges. A stall of
        half a loss limit or more (the supervisor stopped, or starved on a busy host) leaves
        less than the limits' twofold margin to the messages still on their way, whose
        process may itself just be resuming: silences then count from the resume, as if the
        supervisor had just started listening. A stream that stays silent faults a loss
        limit later; the heating stopped 35 ms into the stall (the units' permission).
        """
        interval = 0.0 if self._last_check is None else now - self._last_check
        self._last_check = now
        if interval >= self.limits.loss_s / 2:
            self._listening_since = now
            self._excused_at_resume = self._excused_by(now)
        if self.state != State.ENABLED or interval > self.limits.stale_s / 2:
            return
        for finger in self.fingers:
            silence = self._silence("heartbeat", finger, now)
            if silence > self.limits.heartbeat_timeout_s:
                self._fault(
                    finger,
                    "heartbeat",
                    f"heartbeat stale ({1e3 * silence:.0f} ms without a message)",
                )
            silence = self._silence("unit state", finger, now)
            if silence > self.limits.lost_s:
                self._fault(
                    finger,
                    "unit state",
                    f"unit state lost ({1e3 * silence:.0f} ms without a report)",
                )

    def missing_streams(self, now: float) -> list[str]:
        """Streams never seen or currently stale: the reasons enabling is refused."""
        missing = []
        for finger in self.fingers:
            for stream in STREAMS:
                if (stream, finger) not in self._last_seen:
                    missing.append(f"{finger}: no {stream} yet")
                elif not self._fresh(stream, finger, now):
                    missing.append(f"{finger}: {stream} stale")
            if now - self._since.get((finger, "watchdog"), math.inf) >= self.limits.watchdog_hold_s:
                missing.append(
                    f"{finger}: no duty commands reach the unit (its watchdog is tripped)"
                )
        return missing

    def heard_fingers(self, now: float) -> list[str]:
        """Fingers whose controller's heartbeat is fresh: a status tool that does not hear one
        of them yet is still discovering the graph, not looking at a dead controller."""
        return [finger for finger in self.fingers if self._fresh("heartbeat", finger, now)]

    def _fresh(self, stream: str, finger: str, now: float) -> bool:
        """``stream`` of ``finger`` seen within its timeout of ``now``."""
        seen = self._last_seen.get((stream, finger), -math.inf)
        return now - seen <= self.limits.timeout(stream)

    # commands -----------------------------------------------------------------
    def request(self, command: str, now: float) -> tuple[bool, str]:
        """Apply enable | disable | estop | reset; (accepted, message)."""
        if command == "estop":
            self.state = State.ESTOP
            return True, "ESTOP: all duties forced to 0 until reset"
        if command == "enable":
            if self.state in (State.FAULT, State.ESTOP):
                return False, f"cannot enable from {self.state.name}: call reset first"
            missing = self.missing_streams(now)
            if missing:
                return False, "cannot enable: " + "; ".join(missing)
            if self.state != State.ENABLED:
                self._taken.clear()
            self.state = State.ENABLED
            self._enabled_at = now
            self._excused_at_enable = self._excused_by(now)
            return True, "ENABLED"
        if command == "disable":
            if self.state in (State.FAULT, State.ESTOP):
                return False, f"{self.state.name} is latched: call reset"
            self.state = State.DISABLED
            return True, "DISABLED"
        if command == "reset":
            if self.state not in (State.FAULT, State.ESTOP):
                return True, f"nothing to reset ({self.state.name})"
            missing = self.missing_streams(now)
            if missing:
                return False, "reset refused, faults persist: " + "; ".join(missing)
            self.faults.clear()
            self._readings.clear()  # a reading from before the repair is no reference for speed
            self.state = State.IDLE
            return True, "reset: IDLE (call enable to heat again)"
        raise ValueError(f"unknown supervisor command {command!r}")

    @property
    def heating_allowed(self) -> bool:
        return self.state == State.ENABLED

    def _fault(self, finger: str, kind: str, text: str) -> None:
        if any(f.finger == finger and f.kind == kind for f in self.faults):
            return
        self.faults.append(Fault(finger, kind, text))
        if self.state != State.ESTOP:
            self.state = State.FAULT


GAP_KEY = "gaps"
LOSS_LIMIT_KEY = "loss limit ms"  # the shorter of lost_s and heartbeat_timeout_s
GAP_FLOOR_KEY = "gap floor ms"  # stale_s: shorter silences are not counted as gaps
TAKE_KEY = "enable taken"  # the longest of SupervisorLogic.enable_takes, and whose
GRACE_KEY = "enable grace ms"  # enable_grace_s
QUIET_KEY = "supervisor quiets"  # SupervisorLogic.quiets, as "count, longest N ms"
HEARD_KEY = "fingers heard"  # SupervisorLogic.heard_fingers, comma-separated


def gap_entries(gaps: dict[tuple[str, str], tuple[int, float]]) -> list[tuple[str, str]]:
    """:meth:`SupervisorLogic.gaps` as the supervisor's /diagnostics key-value pairs."""
    return [
        (f"{GAP_KEY} {finger} {stream}", f"{count}, longest {1e3 * longest:.0f} ms")
        for (finger, stream), (count, longest) in sorted(gaps.items())
    ]


def quiet_entry(quiets: tuple[int, float]) -> tuple[str, str]:
    """:meth:`SupervisorLogic.quiets` as a /diagnostics key-value pair."""
    return QUIET_KEY, f"{quiets[0]}, longest {1e3 * quiets[1]:.0f} ms"


def parse_quiets(value: str) -> tuple[int, float]:
    """The inverse of :func:`quiet_entry`'s value: (count, longest s)."""
    count, longest = value.split(", longest ")
    return int(count), float(longest.removesuffix(" ms")) / 1e3


def parse_gaps(pairs: Iterable[tuple[str, str]]) -> dict[tuple[str, str], tuple[int, float]]:
    """The inverse of :func:`gap_entries`, from (key, value) pairs; other keys are skipped."""
    gaps = {}
    for key, value in pairs:
        words = key.split(" ", 2)
        if len(words) == 3 and words[0] == GAP_KEY:
            count, longest = value.split(", longest ")
            gaps[(words[1], words[2])] = (int(count), float(longest.removesuffix(" ms")) * 1e-3)
    return gaps


def longest_take(takes: dict[tuple[str, str], float]) -> str:
    """The longest of :meth:`SupervisorLogic.enable_takes` and whose, as "85 ms (index unit)"."""
    (finger, component), took = max(takes.items(), key=lambda item: item[1])
    return f"{1e3 * took:.0f} ms ({finger} {component})"


def parse_take(value: str) -> tuple[float, str]:
    """The inverse of :func:`longest_take`: (ms, whose)."""
    took, whose = value.split(" ms (", 1)
    return float(took), whose.removesuffix(")")


def gap_report(pairs: Iterable[tuple[str, str]]) -> dict[str, float | int | str | None]:
    """The supervisor's stream-gap figures from its /diagnostics pairs, as numbers for scripts.

    Times in ms as the diagnostics carry them; None where the supervisor reported no such
    figure (no gap counted, no enable taken yet, an older supervisor without the key)."""
    pairs = list(pairs)
    values = dict(pairs)
    gaps = parse_gaps(pairs)
    longest = max(gaps.items(), key=lambda item: item[1][1]) if gaps else None
    quiets, longest_quiet_s = parse_quiets(values[QUIET_KEY]) if QUIET_KEY in values else (0, 0.0)
    take = parse_take(values[TAKE_KEY]) if TAKE_KEY in values else None

    def number(key: str) -> float | None:
        try:
            return float(values[key])
        except (KeyError, ValueError):
            return None

    return {
        "gaps": sum(count for count, _ in gaps.values()),
        "longest_gap_ms": None if longest is None else round(1e3 * longest[1][1]),
        "longest_gap_stream": None if longest is None else " ".join(longest[0]),
        "gap_floor_ms": number(GAP_FLOOR_KEY),
        "loss_limit_ms": number(LOSS_LIMIT_KEY),
        "quiets": quiets,
        "longest_quiet_ms": round(1e3 * longest_quiet_s) if quiets else None,
        "enable_taken_ms": None if take is None else take[0],
        "enable_taken_by": None if take is None else take[1],
        "enable_grace_ms": number(GRACE_KEY),
    }
