"""PID with filtered derivative, discretised by backward Euler (eqs. 5.5-5.10).

    C(s) = Kp + Ki / s + Kd N s / (s + N),   s -> (1 - z^-1) / Ts

gives the recursion of eq. 5.5

    u(k) = -(a1/a0) u(k-1) - (a2/a0) u(k-2) + (b0/a0) e(k) + (b1/a0) e(k-1) + (b2/a0) e(k-2)

with the coefficients of eq. 5.8 (see :func:`pid_coefficients`). Its denominator is
(1 - z^-1)(a0 - z^-1): a velocity form whose memory u(k-1) integrates, which is where the
anti-windup of :mod:`hems_ros.control.base` acts.
"""

from __future__ import annotations

from typing import Any

from hems_ros.control.base import Controller, integral_cut
from hems_ros.control.gains import PIDGains


def pid_coefficients(
    kp: float, ki: float, kd: float, n: float, ts: float
) -> tuple[float, float, float, float, float, float]:
    """(a0, a1, a2, b0, b1, b2) of eq. 5.8."""
    nts = n * ts
    a0 = 1.0 + nts
    a1 = -(2.0 + nts)
    a2 = 1.0
    b0 = kp * (1.0 + nts) + ki * ts * (1.0 + nts) + kd * n
    b1 = -(kp * (2.0 + nts) + ki * ts + 2.0 * kd * n)
    b2 = kp + kd * n
    return a0, a1, a2, b0, b1, b2


class PIDController(Controller):
    """Eq. 5.5 on the scaled error; Table 5.1: Kp 0.8, Ki 0, Kd 0.05."""

    strategy = "pid"
    gains_type: type[Any] = PIDGains

    def _setup(self) -> None:
        g = self.gains
        self.coefficients = pid_coefficients(g.kp, g.ki, g.kd, self.n_filter, self.ts)
        a0, a1, a2, b0, b1, b2 = self.coefficients
        self._c1 = -a1 / a0
        self._c2 = -a2 / a0
        self._d0 = b0 / a0
        self._d1 = b1 / a0
        self._d2 = b2 / a0
        self._ki_ts = g.ki * self.ts

    def _reset_state(self) -> None:
        self._u1 = 0.0
        self._u2 = 0.0
        self._e1 = 0.0
        self._e2 = 0.0

    def _advance(self, e: float) -> float:
        """Eq. 5.5 for error ``e``; returns u(k) and shifts the history."""
        u = (
            self._c1 * self._u1
            + self._c2 * self._u2
            + self._d0 * e
            + self._d1 * self._e1
            + self._d2 * self._e2
        )
        self._u2 = self._u1
        self._u1 = u
        self._e2 = self._e1
        self._e1 = e
        return u

    def _shift_memory(self, delta: float) -> None:
        """Move the integral level by ``delta`` (both past outputs, see the base module)."""
        self._u1 += delta
        self._u2 += delta

    def _step(self, r: float, y: float, bias: float) -> float:
        e = r - y
        out = self._advance(e) + bias
        cut = integral_cut(out, self._ki_ts * e)
        if cut:
            self._shift_memory(-cut)
            out -= cut
        return out
