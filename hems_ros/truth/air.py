"""Heat a thin horizontal wire loses to still air: free convection and radiation.

Free convection from the Churchill and Chu correlation for a horizontal cylinder (Int. J.
Heat Mass Transfer 18 (1975) 1049-1053), valid over the small Rayleigh numbers of a wire of
half a millimetre; air's conductivity and viscosity follow power laws in the film
temperature, its Prandtl number is held at 0.71. Radiation is a grey body's. The
dissertation evaluates the same correlation once, at a 90 degC wire (Appendix 4.4), and its
model carries a polynomial h(T) fitted over it (ch. 4, heat balance): another form of the
same loss, which here follows the film temperature at every instant.
"""

from __future__ import annotations

STEFAN_BOLTZMANN = 5.670374419e-8  # W/(m2 K4)
GRAVITY = 9.81
PRANDTL = 0.71
KELVIN = 273.15


def air_conductivity(film_k: float) -> float:
    """W/(m K), within a few per cent from 250 to 500 K."""
    return 0.0241 * (film_k / 273.15) ** 0.81


def air_kinematic_viscosity(film_k: float) -> float:
    """m2/s, within a few per cent from 250 to 500 K."""
    return 1.33e-5 * (film_k / 273.15) ** 1.75


def heat_loss_w_m2(wire_c: float, ambient_c: float, diameter_m: float, emissivity: float) -> float:
    """Heat flux from the wire's surface, W/m2 (negative when the air is warmer)."""
    wire_k, ambient_k = wire_c + KELVIN, ambient_c + KELVIN
    difference = wire_k - ambient_k
    film_k = 0.5 * (wire_k + ambient_k)
    nu = air_kinematic_viscosity(film_k)
    alpha = nu / PRANDTL
    rayleigh = GRAVITY * abs(difference) / film_k * diameter_m**3 / (nu * alpha)
    nusselt = (
        0.60
        + 0.387
        * rayleigh ** (1.0 / 6.0)
        / (1.0 + (0.559 / PRANDTL) ** (9.0 / 16.0)) ** (8.0 / 27.0)
    ) ** 2
    convection = nusselt * air_conductivity(film_k) / diameter_m * difference
    radiation = emissivity * STEFAN_BOLTZMANN * (wire_k**4 - ambient_k**4)
    return convection + radiation
