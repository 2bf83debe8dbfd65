"""Electrical block (eqs. 4.1-4.5) and the drive stages.

Three drives feed the wire: the dissertation's ideal current source (validation runs), the
HEMS PWM stage (20 V supply, 4 A current limit, duty 0-100 %), and a constant-voltage
source (shows the thermal runaway: a shorter, austenitic wire has a lower resistance and so
draws more power). A fourth drive feeds no power and imposes the wire temperature instead
(DRIVE_TEMPERATURE, the drive value in degC at the end of the step: the quasi-static
thermal cycles at constant stress that materials labs publish, which test the kinetics and
the constitutive law without the heat balance). All functions are scalar and
numba-compiled; the kernel inlines them.
"""

from __future__ import annotations

from hems_ros.physics.jit import jit

DRIVE_DUTY = 0
DRIVE_CURRENT = 1
DRIVE_VOLTAGE = 2
DRIVE_TEMPERATURE = 3
DRIVE_NAMES = {
    "duty": DRIVE_DUTY,
    "current": DRIVE_CURRENT,
    "voltage": DRIVE_VOLTAGE,
    "temperature": DRIVE_TEMPERATURE,
}


@jit
def phase_resistivity(rho0, t0_c, drho_dt, drho_dsigma, temperature_c, stress_pa):
    """Resistivity of one phase, eq. 4.4: rho = rho0 + (T - T0) drho/dT + sigma drho/dsigma."""
    return rho0 + (temperature_c - t0_c) * drho_dt + stress_pa * drho_dsigma


@jit
def mixture_resistivity(xi, rho_martensite, rho_austenite):
    """Phases in series, eq. 4.3: rho = rho_M xi + rho_A (1 - xi)."""
    return rho_martensite * xi + rho_austenite * (1.0 - xi)


@jit
def wire_resistance(resistivity, length_m, inv_cross_section_per_m2):
    """R = rho l / S with the current wire length l (eq. 4.2); takes 1/S (a constant of
    the parameter set that the batch would otherwise divide by in every step)."""
    return resistivity * length_m * inv_cross_section_per_m2


@jit
def current_source(current_a, resistance):
    """Ideal current source (the dissertation's validation drive): P = I^2 R (eq. 4.1)."""
    return current_a, current_a * current_a * resistance


@jit
def pwm_stage(duty_percent, resistance, supply_v, current_limit_a, source_resistance=0.0):
    """HEMS PWM MOSFET stage: while on, I = min(V/(R + R_s), I_limit); returns period means.

    Mean current = duty * I_on; mean power = duty * I_on^2 R (the I^2 R of the on-time, not
    the square of the mean current). R_s (``source_resistance``, ohm) is the supply sag: the
    supply, MOSFET and leads in series drop part of V, and the heat they dissipate is not
    the wire's.
    """
    i_on = supply_v / (resistance + source_resistance)
    if i_on > current_limit_a:
        i_on = current_limit_a
    d = duty_percent * 0.01
    return d * i_on, d * i_on * i_on * resistance


@jit
def voltage_source(voltage_v, resistance):
    """Constant voltage across the wire: I = V/R, P = V^2/R (grows as R falls: runaway)."""
    i = voltage_v / resistance
    return i, voltage_v * i


def select_drive(
    duty: float | None,
    current: float | None,
    voltage: float | None,
    temperature: float | None = None,
):
    """(kind name, value) of the one drive given; ValueError unless exactly one is given."""
    given = [
        (k, v)
        for k, v in (
            ("duty", duty),
            ("current", current),
            ("voltage", voltage),
            ("temperature", temperature),
        )
        if v is not None
    ]
    if len(given) != 1:
        raise ValueError(
            "give exactly one of duty, current, voltage, temperature "
            f"(got {', '.join(k for k, _ in given) or 'none'})"
        )
    return given[0]
