"""Validation of user setpoints (tendon side).

Limits derived from chapter 6: the unit's nominal output with the multiplier
is 54 mm of tendon travel, and the wire-force sensors read 0-50 N, which behind the x2
pulley is 0-25 N of tendon force. Anything outside, non-finite, or in an unknown mode is
rejected; the caller keeps its last valid setpoint.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

MODES = ("position", "force")


@dataclass(frozen=True)
class SetpointLimits:
    max_position_m: float = 0.054
    max_force_n: float = 25.0

    def __post_init__(self) -> None:
        for name in ("max_position_m", "max_force_n"):
            value = getattr(self, name)
            if not (math.isfinite(value) and value > 0):
                raise ValueError(f"{name} = {value!r}: must be a finite value > 0")


@dataclass(frozen=True)
class Setpoint:
    mode: str
    value: float  # m (position) or N (force), tendon side


class SetpointError(ValueError):
    """A setpoint was rejected; the message says why."""


def validate(mode: str, value: float, limits: SetpointLimits) -> Setpoint:
    if mode not in MODES:
        raise SetpointError(f"unknown mode {mode!r}: expected 'position' or 'force'")
    if not isinstance(value, (int, float)) or not math.isfinite(value):
        raise SetpointError(f"{mode} setpoint {value!r} is not a finite number")
    if mode == "position" and not 0.0 <= value <= limits.max_position_m:
        raise SetpointError(
            f"position setpoint {value:g} m outside the tendon stroke 0-{limits.max_position_m:g} m"
        )
    if mode == "force" and not 0.0 <= value <= limits.max_force_n:
        raise SetpointError(
            f"force setpoint {value:g} N outside the tendon force range 0-{limits.max_force_n:g} N"
        )
    return Setpoint(mode, float(value))
