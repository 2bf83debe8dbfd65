"""The dissertation's law written again for the truths: heating follows the printed major
branch at the stress-shifted temperatures, the heat balance closes, the rig's equilibrium
holds with the spring and the mass, and cooling brings the wire back to its cold rest."""

from __future__ import annotations

import math

import numpy as np
import pytest

from hems_ros.truth.cases import FAMILIES
from hems_ros.truth.duhem import DuhemMaterial
from hems_ros.truth.rig import simulate

RIG = FAMILIES["dissertation"]
MAT = RIG.material
PULSE = (1.0, 3.0, 4.5)  # a part of the wire transforms


@pytest.fixture(scope="module")
def run():
    return simulate(RIG, [PULSE], 25.0, sample_s=0.002)


def test_the_family_is_the_dissertations_law_with_its_convection():
    assert isinstance(MAT, DuhemMaterial)
    assert RIG.convection_h0_h2 == (37.67, 0.01)
    # h(T) of eqs. 4.7-4.12 at 22 degC: 42.51 W/m2K
    assert RIG.bare_loss_w(22.0) / (math.pi * RIG.diameter_m * RIG.length_m) / (
        22.0 - RIG.ambient_c
    ) == pytest.approx(42.51, abs=0.01)


def test_heating_follows_the_austenite_branch_at_the_stress_shifted_temperature(run):
    """From full martensite, eqs. 4.21-4.22 keep xi on z+(T - sigma/C_A) while it heats."""
    sigma = run.wire_force_n / RIG.section_m2
    u = run.temperature_c - sigma / MAT.c_a
    z_plus = 0.5 * np.tanh(2.0 * ((MAT.a_s - u) / (MAT.a_f - MAT.a_s) + 0.5)) + 0.5
    heating = (run.time_s > PULSE[0] + 0.2) & (run.time_s < PULSE[1])
    assert run.martensite_fraction[heating].min() < 0.6  # the pulse transforms much of it
    assert np.max(np.abs(run.martensite_fraction[heating] - z_plus[heating])) < 2e-3


def test_the_heat_put_in_is_stored_lost_or_taken_by_the_transformation(run):
    volume = RIG.section_m2 * RIG.length_m
    capacity = RIG.density_kg_m3 * volume * RIG.heat_capacity_j_kg_k
    dt = np.diff(run.time_s)
    electrical = np.concatenate([[0.0], np.cumsum(run.current_a[:-1] * run.voltage_v[:-1] * dt)])
    loss = np.array([RIG.bare_loss_w(t) for t in run.temperature_c])
    lost = np.concatenate([[0.0], np.cumsum(0.5 * (loss[1:] + loss[:-1]) * dt)])
    stored = capacity * (run.temperature_c - run.temperature_c[0])
    released = (
        RIG.density_kg_m3
        * volume
        * RIG.latent_heat_j_kg
        * (run.martensite_fraction - run.martensite_fraction[0])
    )
    assert released.min() < -2.0  # joules the reverse transformation took
    assert np.max(np.abs(electrical - (stored + lost - released))) < 0.002 * electrical[-1]


def test_the_wire_holds_the_mass_the_spring_and_the_damper(run):
    """Contraction x lifts the mass and stretches the spring: F = m g + F0 + k x + b x' + m x''."""
    x = run.contraction_m
    velocity = np.gradient(x, run.time_s)
    acceleration = np.gradient(velocity, run.time_s)
    load = (
        RIG.cold_load_n
        + RIG.spring_n_m * x
        + RIG.damping_n_s_m * velocity
        + RIG.mass_kg * acceleration
    )
    inner = slice(5, -5)  # the differences are one-sided at the ends
    assert np.max(np.abs(run.wire_force_n[inner] - load[inner])) < 0.1
    assert run.wire_force_n.max() - RIG.cold_load_n > 0.9 * RIG.spring_n_m * x.max()


def test_cooling_brings_the_wire_back_to_martensite_at_its_cold_rest(run):
    assert run.contraction_m.max() > 0.01
    assert run.martensite_fraction[-1] == pytest.approx(1.0, abs=1e-3)
    assert abs(run.contraction_m[-1]) < 0.02 * run.contraction_m.max()
