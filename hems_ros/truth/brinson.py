"""Brinson's one-dimensional SMA model: stress law and cosine phase kinetics.

L. C. Brinson, "One-dimensional constitutive behavior of shape memory alloys:
thermomechanical derivation with non-constant material functions and redefined martensite
internal variable", J. Intell. Mater. Syst. Struct. 4 (1993) 229-242. Martensite is split
into a stress-induced, detwinned fraction ``xi_s`` (the one that carries the recoverable
strain) and a temperature-induced, twinned fraction ``xi_t``. The project's own model (a
single fraction with tanh kinetics, dissertation ch. 4) is another family; the diagnosis
meets this one only through the runs it produces.

The paper writes each transformation in closed form from the fractions at its start. Here
each is used in rate form, its derivative along the path with those start values replaced
by the current fractions, so that an ODE solver can carry the fractions as states: along a
monotonic path the two agree (tests/truth/test_brinson.py), and a transformation that
reverses inside its band goes on from where it is instead of from the band's edge.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

# A fraction this close to 0 or 1 has nothing left to transform.
FRACTION_EPS = 1e-9


@dataclass(frozen=True)
class BrinsonMaterial:
    """Material functions; temperatures in degC, stresses and moduli in Pa.

    Transformation temperatures, moduli, stress slopes and the recoverable strain are the
    dissertation's wire (Table 4.1); the critical detwinning stresses and the thermoelastic
    coefficient, which that model has no counterpart for, are Brinson's (1993, Table 1).
    """

    e_austenite: float = 75e9
    e_martensite: float = 28e9
    theta: float = 0.55e6  # Pa/K
    eps_l: float = 0.038
    m_s: float = 72.0
    m_f: float = 62.0
    a_s: float = 88.0
    a_f: float = 98.0
    c_m: float = 6.89e6  # Pa/K
    c_a: float = 6.89e6  # Pa/K
    sigma_s: float = 100e6  # detwinning starts
    sigma_f: float = 170e6  # detwinning ends
    t_ref: float = 20.0  # temperature of zero thermal stress
    resistivity_martensite_ohm_m: float = 94.585e-8  # each phase's constant value
    resistivity_austenite_ohm_m: float = 90.858e-8

    #: solver tolerances of the states: the detwinned and the twinned fraction
    state_atol = (1e-9, 1e-9)

    def __post_init__(self) -> None:
        if not (self.m_f < self.m_s and self.a_s < self.a_f):
            raise ValueError(f"transformation temperatures out of order: {self}")
        if not self.sigma_s < self.sigma_f:
            raise ValueError(f"critical stresses out of order: {self}")

    # The rig's view of a material (shared with ``duhem.DuhemMaterial``): states (xi_s, xi_t).
    def cold(self, sigma: float, temp: float) -> tuple[float, tuple[float, float]]:
        """(strain, states) of fully detwinned martensite at rest under ``sigma``."""
        if sigma <= self.sigma_f:
            raise ValueError(
                f"the cold load stresses the wire to {sigma / 1e6:.0f} MPa, under the "
                f"{self.sigma_f / 1e6:.0f} MPa that detwins it fully: the cold wire would not "
                "start as detwinned martensite"
            )
        return strain_at(self, sigma, 1.0, 0.0, temp), (1.0, 0.0)

    def stress_pa(self, strain: float, states, temp: float) -> float:
        return stress(self, strain, *self._fractions(states), temp)

    def martensite(self, states) -> float:
        return sum(self._fractions(states))

    def resistivity(self, xi: float, temp: float, sigma: float) -> float:
        return (
            xi * self.resistivity_martensite_ohm_m + (1.0 - xi) * self.resistivity_austenite_ohm_m
        )

    def rates(self, strain, states, temp, strain_rate, heating_rate, latent_rise):
        """(d states/dt, d xi/dt): :func:`phase_rates` and their sum."""
        xs_rate, xt_rate = phase_rates(
            self, strain, *self._fractions(states), temp, strain_rate, heating_rate, latent_rise
        )
        return [xs_rate, xt_rate], xs_rate + xt_rate

    @staticmethod
    def _fractions(states) -> tuple[float, float]:
        xi_s = min(max(states[0], 0.0), 1.0)
        return xi_s, min(max(states[1], 0.0), 1.0 - xi_s)


def modulus(mat: BrinsonMaterial, xi: float) -> float:
    """Young's modulus of the mixture, Pa (linear in the martensite fraction)."""
    return mat.e_austenite + xi * (mat.e_martensite - mat.e_austenite)


