"""The dissertation's own SMA law (ch. 4), written again for truths of the model's family.

The diagnosis fits the project's kernel (``hems_ros.physics``); this module states the same
printed equations in rate form for scipy's solver, with nothing shared: Duhem kinetics with
Likhachev's scaling (eqs. 4.13-4.24) on the transformation temperatures that stress shifts
(eq. 4.25), the Brinson rate law with a Reuss mixture (eqs. 4.26-4.31) and the phases'
resistivities (eqs. 4.3-4.4). The kinetics are the printed first-order law, without the
kernel's return-point memory: a heating that starts from full martensite and a cooling back
to it, which is what the truths' pulses do, is the same path under both. States: the
martensite fraction and the stress.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

# Below this separation the two branches coincide (far outside the loop) and their slopes
# vanish with it, so the fraction does not move whatever the scaling ratio.
BRANCH_GAP_FLOOR = 1e-12


def _branch(u: float, start: float, finish: float) -> tuple[float, float]:
    """(z, dz/du) of a major branch, eqs. 4.21 and 4.23: z = 1/2 tanh(2((start - u) /
    (finish - start) + 1/2)) + 1/2, with (start, finish) = (As, Af) or (Mf, Ms)."""
    width = finish - start
    arg = 2.0 * ((start - u) / width + 0.5)
    return 0.5 * math.tanh(arg) + 0.5, -1.0 / width / math.cosh(arg) ** 2


@dataclass(frozen=True)
class DuhemMaterial:
    """Table 4.1's wire; temperatures in degC, stresses and moduli in Pa."""

    e_austenite: float = 75e9
    e_martensite: float = 28e9
    eps_l: float = 0.038
    m_s: float = 72.0
    m_f: float = 62.0
    a_s: float = 88.0
    a_f: float = 98.0
    c_m: float = 6.89e6  # Pa/K
    c_a: float = 6.89e6  # Pa/K
    alpha_martensite: float = 6.6e-6  # 1/K
    alpha_austenite: float = 11e-6  # 1/K
    poisson: float = 0.33
    rho0_martensite: float = 94.585e-8  # ohm m at t0_martensite
    rho0_austenite: float = 90.858e-8  # ohm m at t0_austenite
    t0_martensite: float = 0.0
    t0_austenite: float = 225.0
    drho_dt_martensite: float = 1.5e-9  # ohm m/K
    drho_dt_austenite: float = 0.5e-9
    drho_dsigma_martensite: float = 1.5e-17  # ohm m/Pa
    drho_dsigma_austenite: float = 0.5e-17

    #: solver tolerances of the states: fraction, Pa
    state_atol = (1e-9, 1.0)

    def modulus(self, xi: float) -> float:
        """Reuss mixture, eq. 4.28."""
        return (
            self.e_martensite
            * self.e_austenite
            / (self.e_martensite * (1.0 - xi) + self.e_austenite * xi)
        )

    def cold(self, sigma: float, temp: float) -> tuple[float, tuple[float, float]]:
        """(strain, states) of martensite at rest under ``sigma``. The rate law knows strain
        only by its rate: the value is the reference the contraction is measured from."""
        return sigma / self.e_martensite + self.eps_l, (1.0, sigma)

    def stress_pa(self, strain: float, states, temp: float) -> float:
        return states[1]

    def martensite(self, states) -> float:
        return min(max(states[0], 0.0), 1.0)

    def resistivity(self, xi: float, temp: float, sigma: float) -> float:
        """Phases in series (eq. 4.3), each linear in temperature and stress (eq. 4.4)."""
        martensite = (
            self.rho0_martensite
            + (temp - self.t0_martensite) * self.drho_dt_martensite
            + sigma * self.drho_dsigma_martensite
        )
        austenite = (
            self.rho0_austenite
            + (temp - self.t0_austenite) * self.drho_dt_austenite
            + sigma * self.drho_dsigma_austenite
        )
        return xi * martensite + (1.0 - xi) * austenite

    def rates(
        self,
        strain: float,
        states,
        temp: float,
        strain_rate: float,
        heating_rate: float,
        latent_rise: float,
    ) -> tuple[list[float], float]:
        """(d states/dt, d xi/dt).

        The fraction's rate drives the temperature (latent heat, ``latent_rise`` K per unit
        of martensite) and the stress (Omega, Theta), which shift the effective temperature
        u = T - sigma/C that drives the fraction; the loop is linear in the rate and solved
        for it in closed form. Heating runs on the austenite branch while u_A rises,
        cooling on the martensite branch while u_M falls.
        """
        xi = self.martensite(states)
        sigma = states[1]
        e = self.modulus(xi)
        omega = -self.eps_l * e
        alpha = self.alpha_martensite * xi + self.alpha_austenite * (1.0 - xi) * (
            1.0 + self.poisson
        )
        theta = alpha * e
        held = e * strain_rate + theta * heating_rate  # the stress rate at a fixed fraction
        z_plus, slope_plus = _branch(temp - sigma / self.c_a, self.a_s, self.a_f)
        z_minus, slope_minus = _branch(temp - sigma / self.c_m, self.m_f, self.m_s)
        gap = z_plus - z_minus
        to_austenite = heating_rate - held / self.c_a
        to_martensite = heating_rate - held / self.c_m
        if gap > BRANCH_GAP_FLOOR and to_austenite > 0.0:
            gain = slope_plus * min(max((xi - z_minus) / gap, 0.0), 1.0)
            c, drive = self.c_a, to_austenite
        elif gap > BRANCH_GAP_FLOOR and to_martensite < 0.0:
            gain = slope_minus * min(max((z_plus - xi) / gap, 0.0), 1.0)
            c, drive = self.c_m, to_martensite
        else:
            return [0.0, held], 0.0
        feedback = latent_rise - (omega + theta * latent_rise) / c
        rate = gain * drive / (1.0 - gain * feedback)
        return [rate, held + (omega + theta * latent_rise) * rate], rate
