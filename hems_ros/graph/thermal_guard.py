"""The wire's temperature from what its drive board measures, and the heating cut before a limit.

The board reports, at every sample, the duty it applied over the period that ended and the
wire's current and voltage while it conducted (hems_msgs/EncoderReading carries them beside
the encoder reading, one packet a sample). The guard runs the unit's model (the physics
kernel) on that applied duty, which gives the wire temperature the energy put in implies
with the model's heat balance, and checks it against the wire itself:
the measured resistance V/I against the model's, the difference moved onto the temperature
through the resistance law's slope (eqs. 4.2-4.4 at the model's phase mixture). No encoder
or force reading enters, so a stuck sensor that keeps a controller heating cannot hide the
heat (docs/reliability.md).

Above ``cut_c`` the guard holds the duty at 0 until the estimate is back below
``resume_c``; the supervisor latches a FAULT if an estimate still reaches its own limit.
"""

from __future__ import annotations

import math

from hems_ros.duty import DUTY_MAX, DUTY_MIN
from hems_ros.physics import ActuationUnit
from hems_ros.physics.params import UnitParams

#: The resistance check moves the model's temperature by at most this much (K): it corrects
#: a model that drifted from the wire, it does not replace the model where the slope is flat.
MAX_CORRECTION_K = 30.0


class ThermalGuard:
    """Wire-temperature estimate and heating cut-off of one unit (module docstring)."""

    def __init__(
        self, params: UnitParams, cut_c: float, resume_c: float, period_s: float, dt: float = 1e-3
    ):
        if not resume_c < cut_c:
            raise ValueError(
                f"resume at {resume_c:g} degC must be below the cut-off {cut_c:g} degC"
            )
        self.model = ActuationUnit(params.replace({"force_sensor.noise_std_n": 0.0}), dt=dt)
        self.steps = max(1, int(round(period_s / dt)))
        self.cut_c, self.resume_c = cut_c, resume_c
        self.estimate_c = math.nan
        self.limited = False

    def reading(self, duty_percent: float, on_current_a: float, on_voltage_v: float) -> float:
        """One board reading: advance the model over the period at the applied duty, correct it
        with the measured resistance, update the cut-off; the estimate, degC."""
        duty = min(max(duty_percent, DUTY_MIN), DUTY_MAX) if math.isfinite(duty_percent) else 0.0
        self.model.advance(duty=duty, steps=self.steps)
        estimate, xi, slider_m = self.model.wire()
        if math.isfinite(on_current_a) and math.isfinite(on_voltage_v) and on_current_a > 0.0:
            estimate += self._correction(on_voltage_v / on_current_a, xi, slider_m)
        self.estimate_c = estimate
        self.limited = estimate >= self.cut_c or (self.limited and estimate > self.resume_c)
        return estimate

    def _correction(self, measured_ohm: float, xi: float, slider_m: float) -> float:
        """Temperature difference the measured resistance asks for, from the resistance law's
        temperature slope at the model's martensite fraction ``xi`` and wire length (eq. 4.4
        in both phases, mixed by eq. 4.3)."""
        p = self.model.params
        el = p.electrical
        length = p.wire.length_m - slider_m
        slope = (
            (xi * el.drho_dt_martensite_ohm_m_per_c + (1.0 - xi) * el.drho_dt_austenite_ohm_m_per_c)
            * length
            / p.wire.cross_section_m2
        )
        if not slope > 0.0:
            return 0.0
        model_ohm = self.model.electrical()[0]
        delta = (measured_ohm - model_ohm) / slope
        return max(-MAX_CORRECTION_K, min(MAX_CORRECTION_K, delta))
