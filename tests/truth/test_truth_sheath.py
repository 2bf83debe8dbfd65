"""The sheath as radial shells: its resistances are the dissertation's (Table 3.1), the heat
the wire loses goes into the shells or the air, and the sheath takes heat the bare wire keeps."""

from __future__ import annotations

import numpy as np
import pytest

from hems_ros.truth.rig import WireRig, simulate
from hems_ros.truth.sheath import Sheath, SheathNetwork

RIG = WireRig(sheath=Sheath())
PULSE = (1.0, 3.4, 4.0)


def shell(inner_m: float, outer_m: float, conductivity: float) -> float:
    return np.log(outer_m / inner_m) / (2 * np.pi * conductivity * 0.9)


def test_the_shells_give_the_dissertations_resistances():
    network = SheathNetwork.build(Sheath(), 0.254e-3, 0.9)
    ptfe = shell(0.33e-3, 0.584e-3, 0.25)
    assert ptfe == pytest.approx(0.4038, abs=1e-4)  # Table 3.1's PTFE conduction, K/W
    steel_out = 1.0 / (13.68 * 9.77e-3)
    assert steel_out == pytest.approx(7.48, abs=0.01)  # Table 3.1's helix convection, K/W
    gaps = shell(0.254e-3, 0.33e-3, 0.028) + shell(0.584e-3, 0.7e-3, 0.028)
    steel = shell(0.7e-3, 1.5e-3, 16.0)
    # split into sub-shells, the chain still adds up to its shells and gaps in series
    assert network.resistances.sum() == pytest.approx(gaps + ptfe + steel + steel_out, rel=1e-9)
    assert network.resistances[-1] > steel_out
    # J/K: the liner and helix capacities config/physics/ch5_straight_40n.yaml calibrated, together
    assert network.capacities.sum() == pytest.approx(17.0, rel=0.1)


@pytest.fixture(scope="module")
def runs():
    return simulate(RIG, [PULSE], 30.0, sample_s=0.002), simulate(WireRig(), [PULSE], 30.0)


def test_the_heat_put_in_is_in_the_wire_the_shells_or_the_air(runs):
    run, _ = runs
    network = RIG.network()
    assert network is not None
    volume = RIG.section_m2 * RIG.length_m
    wire = RIG.density_kg_m3 * volume * RIG.heat_capacity_j_kg_k
    dt = np.diff(run.time_s)
    electrical = np.concatenate([[0.0], np.cumsum(run.current_a[:-1] * run.voltage_v[:-1] * dt)])
    outflow = (run.sheath_node_c[:, -1] - RIG.ambient_c) / network.resistances[-1]
    to_air = np.concatenate([[0.0], np.cumsum(0.5 * (outflow[1:] + outflow[:-1]) * dt)])
    stored = (
        wire * (run.temperature_c - run.temperature_c[0])
        + (run.sheath_node_c - RIG.ambient_c) @ network.capacities
    )
    released = (
        RIG.density_kg_m3
        * volume
        * RIG.latent_heat_j_kg
        * (run.martensite_fraction - run.martensite_fraction[0])
    )
    assert np.max(np.abs(electrical - (stored + to_air - released))) < 0.002 * electrical[-1]


def test_the_sheath_takes_heat_the_bare_wire_keeps(runs):
    sheathed, bare = runs
    assert sheathed.temperature_c.max() < bare.temperature_c.max() - 20.0
    assert sheathed.contraction_m.max() < 0.5 * bare.contraction_m.max()
    # the liner warms first and most; the helix's outside last
    peaks = sheathed.sheath_node_c.max(axis=0)
    assert np.all(np.diff(peaks) < 0.0) and peaks[0] > RIG.ambient_c + 20.0
