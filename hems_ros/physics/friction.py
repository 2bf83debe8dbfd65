"""Transmission losses between the wire and the load (beyond the dissertation's model).

Capstan friction of the wire in the bent Bowden sheath (dissertation eq. 3.1):
F_out / F_in = exp(-mu Theta); mu = 0.04, Theta = pi gives 0.88 (0.84 measured). Coulomb
friction of the tendon in the glove (chapter 6 force-displacement hysteresis).

Both oppose the motion: while the wire pulls the load in (slider velocity > 0) the load
receives c F_wire / n - F_c; while the load drags the wire out it receives F_wire / (c n)
+ F_c; at rest anything in between holds (stiction). loads.slider_velocity resolves
the three cases exactly for the implicit step.
"""

from __future__ import annotations

import math


def capstan_ratio(friction_coefficient: float, bend_angle_rad: float) -> float:
    """F_out / F_in = exp(-mu Theta) (eq. 3.1)."""
    return math.exp(-friction_coefficient * bend_angle_rad)


def transmitted_force(
    wire_force: float, direction: float, capstan: float, pulley_ratio: float, coulomb_n: float
) -> float:
    """Force reaching the load for motion ``direction`` (+1 pulling in, -1 paying out)."""
    if direction > 0:
        return capstan * wire_force / pulley_ratio - coulomb_n
    return wire_force / (capstan * pulley_ratio) + coulomb_n
