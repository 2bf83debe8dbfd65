"""A Bowden sheath around the wire as radial conduction through its shells.

The wire's heat crosses the air gap to the PTFE liner, the liner, a second gap and the
steel helix, and leaves the helix's outside by free convection (dissertation ch. 3: the
sheath's dimensions, conductivities and outer coefficient, Table 3.1). Each solid shell is
split into thin sub-shells, each a node with its own heat capacity; the gaps hold no heat.
The project's model lumps the whole sheath into one capacity behind one resistance: here the
heat also takes time to cross the liner and the helix.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

AIR_CONDUCTIVITY = 0.028  # W/(m K), near 60 degC


@dataclass(frozen=True)
class Shell:
    """A solid cylindrical shell; radii in m, conductivity W/(m K), heat capacity J/(m3 K)."""

    inner_m: float
    outer_m: float
    conductivity: float
    heat_capacity_j_m3_k: float
    nodes: int = 2


@dataclass(frozen=True)
class Sheath:
    """PTFE liner and steel helix of the dissertation's actuator (ch. 3)."""

    liner: Shell = Shell(0.33e-3, 0.584e-3, 0.25, 2200.0 * 1000.0)
    # a helix of wound wire fills about 80 % of its annulus with steel
    helix: Shell = Shell(0.7e-3, 1.5e-3, 16.0, 0.8 * 7900.0 * 500.0)
    outer_convection_w_m2_k: float = 13.68
    outer_area_m2: float = 9.77e-3

    @property
    def shells(self) -> tuple[Shell, ...]:
        return (self.liner, self.helix)


def _shell_resistance(
    inner_m: float, outer_m: float, conductivity: float, length_m: float
) -> float:
    return math.log(outer_m / inner_m) / (2.0 * math.pi * conductivity * length_m)


@dataclass(frozen=True)
class SheathNetwork:
    """The sheath as a chain of nodes: capacities (J/K) and the resistances (K/W) from the
    wire to the first node, between consecutive nodes, and from the last node to the air."""

    capacities: np.ndarray
    resistances: np.ndarray  # one more than the nodes

    @classmethod
    def build(cls, sheath: Sheath, wire_radius_m: float, length_m: float) -> SheathNetwork:
        capacities, resistances = [], []
        pending = 0.0  # resistance met since the last node
        inner = wire_radius_m
        for shell in sheath.shells:
            pending += _shell_resistance(inner, shell.inner_m, AIR_CONDUCTIVITY, length_m)
            edges = np.linspace(shell.inner_m, shell.outer_m, shell.nodes + 1)
            for a, b in zip(edges[:-1], edges[1:]):
                middle = 0.5 * (a + b)
                resistances.append(
                    pending + _shell_resistance(a, middle, shell.conductivity, length_m)
                )
                capacities.append(shell.heat_capacity_j_m3_k * math.pi * (b * b - a * a) * length_m)
                pending = _shell_resistance(middle, b, shell.conductivity, length_m)
            inner = shell.outer_m
        resistances.append(pending + 1.0 / (sheath.outer_convection_w_m2_k * sheath.outer_area_m2))
        return cls(np.array(capacities), np.array(resistances))

    def flows(
        self, wire_c: float, nodes_c: np.ndarray, ambient_c: float
    ) -> tuple[float, np.ndarray]:
        """(heat leaving the wire, W; each node's temperature rate, K/s)."""
        chain = np.concatenate([[wire_c], nodes_c, [ambient_c]])
        through = np.diff(-chain) / self.resistances  # W, outwards between neighbours
        return through[0], (through[:-1] - through[1:]) / self.capacities
