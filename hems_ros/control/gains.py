"""Typed gain sets of the three controllers and the Table 5.1 values (dissertation chapter 5).

Unit convention
---------------
The controllers take SI inputs (metres of wire displacement, newtons of wire tension) but
the gains act on a *scaled* error ``e = scale * (r - y)``, the scale depending on the mode:

``position_scale`` (default :data:`UM_PER_M` = 1e6, error in micrometres)
    Table 5.1 prints the gains without units. They fit an error in
    micrometres: with Ki = 0 the wire needs roughly 7-10 % duty to hold a position against
    the 40 N load, which at Kp = 0.8 %/unit is about 10 units of error, and the dissertation
    reports steady-state errors of 0.01-0.02 mm = 10-20 um for PID and BPID. An error in mm
    would leave 10 mm of steady-state error; an error in metres would never lift the wire.
    Gains are then Kp in %/um, Ki in %/(um s), Kd in % s/um, Kb in 1/um.

``force_scale`` (default :data:`FORCE_SCALE` = 400 per N, error in units of 2.5 mN)
    Chapter 6 runs BPID in force mode with no separate gain table. The first choice, an
    error in mN (1e3 per N), kept the Table 5.1 gains at about their position-mode loop
    gain (the HEMS load takes about 0.5 N per mm of wire, so 1 mN is about 2 um), but it
    ignores the force sensor's noise (0.03 N rms): at 1e3 per N that noise alone moves the
    duty by 24 % rms through Kp and 35 % through the filtered derivative, the duty chatters
    between 0 and 100 % (MACSI 16-36 %/sample in the chapter 6 lockstep runs) and the
    staircase steady-state error grows to 0.15 N. The scale was swept in the lockstep
    simulation (``hems experiment ch6``, docs/experiments.md): at 400 per N the noise moves
    the duty by 10 % and 14 % rms, MACSI drops by 10-15 % and the steady-state errors are
    0.036 N (step) and 0.028 N (staircase), the order of the dissertation's 0.05 and 0.04 N;
    lower scales lose holding gain (0.10 N at 250 per N). Gains are then Kp in %/(2.5 mN),
    Kb in 1/(2.5 mN).

    With the Table 5.1 gains the force loop still limit-cycles between 0 and 100 % duty
    with a period of 3-4 samples. The HEMS load carries the wire's contraction rate into
    the force (the tendon damper, n^2 b v = 4 x 65 N s/m on the wire, plus friction), so a
    single 10 ms sample at full duty lifts the force by about 0.6 N while the proportional
    band at 400 per N is 0.31 N wide, and the derivative term differentiates that rate
    once more. :data:`FORCE_MODE_BPID` is the force-mode set used for chapter 6: Kd = 0
    (the measured force already contains the rate), an error in units of 10 mN
    (proportional band 2.5 N at Kp = 0.4, the noise moves the duty by 1.2 % rms) and
    Ki = 0.2 to hold the force without the error a lower Kp leaves (0.42 N at 100 per N
    with Ki = 0). Kp and Ki were chosen on the lockstep sweep of
    :func:`hems_ros.experiments.findings.force_gain_sweep` (docs/experiments.md): the
    dissertation reports no overshoot on the force steps, and the earlier Kp 0.8, Ki 0.5
    saturated the duty for two or three samples on each 4 N staircase jump, so the wire's
    first burst of speed carried the force 0.13 and 0.23 N past the 16 and 20 N levels (without
    sensor noise). Kp 0.4, Ki 0.2 passes no level by more than 0.062 N, without the noise
    and with it (eight noise seeds), and leaves steady-state errors of about 0.05 N (step)
    and 0.02 N (staircase), the dissertation's 0.05 and 0.04 N. It approaches more slowly:
    the RMSE grows from 0.26 to 0.42 N on the step (Table 6.2: 0.12 N) and from 0.75 / 2.91
    to 0.99 / 3.11 N on the 0.125 / 0.25 Hz sines, which the cooling wire limits either way
    (Table 6.2: 0.10 / 0.18 N). Kp 0.5, Ki 0.3 was faster but passed a level by 0.096 N
    with one of the seeds. MACSI is about 1.2-1.4 %/sample (11-32 with the Table 5.1 gains).

The scales are fields of every gain set so a tuned force set can change them explicitly.
Validation rejects negative, NaN and infinite gains at construction, naming the gain.
"""

