"""One finger's control loop without the middleware: what the finger controller node decides.

The node (hems_ros.nodes.finger_controller) hands this core each message's content and
publishes what it returns; everything that decides a duty lives here: setpoint validation
and the switch between position and force mode without a jump in duty (the controller's
bumpless transfer), the supervisor's permission, the other mode's readings checked for
freshness on the unit's stamps (so the host's timing does not enter), a failed (non-finite)
sensor, the thermal guard's cut-off, and what the status reports. Setpoints are tendon side,
readings wire side; the pulley ratio converts between them.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from hems_ros.control.base import Controller
from hems_ros.control.gains import Gains
from hems_ros.graph import transmission
from hems_ros.graph.setpoints import Setpoint, SetpointLimits, validate
from hems_ros.graph.thermal_guard import ThermalGuard

NO_STAMP = (0, 0)


def lag_ns(later: tuple[int, int], earlier: tuple[int, int]) -> int:
    """Nanoseconds from stamp ``earlier`` to stamp ``later``, both (sec, nanosec)."""
    return (later[0] - earlier[0]) * 1_000_000_000 + later[1] - earlier[1]


@dataclass
class Reading:
    """The latest reading of one stream: wire side (m or N) and the unit's stamp."""

    value: float | None = None
    stamp: tuple[int, int] = NO_STAMP


def _nan_if_none(value: float | None) -> float:
    return math.nan if value is None else value


class FingerLoop:
    """One finger: setpoint, mode, permission, readings and the duty they give."""

    def __init__(
        self,
        controller: Controller,
        gains: dict[str, Gains],
        limits: SetpointLimits,
        pulley_ratio: float,
        feedback_lag_s: float,
        guard: ThermalGuard,
    ) -> None:
        self.controller = controller
        self.gains = gains  # mode -> the gains the controller takes in that mode
        self.limits = limits
        self.ratio = pulley_ratio
        self.feedback_lag_ns = int(round(feedback_lag_s * 1e9))
        self.guard = guard
        self.setpoint = Setpoint(controller.mode, 0.0)
        self.readings = {"position": Reading(), "force": Reading()}
        self.enabled = False
        self.duty = 0.0
        self.rejected = 0
        self.last_rejection = ""

    @property
    def other_mode(self) -> str:
        return "force" if self.setpoint.mode == "position" else "position"

    def set_point(self, mode: str, value: float) -> Setpoint:
        """A user's setpoint; raises SetpointError (counted, the last valid one kept) if it is
        invalid. A setpoint of the other mode switches the controller, carrying its output
        over from that mode's latest reading, or starting afresh if there is none."""
        try:
            setpoint = validate(mode, value, self.limits)
        except ValueError as error:
            self.rejected += 1
            self.last_rejection = str(error)
            raise
        if setpoint.mode != self.controller.mode:
            measurement = self.readings[setpoint.mode].value
            self.controller.set_mode(
                setpoint.mode,
                0.0 if measurement is None else measurement,
                self.gains[setpoint.mode],
            )
            if measurement is None:
                self.controller.reset()
        self.setpoint = setpoint
        return setpoint

    def supervisor(self, enabled: bool) -> None:
        """The supervisor's state: a fresh enable starts the controller from rest."""
        if enabled and not self.enabled:
            self.controller.reset()
        self.enabled = enabled

    def reading(self, mode: str, value: float, stamp: tuple[int, int]) -> bool:
        """The encoder's ("position") or the force sensor's reading; whether it is the
        feedback of the current mode, so a control step is due."""
        self.readings[mode] = Reading(value, stamp)
        return mode == self.setpoint.mode

    def other_fresh(self, stamp: tuple[int, int]) -> bool:
        """The other mode's latest reading is finite and at most ``feedback_lag_s`` older than
        the feedback sample stamped ``stamp``: without it over-force (or over-travel) cannot
        be seen while the wire heats."""
        other = self.readings[self.other_mode]
        if other.stamp == NO_STAMP or other.value is None or not math.isfinite(other.value):
            return False
        return lag_ns(stamp, other.stamp) <= self.feedback_lag_ns

    def step(self, other_fresh: bool) -> float:
        """The duty for the feedback sample just taken, percent: 0 unless enabled, the other
        mode's reading fresh and the thermal guard not limiting."""
        measurement = self.readings[self.setpoint.mode].value
        if self.enabled and other_fresh and not self.guard.limited and measurement is not None:
            self.duty = self.controller.update(self._wire_reference(), measurement)
        else:
            self.duty = 0.0
        return self.duty

    def _wire_reference(self) -> float:
        if self.setpoint.mode == "position":
            return transmission.wire_position(self.setpoint.value, self.ratio)
        return transmission.wire_force(self.setpoint.value, self.ratio)

    def status_key(self) -> tuple[object, ...]:
        """What a status must go out at once for when it changes."""
        return (
            self.setpoint.mode,
            self.setpoint.value,
            self.enabled,
            self.controller.fault,
            self.guard.limited,
        )

    def status_fields(self) -> dict[str, object]:
        """What the controller status reports (hems_msgs/ControllerStatus's fields but the
        header and sequence): setpoint and measurement tendon side, readings wire side with
        the unit's stamps, NaN for a reading not yet received."""
        tendon = self.tendon_measurement()
        position, force = self.readings["position"], self.readings["force"]
        return dict(
            strategy=self.controller.strategy,
            mode=self.setpoint.mode,
            active=self.enabled,
            setpoint=self.setpoint.value,
            measurement=tendon,
            error=self.setpoint.value - tendon,
            duty_percent=self.duty,
            fault=self.controller.fault or "",
            encoder_stamp_sec=position.stamp[0],
            encoder_stamp_nanosec=position.stamp[1],
            wire_position=_nan_if_none(position.value),
            force_stamp_sec=force.stamp[0],
            force_stamp_nanosec=force.stamp[1],
            wire_force=_nan_if_none(force.value),
            rejected_setpoints=self.rejected,
            last_rejection=self.last_rejection,
            wire_temperature_c=self.guard.estimate_c,
            thermal_limited=self.guard.limited,
        )

    def tendon_measurement(self) -> float:
        """The current mode's reading on the tendon side (m or N); NaN before the first."""
        measurement = self.readings[self.setpoint.mode].value
        if measurement is None:
            return math.nan
        if self.setpoint.mode == "position":
            return transmission.tendon_position(measurement, self.ratio)
        return transmission.tendon_force(measurement, self.ratio)
