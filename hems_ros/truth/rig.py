"""A bare SMA wire lifting a hanging mass against a pretensioned series spring, heated by
current pulses.

The rig of the dissertation's chapter 3 characterisation (a 30 N mass and a spring
pretensioned to 20 N, 754 N/m) on the chapter 4 wire (Table 4.1), written again with its own
equations: a material (Brinson's, ``brinson``, or the dissertation's own law written again,
``duhem``) that gives the stress, the transformation and the resistivity, a lumped wire
temperature with Joule heating over the wire's current length, free convection and radiation
to still air (``air``) or the h(T) of eqs. 4.7-4.12, the transformation's latent heat, and
the mass's motion with viscous damping; the wire bare or in a Bowden sheath (``sheath``).
Two effects in forms of their own: dry friction on the mass's guide with pre-sliding (Dahl
1968: the friction force F follows dF/dx = sigma0 (1 - F/Fc sgn(v)), so it builds up over a
short travel instead of jumping to Fc), and a bias spring given by a force-extension table
(linear between its points) instead of a rate. States: wire temperature, wire elongation,
the mass's velocity, the friction force, the material's two states (Brinson's two martensite
fractions, or the fraction and the stress of the dissertation's own law, ``duhem``), the
sheath's nodes; scipy's LSODA integrates them between the current's edges at tolerances of
this module. The current comes in pulses here, or through a PWM drive under a position loop
(``drive``); the wire may start warmer than the room (``start_c``).
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field

import numpy as np
from scipy.integrate import solve_ivp

from hems_ros.truth.air import heat_loss_w_m2
from hems_ros.truth.brinson import BrinsonMaterial
from hems_ros.truth.duhem import DuhemMaterial
from hems_ros.truth.sheath import Sheath, SheathNetwork

RTOL = 1e-7
ATOL = [1e-6, 1e-10, 1e-8, 1e-6]  # K, m, m/s, N; then the material's states; 1e-6 K a node
MATERIAL_STATES = 4  # where the material's two states start
MAX_STEP_S = 0.005  # the fractions' rates switch on and off inside a step


@dataclass(frozen=True)
class WireRig:
    """SI units; temperatures in degC. Wire and heat data are the dissertation's Table 4.1."""

    material: BrinsonMaterial | DuhemMaterial = field(default_factory=BrinsonMaterial)
    length_m: float = 0.9
    diameter_m: float = 0.508e-3
    density_kg_m3: float = 6450.0
    heat_capacity_j_kg_k: float = 837.4
    latent_heat_j_kg: float = 24183.52
    emissivity: float = 0.1  # bright NiTi: radiation a few per cent of the loss
    # (h0 W/m2K, h2 W/m2K3) of the h(T) = h0 + h2 T^2 of eqs. 4.7-4.12 for the bare wire's loss;
    # None: free convection and radiation to still air (``air``)
    convection_h0_h2: tuple[float, float] | None = None
    ambient_c: float = 20.0
    mass_kg: float = 30.0 / 9.81
    gravity_m_s2: float = 9.81
    spring_n_m: float = 754.0
    preload_n: float = 20.0  # the spring's pull on the cold wire at rest
    damping_n_s_m: float = 65.0
    sheath: Sheath | None = None  # a bare wire
    friction_n: float = 0.0  # Dahl's Coulomb level Fc on the mass's guide; 0: none
    friction_stiffness_n_m: float = 2.0e4  # Dahl's sigma0: Fc is reached over about Fc/sigma0
    # (extension from the cold rest position m, spring force change N) points, rising; the
    # spring then pulls ``preload_n`` plus the table's value instead of spring_n_m * extension
    spring_table: tuple[tuple[float, float], ...] | None = None
    start_c: float | None = None  # the wire's and sheath's temperature at the start

    def __post_init__(self) -> None:
        if self.friction_n < 0.0 or self.friction_stiffness_n_m <= 0.0:
            raise ValueError("friction_n must be >= 0 and friction_stiffness_n_m > 0")
        if self.spring_table is not None:
            ext = [e for e, _ in self.spring_table]
            if len(ext) < 2 or any(b <= a for a, b in zip(ext[:-1], ext[1:])):
                raise ValueError("spring_table needs two or more points of rising extension")

    def spring_force_n(self, extension_m: float) -> float:
        """The spring's pull beyond its pretension at ``extension_m`` past the cold rest."""
        if self.spring_table is None:
            return self.spring_n_m * extension_m
        ext, force = zip(*self.spring_table)
        return float(np.interp(extension_m, ext, force, left=None, right=None))

    def network(self) -> SheathNetwork | None:
        if self.sheath is None:
            return None
        return SheathNetwork.build(self.sheath, 0.5 * self.diameter_m, self.length_m)

    @property
    def cold_load_n(self) -> float:
        """The wire's tension at rest, cold: the mass's weight and the spring's pretension."""
        return self.mass_kg * self.gravity_m_s2 + self.preload_n

    @property
    def section_m2(self) -> float:
        return math.pi * self.diameter_m**2 / 4.0

    def cold_state(self) -> np.ndarray:
        """At rest, all (detwinned) martensite under the cold load, wire and sheath at
        ``start_c`` (the room's temperature unless told)."""
        warm = self.ambient_c if self.start_c is None else self.start_c
        strain, states = self.material.cold(self.cold_load_n / self.section_m2, warm)
        network = self.network()
        nodes = [] if network is None else [warm] * network.capacities.size
        return np.array([warm, strain * self.length_m, 0.0, 0.0, *states, *nodes])

    def bare_loss_w(self, temp: float) -> float:
        """Heat the bare wire gives the room at ``temp``, W."""
        surface = math.pi * self.diameter_m * self.length_m
        if self.convection_h0_h2 is None:
            return surface * heat_loss_w_m2(temp, self.ambient_c, self.diameter_m, self.emissivity)
        h0, h2 = self.convection_h0_h2
        return surface * (h0 + h2 * temp * temp) * (temp - self.ambient_c)