from __future__ import annotations

import math
import numbers
from collections.abc import Mapping
from dataclasses import dataclass, fields
from types import MappingProxyType

UM_PER_M = 1e6
MN_PER_N = 1e3
FORCE_SCALE = 400.0


def _check_gain(name: str, value: object) -> None:
    if isinstance(value, bool) or not isinstance(value, numbers.Real):
        raise TypeError(f"gain {name} must be a real number, got {value!r}")
    if not math.isfinite(value):
        raise ValueError(f"gain {name} must be finite, got {value!r}")
    if value < 0:
        raise ValueError(f"gain {name} must be non-negative, got {value!r}")


@dataclass(frozen=True, kw_only=True)
class _Gains:
    position_scale: float = UM_PER_M
    force_scale: float = FORCE_SCALE

    def __post_init__(self) -> None:
        for f in fields(self):
            _check_gain(f.name, getattr(self, f.name))
        for name in ("position_scale", "force_scale"):
            if getattr(self, name) == 0:
                raise ValueError(f"gain {name} must be positive, got 0")

    def scale_for(self, mode: str) -> float:
        """Error scale of ``mode``: scaled units per SI unit (see the module docstring)."""
        if mode == "position":
            return float(self.position_scale)
        if mode == "force":
            return float(self.force_scale)
        raise ValueError(f"mode must be 'position' or 'force', got {mode!r}")


@dataclass(frozen=True, kw_only=True)
class PIDGains(_Gains):
    """PID with filtered derivative (eqs. 5.5-5.10)."""

    kp: float
    ki: float
    kd: float


@dataclass(frozen=True, kw_only=True)
class BPIDGains(_Gains):
    """Four-term bilinear PID (eq. 5.36): PID gains plus the bilinear gain Kb = rho0d / b0d."""

    kp: float
    ki: float
    kd: float
    kb: float


@dataclass(frozen=True, kw_only=True)
class PIPDGains(_Gains):
    """PI-PD with commuted feed-forward (eqs. 5.11-5.21); ``u_ff`` is in % duty."""

    kp_pi: float
    ki_pi: float
    kp_pd: float
    kd_pd: float
    u_ff: float


Gains = BPIDGains | PIDGains | PIPDGains
"""The gain set of any strategy."""

TABLE_5_1_BPID = BPIDGains(kp=0.8, ki=0.0, kd=0.05, kb=1.0)
"""The BPID row of :data:`TABLE_5_1`, typed as BPID gains."""

TABLE_5_1: Mapping[str, Gains] = MappingProxyType(
    {
        "bpid": TABLE_5_1_BPID,
        "pid": PIDGains(kp=0.8, ki=0.0, kd=0.05),
        "pipd": PIPDGains(kp_pi=0.8, ki_pi=0.25, kp_pd=0.08, kd_pd=0.003, u_ff=3.0),
    }
)
"""Dissertation Table 5.1 gain sets by strategy name, in the units of the module docstring."""

FORCE_MODE_BPID = BPIDGains(kp=0.4, ki=0.2, kd=0.0, kb=1.0, force_scale=100.0)
"""BPID gains for force mode on the HEMS unit (module docstring): Kp in %/(10 mN),
Ki in %/(10 mN s), Kb in 1/(10 mN). Position mode keeps Table 5.1."""


def mode_gains(strategy: str, mode: str) -> Gains:
    """Return the default gains of ``strategy`` in ``mode``.

    Table 5.1, except BPID in force mode (:data:`FORCE_MODE_BPID`); PID and PI-PD have no
    force-mode set of their own.
    """
    return FORCE_MODE_BPID if (strategy, mode) == ("bpid", "force") else TABLE_5_1[strategy]
