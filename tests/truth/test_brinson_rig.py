"""The independent truth: Brinson's kinetics in rate form, integrated in the wire rig, agree
with the paper's closed forms along monotonic paths, conserve energy, and refuse a rig they
cannot start."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from hems_ros.truth.air import heat_loss_w_m2
from hems_ros.truth.brinson import BrinsonMaterial, phase_rates, stress
from hems_ros.truth.rig import WireRig, simulate

RIG = WireRig()
MAT = RIG.material
PULSE = (
    1.0,
    3.4,
    4.0,
)  # 4 A, the chapter 4 pulses' current, for 2.4 s: most of the wire transforms


@pytest.fixture(scope="module")
def run():
    return simulate(RIG, [PULSE], 30.0, sample_s=0.002)


def test_a_pulse_contracts_the_wire_and_cooling_brings_it_back(run):
    peak = run.contraction_m.max()
    least = run.martensite_fraction.min()
    # the recoverable strain of the transformed share, less the spring's added stretch
    assert 0.6 * MAT.eps_l * (1 - least) * RIG.length_m < peak < MAT.eps_l * RIG.length_m
    assert run.temperature_c.max() > MAT.a_s + RIG.cold_load_n / RIG.section_m2 / MAT.c_a
    assert run.martensite_fraction[-1] == pytest.approx(1.0, abs=1e-6)
    # what is left is the thermoelastic term of the still warm wire
    assert 0.0 < run.contraction_m[-1] < 0.05 * peak


def test_heating_follows_the_closed_reverse_law(run):
    """Brinson (1993): xi = xi0/2 (cos(a_A (T - As - sigma/C_A)) + 1) from xi0 = 1."""
    sigma = run.wire_force_n / RIG.section_m2
    phi = math.pi * (run.temperature_c - MAT.a_s - sigma / MAT.c_a) / (MAT.a_f - MAT.a_s)
    heating = (run.time_s >= PULSE[0]) & (run.time_s < PULSE[1]) & (phi > 0.05)
    assert heating.sum() > 50
    closed = 0.5 * (np.cos(phi[heating]) + 1.0)
    assert np.max(np.abs(run.martensite_fraction[heating] - closed)) < 1e-4


def test_cooling_follows_the_closed_forward_law(run):
    """Brinson (1993), above Ms: xi_s = (1 - xi_s0)/2 cos(psi) + (1 + xi_s0)/2 from the fraction
    the heating left, psi from sigma - C_M (T - Ms) across the detwinning stresses."""
    sigma = run.wire_force_n / RIG.section_m2
    effective = sigma - MAT.c_m * (run.temperature_c - MAT.m_s)
    psi = math.pi * (effective - MAT.sigma_f) / (MAT.sigma_s - MAT.sigma_f)
    start = run.martensite_fraction.min()
    cooling = (run.time_s > PULSE[1]) & (psi < math.pi - 0.05) & (psi > 0.0)
    cooling &= run.temperature_c > MAT.m_s
    assert cooling.sum() > 50
    closed = 0.5 * (1.0 - start) * np.cos(psi[cooling]) + 0.5 * (1.0 + start)
    assert np.max(np.abs(run.martensite_fraction[cooling] - closed)) < 1e-3


def test_the_heat_put_in_is_stored_lost_or_taken_by_the_transformation(run):
    """At every sample: electrical energy = heat stored + convected - latent heat released."""
    volume = RIG.section_m2 * RIG.length_m
    capacity = RIG.density_kg_m3 * volume * RIG.heat_capacity_j_kg_k
    surface = math.pi * RIG.diameter_m * RIG.length_m
    dt = np.diff(run.time_s)
    # the current is constant from each sample to the next (pulse edges fall on samples)
    electrical = np.concatenate([[0.0], np.cumsum(run.current_a[:-1] * run.voltage_v[:-1] * dt)])
    convected = surface * np.array(
        [
            heat_loss_w_m2(t, RIG.ambient_c, RIG.diameter_m, RIG.emissivity)
            for t in run.temperature_c
        ]
    )
    lost = np.concatenate([[0.0], np.cumsum(0.5 * (convected[1:] + convected[:-1]) * dt)])
    stored = capacity * (run.temperature_c - run.temperature_c[0])
    released = (
        RIG.density_kg_m3
        * volume
        * RIG.latent_heat_j_kg
        * (run.martensite_fraction - run.martensite_fraction[0])
    )
    end_of_pulse = np.searchsorted(run.time_s, PULSE[1])
    assert released[end_of_pulse] < -5.0  # joules the reverse transformation took
    assert np.max(np.abs(electrical - (stored + lost - released))) < 0.002 * electrical[-1]


def test_cooling_an_unloaded_wire_between_ms_and_mf_follows_the_twinned_law():
    """Brinson (1993): xi_t = (1 - xi_t0)/2 (cos(a_M (T - Mf)) + 1), here from xi_t0 = 0, at a
    stress under the detwinning start (no strain: the thermoelastic stress alone)."""
    cooling = -2.0  # K/s

    def rates(t, x):
        temp = MAT.m_s + cooling * t
        return [phase_rates(MAT, 0.0, 0.0, x[0], temp, 0.0, cooling, 0.0)[1]]

    span = (MAT.m_s - MAT.m_f) / -cooling
    times = np.linspace(0.0, span, 41)[1:-1]
    solution = solve_ivp(rates, (0.0, span), [0.0], t_eval=times, rtol=1e-9, atol=1e-12)
    temp = MAT.m_s + cooling * times
    assert stress(MAT, 0.0, 0.0, 0.0, temp[0]) < MAT.sigma_s
    closed = 0.5 * (np.cos(math.pi * (temp - MAT.m_f) / (MAT.m_s - MAT.m_f)) + 1.0)
    assert np.max(np.abs(solution.y[0] - closed)) < 1e-5


def test_a_preload_that_cannot_detwin_the_cold_wire_is_refused():
    with pytest.raises(ValueError, match="under the 170 MPa that detwins it fully"):
        WireRig(mass_kg=0.5, preload_n=12.0).cold_state()


def test_a_material_with_its_temperatures_out_of_order_is_refused():
    with pytest.raises(ValueError, match="transformation temperatures out of order"):
        BrinsonMaterial(m_s=60.0, m_f=62.0)


def test_free_convection_matches_the_dissertations_coefficient_at_its_conditions():
    """Appendix 4.4: h = 42.51 W/m2K for this wire at 90 degC in air at 22 degC (the same
    correlation, with air properties of its own)."""
    h = heat_loss_w_m2(90.0, 22.0, 0.508e-3, emissivity=0.0) / (90.0 - 22.0)
    assert h == pytest.approx(42.51, rel=0.08)
    radiation = heat_loss_w_m2(90.0, 22.0, 0.508e-3, 0.1) / (90.0 - 22.0) - h
    assert 0.0 < radiation < 0.05 * h


def test_overlapping_or_backward_pulses_are_refused_naming_them():
    with pytest.raises(ValueError, match=r"\(1.0, 3.0, 4.0\) and \(2.0, 4.0, 4.0\)"):
        simulate(RIG, [(1.0, 3.0, 4.0), (2.0, 4.0, 4.0)], 5.0)
    with pytest.raises(ValueError, match=r"\(3.0, 2.0, 4.0\)"):
        simulate(RIG, [(3.0, 2.0, 4.0)], 5.0)


def test_dahl_friction_holds_the_wire_force_apart_by_twice_its_level_between_the_strokes():
    """Lifting, the wire pulls the load plus the guide's friction; lowering, the load less it:
    at the same contraction the two forces differ by 2 Fc once the friction has built up."""
    rubbing = simulate(WireRig(friction_n=3.0), [PULSE], 30.0, sample_s=0.002)
    free = simulate(RIG, [PULSE], 30.0, sample_s=0.002)

    def spread(run) -> float:
        up = (run.time_s > PULSE[0]) & (run.time_s < PULSE[1])
        down = run.time_s > PULSE[1] + 1.0
        level = 0.5 * run.contraction_m.max()
        f_up = np.interp(level, run.contraction_m[up], run.wire_force_n[up])
        order = np.argsort(run.contraction_m[down])
        return f_up - np.interp(
            level, run.contraction_m[down][order], run.wire_force_n[down][order]
        )

    # the damping's share of the spread is in both; friction adds 2 Fc
    assert spread(rubbing) - spread(free) == pytest.approx(6.0, abs=0.5)
    assert rubbing.contraction_m.max() < free.contraction_m.max()


def test_a_linear_spring_table_is_the_spring_rate():
    k = RIG.spring_n_m
    table = WireRig(spring_table=((-0.05, -0.05 * k), (0.0, 0.0), (0.05, 0.05 * k)))
    a = simulate(table, [PULSE], 10.0)
    b = simulate(RIG, [PULSE], 10.0)
    assert np.max(np.abs(a.contraction_m - b.contraction_m)) < 1e-9
    with pytest.raises(ValueError, match="rising extension"):
        WireRig(spring_table=((0.0, 0.0), (0.0, 1.0)))
