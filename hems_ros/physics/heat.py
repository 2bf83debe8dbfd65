"""Heat block (eqs. 4.7-4.12, appendix 4.4).

Lumped wire heat balance rho V c_p dT/dt = P - Q_out + rho V dH dxi/dt. The kernel solves
it over each step together with the kinetics, C dT = (P - Q) dt + L dxi (kernel.step):
while the wire transforms, the latent heat holds the temperature back, which appears as
the plateau of the cooling curve.

The Churchill-Chu correlation derives h for a horizontal cylinder from geometry; with the
appendix conditions it gives the h(22 degC) = 42.51 W/m2K of h(T) = h0 + h2 T^2.
"""

from __future__ import annotations

from hems_ros.physics.jit import jit

# Appendix 4.4: air at 22 degC, wire at 90 degC.
APPENDIX_GRASHOF = 1.6947
APPENDIX_PRANDTL = 0.591
APPENDIX_AIR_CONDUCTIVITY = 0.0257


@jit
def convection_coefficient(temperature_c, h0, h2):
    """h(T) = h0 + h2 T^2, T in degC (eqs. 4.7-4.12); h(22) = 42.51 W/m2K with Table 4.1."""
    return h0 + h2 * temperature_c * temperature_c


@jit
def convection_loss(temperature_c, ambient_c, h0, h2, area_m2):
    """Q = h(T) A (T - T_amb) (eqs. 4.7-4.12)."""
    return convection_coefficient(temperature_c, h0, h2) * area_m2 * (temperature_c - ambient_c)


def churchill_chu_nusselt(rayleigh: float, prandtl: float) -> float:
    """Nu = (0.60 + 0.387 Ra^(1/6) / (1 + (0.559/Pr)^(9/16))^(8/27))^2 (appendix 4.4)."""
    if not (rayleigh > 0 and prandtl > 0):
        raise ValueError(f"Rayleigh {rayleigh!r} and Prandtl {prandtl!r} must be > 0")
    return (
        0.60 + 0.387 * rayleigh ** (1 / 6) / (1 + (0.559 / prandtl) ** (9 / 16)) ** (8 / 27)
    ) ** 2


def grashof_number(
    diameter_m: float,
    surface_c: float,
    air_c: float,
    kinematic_viscosity_m2_s: float,
    gravity: float = 9.81,
) -> float:
    """Gr = g beta (T_s - T_air) d^3 / nu^2 with beta = 1/T_air (ideal gas, K)."""
    beta = 1.0 / (air_c + 273.15)
    return gravity * beta * (surface_c - air_c) * diameter_m**3 / kinematic_viscosity_m2_s**2


def free_convection_h(
    diameter_m: float, grashof: float, prandtl: float, air_conductivity_w_m_k: float
) -> tuple[float, float]:
    """(Nu, h = Nu k / d) of a horizontal cylinder from Gr and Pr (appendix 4.4)."""
    nu = churchill_chu_nusselt(grashof * prandtl, prandtl)
    return nu, nu * air_conductivity_w_m_k / diameter_m


def appendix_free_convection(diameter_m: float = 0.508e-3) -> tuple[float, float]:
    """(Nu, h) at the appendix 4.4 conditions: Nu = 0.8403, h = 42.51 W/m2K."""
    return free_convection_h(
        diameter_m, APPENDIX_GRASHOF, APPENDIX_PRANDTL, APPENDIX_AIR_CONDUCTIVITY
    )


def lossless_temperature_c(
    energy_j: float,
    transformed_fraction: float,
    heat_capacity_j_per_k: float,
    latent_heat_j: float,
    ambient_c: float,
) -> float:
    """Wire temperature after ``energy_j`` of heating with no heat loss at all, degC.

    The heat balance of eqs. 4.7-4.12 integrated with Q_out = 0 from a cold, fully martensitic
    wire at ambient:
    C (T - T_amb) = E - f L, where ``transformed_fraction`` f of the wire has turned to
    austenite and taken f L of latent heat (``latent_heat_j`` = rho V dH for the whole wire,
    ``heat_capacity_j_per_k`` = rho V c_p). Every real loss lowers T, so a transformation
    measured after E joules happened at or below this temperature.
    """
    if not 0.0 <= transformed_fraction <= 1.0:
        raise ValueError(f"transformed_fraction must be in [0, 1], got {transformed_fraction!r}")
    if not heat_capacity_j_per_k > 0:
        raise ValueError(f"heat_capacity_j_per_k must be > 0, got {heat_capacity_j_per_k!r}")
    return ambient_c + (energy_j - transformed_fraction * latent_heat_j) / heat_capacity_j_per_k


__all__ = [
    "convection_coefficient",
    "convection_loss",
    "lossless_temperature_c",
    "churchill_chu_nusselt",
    "grashof_number",
    "free_convection_h",
    "appendix_free_convection",
]
