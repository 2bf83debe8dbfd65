"""Constitutive block (eqs. 4.26-4.31): Brinson rate law, Reuss mixture.

dsigma = E(xi) deps + Omega(xi) dxi + Theta(xi) dT, with eps the wire's Cauchy strain,
elongation positive (the load block converts to the slider's contraction-positive
coordinate: deps = -dx / L). Theta = alpha(xi) E(xi) is kept with the sign and the (1 + nu)
factor as printed; its effect is about 1 mm of a 0.9 m wire per 100 K.
"""

from __future__ import annotations

from hems_ros.physics.jit import jit


@jit
def reuss_modulus(xi, e_martensite, e_austenite):
    """E(xi) = E_M E_A / (E_M (1 - xi) + E_A xi) (eq. 4.28)."""
    return e_martensite * e_austenite / (e_martensite * (1.0 - xi) + e_austenite * xi)


@jit
def transformation_coefficient(modulus, max_recoverable_strain):
    """Omega(xi) = -eps_L E(xi) (eq. 4.29)."""
    return -max_recoverable_strain * modulus


@jit
def thermoelastic_coefficient(xi, modulus, alpha_martensite, alpha_austenite, poisson_ratio):
    """Theta(xi) = alpha(xi) E(xi), alpha = alpha_M xi + alpha_A (1 - xi)(1 + nu)
    (eqs. 4.30-4.31)."""
    alpha = alpha_martensite * xi + alpha_austenite * (1.0 - xi) * (1.0 + poisson_ratio)
    return alpha * modulus


@jit
def stress_increment_at_fixed_strain(omega, theta, dxi, dtemperature):
    """The part of eq. 4.26 not due to strain: Omega dxi + Theta dT."""
    return omega * dxi + theta * dtemperature
