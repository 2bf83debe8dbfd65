"""Wire side <-> tendon side through the slider's pulley multiplier (dissertation chapter 6).

The pulley on the slider doubles the tendon displacement and halves the tendon force.
Losses along the tendon (capstan, glove friction) are physics, not part of this ideal
conversion, which is what a controller or the supervisor can compute from the sensors.
"""

from __future__ import annotations

from typing import TypeVar

import numpy as np

PULLEY_RATIO = 2.0
ArrayOrFloat = TypeVar("ArrayOrFloat", float, np.ndarray)


def tendon_position(wire_position_m: ArrayOrFloat, ratio: float = PULLEY_RATIO) -> ArrayOrFloat:
    return wire_position_m * ratio


def wire_position(tendon_position_m: float, ratio: float = PULLEY_RATIO) -> float:
    return tendon_position_m / ratio


def tendon_force(wire_force_n: float, ratio: float = PULLEY_RATIO) -> float:
    return wire_force_n / ratio


def wire_force(tendon_force_n: float, ratio: float = PULLEY_RATIO) -> float:
    return tendon_force_n * ratio
