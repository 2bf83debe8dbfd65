"""Machinery shared by the three controllers: scaling, output clamp, faults, mode transfer.

Each concrete controller implements one difference equation of dissertation chapter 5 on the
scaled error ``e = scale * (r - y)`` (see :mod:`hems_ros.control.gains` for the scales);
this base class turns SI inputs into that error and the result into a PWM duty.

Decisions documented here because every strategy shares them:

Output clamp
    The drive is a PWM duty, so the output is limited to [0, 100] %.

Anti-windup (acts through Ki, so only when Ki != 0)
    Conditional integration, limited to the headroom: when the unclamped output is beyond
    a limit, the part of this sample's integral increment Ki Ts e(k) that pushes it
    further out is removed from the controller memory. Integration thus fills up to the
    limit but never past it, and a proportional or derivative term that saturates the
    output on its own (e.g. the derivative kick of a step) neither inflates nor drains the
    integral. The recursions are velocity forms whose memory is the past output; the
    weights of eq. 5.5 on u(k-1) and u(k-2) sum to 1, so shifting both by the same amount
    moves only the integral level and keeps the P and filtered-D states. Clamping the
    memory itself (the textbook velocity-form scheme) was rejected: after a clipped
    derivative kick the decaying kick would pull the duty to 0 while the error is large.

Bumpless mode switch
    ``set_mode`` restarts the difference equation of the new mode at rest on the current
    measurement (previous reference and measurement = current measurement, zero error
    history) and adds a transfer term equal to the last applied duty. The term decays
    with time constant ``transfer_tau`` (default 1 s, the order of the wire's thermal time
    constant), so the duty is continuous at the switch and then hands over smoothly to the
    new loop. A decaying term rather than a preloaded integrator is needed because the
    Table 5.1 PID/BPID have Ki = 0 and PI-PD spends constant-reference phases in PD: a
    preloaded memory would either stay as a permanent offset or vanish within 1/N.

Faults
    A NaN or infinite reference or measurement drives the output to 0 duty, sets
    ``fault`` to a reason string and clears the controller state. The fault latches until
    ``reset()``: heating the wire on the word of a sensor that has just failed is unsafe,
    so resuming is the caller's explicit decision.

Initial conditions
    ``reset()`` restores the zero initial conditions of the difference equations (all
    past e, u, r, y equal 0), i.e. an actuator at rest at the zero of its sensor, which is
    how the dissertation's protocols start.
"""

from __future__ import annotations

import math
from typing import Any

from hems_ros.duty import DUTY_MAX, DUTY_MIN

MODES = ("position", "force")
DEFAULT_TS = 0.01
DEFAULT_N_FILTER = 20.0
"""Derivative filter N in rad/s (not printed in the dissertation).

The derivative term of eqs. 5.5-5.10 is Kd N s / (s + N): N is the filter pole and
Kd N the derivative gain at high frequency. N = 20 rad/s gives a filter time constant of
50 ms = 5 Ts at 100 Hz: 6x above the fastest reference (0.5 Hz = 3.1 rad/s) and the
wire's thermal bandwidth (time constants about 1 s), so the derivative acts where the loop
works, while a 1 um jump of the encoder reading moves the duty by Kd N / (1 + N Ts) = 0.8 %
with the Table 5.1 Kd instead of 2.5 % at N = 1/Ts.
"""
DEFAULT_TRANSFER_TAU = 1.0


def check_positive(name: str, value: float) -> float:
    """``value`` as a float, or ValueError naming ``name`` unless finite and > 0."""
    value = float(value)
    if not (math.isfinite(value) and value > 0):
        raise ValueError(f"{name} must be a finite positive number, got {value!r}")
    return value


def integral_cut(out: float, inc: float) -> float:
    """Part of the integral increment ``inc`` that drives the unclamped ``out`` past a limit.

    Both in duty %; the caller subtracts the result from its output and memory.
    """
    if out > DUTY_MAX and inc > 0.0:
        return min(out - DUTY_MAX, inc)
    if out < DUTY_MIN and inc < 0.0:
        return max(out - DUTY_MIN, inc)
    return 0.0


