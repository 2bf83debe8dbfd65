"""Bowden-sheath thermal model (beyond the dissertation's model; dissertation chapter 3, Table 3.1).

The wire inside the PTFE tube exchanges heat with the sheath through the PTFE wall
(ln(d_o/d_i) / (2 pi k L) = 0.4038 K/W) plus a contact/air-gap resistance (calibrated).
The sheath loses heat to air through the steel wall (4.73e-3 K/W) and outer convection
(1/(h A) = 7.48 K/W); the total wire-to-air path with perfect contact is 7.89 K/W, as in
Table 3.1.

The sheath's heat capacity (PTFE + steel helix, 17 J/K) sits in one node, or in two: what
follows the wire within a pulse (the liner and the inner turns of the helix) is a small
first node; the rest of the helix is a large, slow node between it and the air, reached
through a contact resistance. One node fitted to single pulses keeps only the small
capacity and under continuous duty warms far faster than the sheath does; the calibrated
sets have two (hems_ros.physics.calibration).

A cold sheath is a heat sink: it slows heating (less displacement for the same energy)
and speeds cooling; over repeated cycles it warms up and both effects fade.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from hems_ros.physics.jit import jit


def cylinder_conduction_resistance(
    inner_d_m: float, outer_d_m: float, conductivity: float, length_m: float
) -> float:
    """Radial conduction through a tube wall: ln(d_o/d_i) / (2 pi k L), K/W."""
    return math.log(outer_d_m / inner_d_m) / (2.0 * math.pi * conductivity * length_m)


def convection_resistance(h_w_m2_k: float, area_m2: float) -> float:
    """1 / (h A), K/W."""
    return 1.0 / (h_w_m2_k * area_m2)


@dataclass(frozen=True)
class SheathResistances:
    """Thermal resistances of Table 3.1 for a sheath parameter group, K/W."""

    ptfe_conduction: float
    steel_conduction: float
    outer_convection: float
    gap: float

    @property
    def sheathed_total(self) -> float:
        """Wire to air with perfect wire-PTFE contact (Table 3.1: 7.89 K/W)."""
        return self.ptfe_conduction + self.steel_conduction + self.outer_convection

    @property
    def wire_to_sheath(self) -> float:
        """Wire to the (first) sheath node: gap + PTFE wall."""
        return self.gap + self.ptfe_conduction

    @property
    def sheath_to_air(self) -> float:
        """Outer sheath node (the only one, or the helix) to air: steel wall + outer convection."""
        return self.steel_conduction + self.outer_convection


def sheath_resistances(sheath, length_m: float) -> SheathResistances:
    """Table 3.1 resistances from a :class:`~hems_ros.physics.params.Sheath` group."""
    return SheathResistances(
        ptfe_conduction=cylinder_conduction_resistance(
            sheath.ptfe_inner_diameter_m,
            sheath.ptfe_outer_diameter_m,
            sheath.ptfe_conductivity_w_per_m_k,
            length_m,
        ),
        steel_conduction=cylinder_conduction_resistance(
            sheath.steel_inner_diameter_m,
            sheath.steel_outer_diameter_m,
            sheath.steel_conductivity_w_per_m_k,
            length_m,
        ),
        outer_convection=convection_resistance(
            sheath.outer_convection_w_per_m2_k, sheath.outer_area_m2
        ),
        gap=sheath.gap_resistance_k_per_w,
    )


@jit
def sheath_heat_flows(wire_c, sheath_c, outer_c, wire_to_sheath_w_per_k, sheath_to_outer_w_per_k):
    """(wire -> sheath, sheath -> outer) heat flows, W; the outer side is the helix node, or
    the air (a helix held at ambient) for a one-node sheath."""
    return (
        wire_to_sheath_w_per_k * (wire_c - sheath_c),
        sheath_to_outer_w_per_k * (sheath_c - outer_c),
    )


@jit
def helix_heat_loss(helix_c, ambient_c, helix_to_air_w_per_k):
    """Helix node -> air heat flow of the two-node sheath (steel wall + outer convection), W."""
    return helix_to_air_w_per_k * (helix_c - ambient_c)
