"""PI-PD with commuted feed-forward (eqs. 5.11-5.21).

Two first-order recursions share the memory u_c(k-1):

* PI while the reference changes, r(k) != r(k-1) (backward Euler, coefficients eq. 5.15)::

      u_c(k) = -(a1/a0) u_c(k-1) + (b0/a0) e(k) + (b1/a0) e(k-1),
      a0 = 1, a1 = -1, b0 = Kp + Ki Ts, b1 = -Kp

* PD with filtered derivative while it is constant (Kp + Kd N s / (s + N), coefficients
  eq. 5.19), same recursion with::

      a0 = 1 + N Ts, a1 = -1, b0 = Kp (1 + N Ts) + Kd N, b1 = -(Kp + Kd N)

The output adds the feed-forward u_FF = I_FF when r(k) > r(k-1), else 0. u_FF is kept out
of the memory: it is an offset that helps heating, and inside the PD recursion it would
be carried over into later samples.

The reference change is detected by exact comparison; the protocol generators of
:mod:`hems_ros.control.references` hold constant segments exactly constant.
Anti-windup (see :mod:`hems_ros.control.base`) cuts the PI's integral increment
Ki Ts e(k) where memory + u_FF + transfer term would pass a limit; the PD recursion has its
pole at 1/a0 < 1, cannot wind up, and runs unclamped.
"""

from __future__ import annotations

from hems_ros.control.base import Controller, integral_cut
from hems_ros.control.gains import PIPDGains


def pi_coefficients(kp: float, ki: float, ts: float) -> tuple[float, float, float, float]:
    """(a0, a1, b0, b1) of the PI part, eq. 5.15."""
    return 1.0, -1.0, kp + ki * ts, -kp


def pd_coefficients(kp: float, kd: float, n: float, ts: float) -> tuple[float, float, float, float]:
    """(a0, a1, b0, b1) of the PD part with filtered derivative, eq. 5.19."""
    nts = n * ts
    return 1.0 + nts, -1.0, kp * (1.0 + nts) + kd * n, -(kp + kd * n)


class PIPDController(Controller):
    """Table 5.1: Kp_PI 0.8, Ki_PI 0.25, Kp_PD 0.08, Kd_PD 0.003, u_FF 3 %."""

    strategy = "pipd"
    gains_type = PIPDGains

    def _setup(self) -> None:
        g = self.gains
        self.pi_coefficients = pi_coefficients(g.kp_pi, g.ki_pi, self.ts)
        self.pd_coefficients = pd_coefficients(g.kp_pd, g.kd_pd, self.n_filter, self.ts)
        a0, a1, b0, b1 = self.pi_coefficients
        self._pi = (-a1 / a0, b0 / a0, b1 / a0)
        a0, a1, b0, b1 = self.pd_coefficients
        self._pd = (-a1 / a0, b0 / a0, b1 / a0)
        self._u_ff = float(g.u_ff)
        self._ki_ts = g.ki_pi * self.ts

    def _reset_state(self) -> None:
        self._uc1 = 0.0
        self._e1 = 0.0
        self._r1 = 0.0

    def _prime(self, y: float) -> None:
        self._r1 = y

    def _step(self, r: float, y: float, bias: float) -> float:
        e = r - y
        r1 = self._r1
        ff = 0.0
        if r != r1:
            c, d0, d1 = self._pi
            uc = c * self._uc1 + d0 * e + d1 * self._e1
            if r > r1:
                ff = self._u_ff
            cut = integral_cut(uc + ff + bias, self._ki_ts * e)
            uc -= cut
        else:
            c, d0, d1 = self._pd
            uc = c * self._uc1 + d0 * e + d1 * self._e1
        self._uc1 = uc
        self._e1 = e
        self._r1 = r
        return uc + ff + bias
