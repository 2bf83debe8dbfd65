"""The supervisor's state machine and stream monitors (plain Python, no ROS).

States: IDLE -> ENABLED <-> DISABLED; any monitored fault latches FAULT, ``estop`` latches
ESTOP; both stay until ``reset``, which is refused while a fault condition persists.
Heating is allowed only in ENABLED, so every other state means zero duty.

Monitors (per finger, on the receive times of the streams, in the node's clock):
a stream that has been seen and then stays silent longer than ``stale_s`` (encoder, wire
force, controller heartbeat), wire force at or above ``max_wire_force_n``, tendon travel
beyond ``max_tendon_position_m``, and the actuation unit's duty-watchdog flag while ENABLED.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from enum import IntEnum

from hems_ros.graph.transmission import tendon_position

STREAMS = ("encoder", "wire_force", "heartbeat")


class State(IntEnum):
    IDLE = 0
    ENABLED = 1
    DISABLED = 2
    FAULT = 3
    ESTOP = 4


@dataclass(frozen=True)
class MonitorLimits:
    stale_s: float = 0.05
    max_wire_force_n: float = 50.0
    max_tendon_position_m: float = 0.056

    def __post_init__(self) -> None:
        for name in ("stale_s", "max_wire_force_n", "max_tendon_position_m"):
            value = getattr(self, name)
            if not (math.isfinite(value) and value > 0):
                raise ValueError(f"{name} = {value!r}: must be a finite value > 0")


@dataclass
class Fault:
    finger: str
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

    # observations -------------------------------------------------------------
    def saw(self, stream: str, finger: str, now: float) -> None:
        self._last_seen[(stream, finger)] = now

    def wire_force(self, finger: str, force_n: float, now: float) -> None:
        self.saw("wire_force", finger, now)
        if force_n >= self.limits.max_wire_force_n:
            self._fault(finger, f"wire over-force {force_n:.1f} N (limit {self.limits.max_wire_force_n:g} N)")

    def encoder(self, finger: str, wire_position_m: float, now: float) -> None:
        self.saw("encoder", finger, now)
        travel = tendon_position(wire_position_m)
        if travel > self.limits.max_tendon_position_m:
            self._fault(finger, f"tendon over-travel {1e3 * travel:.1f} mm "
                                f"(limit {1e3 * self.limits.max_tendon_position_m:g} mm)")

    def watchdog(self, finger: str, tripped: bool) -> None:
        if tripped and self.state == State.ENABLED:
            self._fault(finger, "duty watchdog tripped: no duty command for three control periods")

    def check_streams(self, now: float) -> None:
        """Fault every stream that was seen and has gone silent for longer than stale_s."""
        for (stream, finger), seen in self._last_seen.items():
            age = now - seen
            if age > self.limits.stale_s:
                self._fault(finger, f"{stream} stale ({1e3 * age:.0f} ms without a message)")

    def missing_streams(self, now: float) -> list[str]:
        """Streams never seen or currently stale: the reasons enabling is refused."""
        missing = []
        for finger in self.fingers:
            for stream in STREAMS:
                seen = self._last_seen.get((stream, finger))
                if seen is None:
                    missing.append(f"{finger}: no {stream} yet")
                elif now - seen > self.limits.stale_s:
                    missing.append(f"{finger}: {stream} stale")
        return missing

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
            self.state = State.ENABLED
            return True, "ENABLED"
        if command == "disable":
            if self.state in (State.FAULT, State.ESTOP):
                return False, f"{self.state.name} is latched: call reset"
            self.state = State.DISABLED
            return True, "DISABLED"
        if command == "reset":
            if self.state not in (State.FAULT, State.ESTOP):
                return True, f"nothing to reset ({self.state.name})"
            self.faults.clear()
            self.check_streams(now)
            missing = self.missing_streams(now)
            if self.faults or missing:
                reasons = [str(f) for f in self.faults] + missing
                self.faults.clear()
                return False, "reset refused, faults persist: " + "; ".join(reasons)
            self.state = State.IDLE
            return True, "reset: IDLE (call enable to heat again)"
        raise ValueError(f"unknown supervisor command {command!r}")

    @property
    def heating_allowed(self) -> bool:
        return self.state == State.ENABLED

    def _fault(self, finger: str, text: str) -> None:
        if any(f.finger == finger and f.text.split(" (")[0] == text.split(" (")[0] for f in self.faults):
            return
        self.faults.append(Fault(finger, text))
        if self.state != State.ESTOP:
            self.state = State.FAULT

    def forget(self, stream: str, finger: str) -> None:
        self._last_seen.pop((stream, finger), None)