def check_mode(mode: str) -> str:
    """Return ``mode`` if it is a control mode, else raise ValueError naming the modes."""
    if mode not in MODES:
        raise ValueError(f"mode must be one of {MODES}, got {mode!r}")
    return mode


class Controller:
    """Common part of the controllers; use :func:`hems_ros.control.make_controller`.

    ``update(reference, measurement)`` takes SI values (m in position mode, N in force
    mode) once per sample period ``ts`` and returns the duty in %.
    """

    strategy = ""
    gains_type: type[Any] = object
    gains: Any  # the gains_type instance
    _bias: float
    fault: str | None

    def __init__(
        self,
        gains: Any,
        mode: str,
        ts: float = DEFAULT_TS,
        n_filter: float = DEFAULT_N_FILTER,
        transfer_tau: float = DEFAULT_TRANSFER_TAU,
    ) -> None:
        if not isinstance(gains, self.gains_type):
            raise TypeError(
                f"{self.strategy} needs {self.gains_type.__name__}, got {type(gains).__name__}"
            )
        self.gains = gains
        self.ts = check_positive("ts", ts)
        self.n_filter = check_positive("n_filter", n_filter)
        self.transfer_tau = check_positive("transfer_tau", transfer_tau)
        self.mode = check_mode(mode)
        self._scale = gains.scale_for(mode)
        self._transfer_decay = math.exp(-self.ts / self.transfer_tau)
        self._setup()
        self.reset()

    def update(self, reference: float, measurement: float) -> float:
        """One control step: duty in [0, 100] % for this sample."""
        if self.fault is not None:
            return 0.0
        r = float(reference)
        y = float(measurement)
        if not math.isfinite(r):
            return self._trip(f"reference is {r}")
        if not math.isfinite(y):
            return self._trip(f"measurement is {y}")
        bias = self._bias
        if r < y:
            # The mode-switch transfer term only carries heating towards or at the setpoint; a
            # setpoint below the measurement (a release) must be free to cut the duty at
            # once, whatever the bilinear factor does to the PID term.
            bias = self._bias = 0.0
        u = self._step(self._scale * r, self._scale * y, bias)
        self._bias = bias * self._transfer_decay
        if u > DUTY_MAX:
            u = DUTY_MAX
        elif u < DUTY_MIN:
            u = DUTY_MIN
        self._output = u
        return u

    def reset(self) -> None:
        """Zero initial conditions, no transfer term, fault cleared."""
        self.fault = None
        self._output = 0.0
        self._bias = 0.0
        self._reset_state()

    def set_mode(self, mode: str, measurement: float, gains: Any = None) -> None:
        """Switch to ``mode`` without a jump in duty, with that mode's ``gains`` if given.

        ``measurement`` is the current value in the new mode's SI unit.
        """
        check_mode(mode)
        if gains is not None and not isinstance(gains, self.gains_type):
            raise TypeError(
                f"{self.strategy} needs {self.gains_type.__name__}, got {type(gains).__name__}"
            )
        y = float(measurement)
        if not math.isfinite(y):
            self._trip(f"measurement is {y} at switch to {mode} mode")
            return
        if mode == self.mode:
            return
        if gains is not None:
            self.gains = gains
            self._setup()
        self.mode = mode
        self._scale = self.gains.scale_for(mode)
        self._reset_state()
        self._prime(self._scale * y)
        self._bias = self._output

    def _trip(self, reason: str) -> float:
        self.fault = reason
        self._output = 0.0
        self._bias = 0.0
        self._reset_state()
        return 0.0

    def _setup(self) -> None:
        """Precompute the difference-equation coefficients."""
        raise NotImplementedError

    def _reset_state(self) -> None:
        raise NotImplementedError

    def _prime(self, y: float) -> None:
        """Make ``y`` (scaled) the previous reference and measurement."""

    def _step(self, r: float, y: float, bias: float) -> float:
        """Unclamped duty from the scaled reference and measurement, plus ``bias``."""
        raise NotImplementedError