@dataclass(frozen=True)
class RigRun:
    """Samples of a run; ``contraction_m`` is the mass's travel from the cold rest position."""

    time_s: np.ndarray
    current_a: np.ndarray
    voltage_v: np.ndarray
    temperature_c: np.ndarray
    wire_force_n: np.ndarray
    contraction_m: np.ndarray
    martensite_fraction: np.ndarray
    sheath_node_c: np.ndarray  # (samples, nodes), inside out; no columns for a bare wire
    duty_percent: np.ndarray | None = None  # a PWM drive's duty; None: a current source


def _derivatives(
    rig: WireRig,
    network: SheathNetwork | None,
    power_w: Callable[[float], float],
    rest_m: float,
    x: np.ndarray,
) -> list[float]:
    mat = rig.material
    temp, elongation, velocity, friction = x[0], x[1], x[2], x[3]
    states = x[MATERIAL_STATES : MATERIAL_STATES + 2]
    strain = elongation / rig.length_m
    sigma = mat.stress_pa(strain, states, temp)
    volume = rig.section_m2 * rig.length_m
    heat_capacity = rig.density_kg_m3 * volume * rig.heat_capacity_j_kg_k
    contraction = rest_m - elongation
    power = power_w(_resistance(rig, mat.martensite(states), temp, sigma, contraction))
    if network is None:
        loss = rig.bare_loss_w(temp)
        node_rates: list[float] = []
    else:
        loss, rates = network.flows(temp, x[MATERIAL_STATES + 2 :], rig.ambient_c)
        node_rates = list(rates)
    heating_rate = (power - loss) / heat_capacity
    latent_rise = rig.latent_heat_j_kg / rig.heat_capacity_j_kg_k
    state_rates, xi_rate = mat.rates(
        strain, states, temp, velocity / rig.length_m, heating_rate, latent_rise
    )
    wire_force = sigma * rig.section_m2
    load = rig.cold_load_n + rig.spring_force_n(rest_m - elongation)  # the spring stretches
    # the guide's friction opposes the mass's motion; velocity > 0 is the wire lengthening
    acceleration = (load - wire_force - rig.damping_n_s_m * velocity - friction) / rig.mass_kg
    friction_rate = _dahl_rate(rig, friction, velocity)
    return [
        heating_rate + latent_rise * xi_rate,
        velocity,
        acceleration,
        friction_rate,
        *state_rates,
        *node_rates,
    ]


def _dahl_rate(rig: WireRig, friction: float, velocity: float) -> float:
    if rig.friction_n == 0.0:
        return 0.0
    direction = 1.0 if velocity >= 0.0 else -1.0
    return rig.friction_stiffness_n_m * (1.0 - friction / rig.friction_n * direction) * velocity


def _resistance(rig: WireRig, xi: float, temp: float, sigma: float, contraction: float) -> float:
    """R = rho l / S (eq. 4.2) over the wire's current length: it shortens as it contracts."""
    return rig.material.resistivity(xi, temp, sigma) * (rig.length_m - contraction) / rig.section_m2