def stress(mat: BrinsonMaterial, strain: float, xi_s: float, xi_t: float, temp: float) -> float:
    """Stress, Pa, of the direct (non-incremental) stress law: elastic strain is the strain
    less the detwinned fraction's transformation strain."""
    return modulus(mat, xi_s + xi_t) * (strain - mat.eps_l * xi_s) + mat.theta * (temp - mat.t_ref)


def strain_at(mat: BrinsonMaterial, sigma: float, xi_s: float, xi_t: float, temp: float) -> float:
    """The strain at which :func:`stress` gives ``sigma``."""
    return (sigma - mat.theta * (temp - mat.t_ref)) / modulus(mat, xi_s + xi_t) + mat.eps_l * xi_s


def phase_rates(
    mat: BrinsonMaterial,
    strain: float,
    xi_s: float,
    xi_t: float,
    temp: float,
    strain_rate: float,
    heating_rate: float,
    latent_rise: float,
) -> tuple[float, float]:
    """(d xi_s/dt, d xi_t/dt), 1/s.

    ``heating_rate``: dT/dt without transformation, K/s; ``latent_rise``: the temperature rise
    per unit of martensite formed (latent heat over heat capacity), K. The latent heat and the
    fractions' share in the stress feed back on the rates they drive; each case solves that
    loop for the rate in closed form (it is linear). At most one transformation runs at a time:
    to austenite when heated (or unloaded) inside its band, else to detwinned martensite
    when loaded (or cooled) inside its band, else to twinned martensite when cooled between
    Mf and Ms under a stress too low to detwin.
    """
    xi = xi_s + xi_t
    e = modulus(mat, xi)
    elastic = strain - mat.eps_l * xi_s
    dsig_dxs = (mat.e_martensite - mat.e_austenite) * elastic - e * mat.eps_l
    dsig_dxt = (mat.e_martensite - mat.e_austenite) * elastic
    sigma = stress(mat, strain, xi_s, xi_t, temp)
    stress_rate0 = e * strain_rate + mat.theta * heating_rate  # with the fractions held

    if xi > FRACTION_EPS:  # martensite to austenite, both fractions in proportion
        phi = math.pi * (temp - mat.a_s - sigma / mat.c_a) / (mat.a_f - mat.a_s)
        drive0 = heating_rate - stress_rate0 / mat.c_a
        if 0.0 < phi < math.pi and drive0 > 0.0:
            gain = -xi * math.pi / (mat.a_f - mat.a_s) * math.tan(0.5 * phi)
            stress_per_xi = (dsig_dxs * xi_s + dsig_dxt * xi_t) / xi + mat.theta * latent_rise
            drive1 = latent_rise - stress_per_xi / mat.c_a
            rate = gain * drive0 / (1.0 - gain * drive1)
            return rate * xi_s / xi, rate * xi_t / xi

    if xi_s < 1.0 - FRACTION_EPS:  # to detwinned martensite, from austenite and twinned
        above_ms = temp > mat.m_s
        c_m = mat.c_m if above_ms else 0.0
        effective = sigma - c_m * (temp - mat.m_s)
        psi = math.pi * (effective - mat.sigma_f) / (mat.sigma_s - mat.sigma_f)
        drive0 = stress_rate0 - c_m * heating_rate
        if 0.0 < psi < math.pi and drive0 > 0.0:
            twinned_share = xi_t / (1.0 - xi_s)
            gain = (1.0 - xi_s) / math.tan(0.5 * psi) * math.pi / (mat.sigma_f - mat.sigma_s)
            xi_per_xs = 1.0 - twinned_share
            stress_per_xs = (
                dsig_dxs - dsig_dxt * twinned_share + mat.theta * latent_rise * xi_per_xs
            )
            drive1 = stress_per_xs - c_m * latent_rise * xi_per_xs
            rate = gain * drive0 / (1.0 - gain * drive1)
            return rate, -rate * twinned_share

    if (
        xi < 1.0 - FRACTION_EPS
        and mat.m_f < temp < mat.m_s
        and heating_rate < 0.0
        and sigma < mat.sigma_s
    ):  # to twinned martensite on cooling
        chi = math.pi * (temp - mat.m_f) / (mat.m_s - mat.m_f)
        gain = -(1.0 - xi) * math.pi / (mat.m_s - mat.m_f) / math.tan(0.5 * chi)
        return 0.0, gain * heating_rate / (1.0 - gain * latent_rise)
    return 0.0, 0.0
