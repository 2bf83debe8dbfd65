"""Four-term bilinear PID (eqs. 5.22-5.36).

The plant model is first-order bilinear, dy/dt = -a0 y + b0 u + rho0 u y, whose static gain
falls as y grows. Eq. 5.36 compensates by multiplying the PID output of eq. 5.5 by

    (1 + Kb r(k)) / (1 + Kb y(k-1)),   Kb = rho0d / b0d,

large far below the setpoint and 1 at it. r and y enter in the scaled unit of the error
(um or mN, see :mod:`hems_ros.control.gains`), so Kb is in 1/um or 1/mN.

Both are clipped at 0 inside the factor: the actuator only pulls, the bilinear model
describes y >= 0, and with Kb = 1/um a reading 1 um below the zero (encoder noise, an
offset) would otherwise zero the denominator and flip the sign of the output.
"""

from __future__ import annotations

from hems_ros.control.base import integral_cut
from hems_ros.control.gains import BPIDGains
from hems_ros.control.pid import PIDController


def bilinear_factor(kb: float, r: float, y_prev: float) -> float:
    """(1 + Kb r(k)) / (1 + Kb y(k-1)) of eq. 5.36, r and y clipped at 0."""
    return (1.0 + kb * max(r, 0.0)) / (1.0 + kb * max(y_prev, 0.0))


class BPIDController(PIDController):
    """Eq. 5.36 on the scaled error; Table 5.1: Kp 0.8, Ki 0, Kd 0.05, Kb 1."""

    strategy = "bpid"
    gains_type = BPIDGains

    def _setup(self) -> None:
        super()._setup()
        self._kb = float(self.gains.kb)

    def _reset_state(self) -> None:
        super()._reset_state()
        self._y1 = 0.0

    def _prime(self, y: float) -> None:
        self._y1 = y

    def _step(self, r: float, y: float, bias: float) -> float:
        e = r - y
        factor = bilinear_factor(self._kb, r, self._y1)
        self._y1 = y
        out = self._advance(e) * factor + bias
        # factor > 0 (r, y clipped, Kb >= 0), so the cut maps back to the memory by division.
        cut = integral_cut(out, self._ki_ts * e * factor)
        if cut:
            self._shift_memory(-cut / factor)
            out -= cut
        return out