def simulate(
    rig: WireRig,
    pulses: Sequence[tuple[float, float, float]],
    duration_s: float,
    sample_s: float = 0.01,
) -> RigRun:
    """The rig from its cold state for ``duration_s``, sampled every ``sample_s``.

    ``pulses``: (start s, end s, current A), not overlapping; no current between them.
    """
    ordered = sorted(pulses)
    bad = [p for p in ordered if not 0.0 <= p[0] < p[1]] + [
        f"{a} and {b}" for a, b in zip(ordered[:-1], ordered[1:]) if b[0] < a[1]
    ]
    if bad:
        raise ValueError(
            f"pulses must start at 0 s or later, end after they start and not "
            f"overlap: {', '.join(map(str, bad))}"
        )
    edges = sorted(
        {0.0, duration_s, *(t for a, b, _ in pulses for t in (a, b) if 0 < t < duration_s)}
    )
    times = np.arange(0.0, duration_s + 0.5 * sample_s, sample_s)
    state = rig.cold_state()
    network = rig.network()
    rest_m = state[1]
    rows = []
    for start, end in zip(edges[:-1], edges[1:]):
        amps = _current(pulses, start)
        t_eval = np.append(times[(times >= start) & (times < end)], end)
        t, states = integrate(rig, network, rest_m, state, start, t_eval, _joule(amps))
        rows += [(ti, amps, *x) for ti, x in zip(t[:-1], states[:-1])]
        state = states[-1]
    if times[-1] > rows[-1][0]:
        rows.append((times[-1], _current(pulses, times[-1]), *state))
    return sampled(rig, rest_m, np.array(rows))


def integrate(
    rig: WireRig,
    network: SheathNetwork | None,
    rest_m: float,
    state: np.ndarray,
    start: float,
    t_eval: np.ndarray,
    power_w: Callable[[float], float],
) -> tuple[np.ndarray, np.ndarray]:
    """The rig's states at ``t_eval`` from ``state`` at ``start`` to the last of ``t_eval``,
    the wire heated by ``power_w(its resistance)``: (times, states by row)."""
    end = float(t_eval[-1])
    solution = solve_ivp(
        lambda t, x: _derivatives(rig, network, power_w, rest_m, x),
        (start, end),
        state,
        method="LSODA",
        t_eval=t_eval,
        rtol=RTOL,
        atol=ATOL + list(rig.material.state_atol) + [1e-6] * (state.size - len(ATOL) - 2),
        max_step=MAX_STEP_S,
    )
    if not solution.success:
        raise RuntimeError(
            f"the rig's integration failed at {start:g}-{end:g} s: {solution.message}"
        )
    return solution.t, solution.y.T


def _joule(amps: float) -> Callable[[float], float]:
    return lambda ohm: amps * amps * ohm


def _current(pulses: Sequence[tuple[float, float, float]], t: float) -> float:
    return next((amps for start, end, amps in pulses if start <= t < end), 0.0)


def resistance_ohm(rig: WireRig, rest_m: float, x: np.ndarray) -> float:
    """The wire's resistance in the state ``x``."""
    states = x[MATERIAL_STATES : MATERIAL_STATES + 2]
    sigma = rig.material.stress_pa(x[1] / rig.length_m, states, x[0])
    return _resistance(rig, rig.material.martensite(states), x[0], sigma, rest_m - x[1])


def sampled(
    rig: WireRig, rest_m: float, rows: np.ndarray, duty_percent: np.ndarray | None = None
) -> RigRun:
    """The run of ``rows`` (time, mean current, states); ``duty_percent`` of a PWM drive."""
    t, amps, temp, elongation = rows.T[:4]
    states = rows[:, 2 + MATERIAL_STATES : 4 + MATERIAL_STATES]
    mat = rig.material
    xi = np.array([mat.martensite(s) for s in states])
    sigma = np.array(
        [mat.stress_pa(e / rig.length_m, s, c) for e, s, c in zip(elongation, states, temp)]
    )
    force = sigma * rig.section_m2
    contraction = rest_m - elongation
    resistance = np.array([_resistance(rig, *row) for row in zip(xi, temp, sigma, contraction)])
    return RigRun(
        time_s=t,
        current_a=amps,
        voltage_v=amps * resistance,
        temperature_c=temp,
        wire_force_n=force,
        contraction_m=contraction,
        martensite_fraction=xi,
        sheath_node_c=rows[:, 4 + MATERIAL_STATES :],
        duty_percent=duty_percent,
    )
