"""Energy balance over a pulse: Joule = stored + convected + latent (+ to sheath), within 1 %.

The accumulators of the kernel are checked against an independent integration of the
recorded trajectories (trapezoidal convective loss from T(t), stored heat from T_end,
latent heat from xi_end), so a wrong sign or a missing term in the kernel fails here.
"""

import math

import numpy as np
import pytest

from hems_ros.physics import heat, scenarios, simulate
from hems_ros.physics.params import load_params
from hems_ros.physics.sheath import sheath_resistances

DT = 1e-3


def _trapezoid(y, dt, y0):
    y = np.concatenate([[y0], y])
    return float(np.sum(0.5 * (y[1:] + y[:-1])) * dt)


@pytest.mark.parametrize("sheathed, helix", [(False, False), (True, False), (True, True)])
def test_joule_equals_stored_convected_latent(sheathed, helix):
    p = load_params("table41").replace({"sheath.enabled": sheathed})
    if helix:  # two sheath nodes, as the calibrated sets have
        p = p.replace(
            {
                "sheath.heat_capacity_j_per_k": 0.5,
                "sheath.helix_heat_capacity_j_per_k": 16.5,
                "sheath.liner_helix_resistance_k_per_w": 2.0,
            }
        )
    # balance at the end of the pulse, where the latent term is largest
    res = simulate(p, DT, current=scenarios.pulse_train(1.8, 1.8, DT))
    t_amb = p.ambient_temperature_c
    temp, xi = res.wire_temperature_c[0], res.martensite_fraction[0]
    c_w = p.thermal.density_kg_m3 * p.wire.volume_m3 * p.thermal.specific_heat_j_kg_c
    lat = p.thermal.density_kg_m3 * p.wire.volume_m3 * p.thermal.latent_heat_j_kg
    joule = float(np.sum(res.electrical_power_w[0]) * DT)
    stored = c_w * (temp[-1] - t_amb)
    latent = lat * (1.0 - xi[-1])
    if sheathed:
        r = sheath_resistances(p.sheath, p.wire.length_m)
        lost = _trapezoid((temp - res.sheath_temperature_c[0]) / r.wire_to_sheath, DT, 0.0)
    else:
        q = heat.convection_loss(
            temp, t_amb, p.thermal.h0_w_m2_c, p.thermal.h2_w_m2_c3, p.wire.surface_area_m2
        )
        lost = _trapezoid(q, DT, 0.0)
    assert 1.0 - xi[-1] > 0.3, "the pulse must transform the wire for the latent term to matter"
    assert latent > 0.05 * joule
    assert stored + lost + latent == pytest.approx(joule, rel=0.01)
    # the kernel's own accumulators close exactly
    e = {k: res[k][0, -1] for k in res.channels() if k.startswith("energy_")}
    total = (
        e["energy_stored_j"]
        + e["energy_convected_j"]
        + e["energy_latent_j"]
        + e["energy_to_sheath_j"]
    )
    assert total == pytest.approx(e["energy_joule_j"], rel=1e-9)
    assert e["energy_joule_j"] == pytest.approx(joule, rel=1e-9)
    if sheathed:
        assert (
            e["energy_convected_j"] == 0.0
            and e["energy_to_sheath_j"] > (0.2 if helix else 0.3) * joule
        )
        assert e["energy_sheath_stored_j"] + e["energy_sheath_convected_j"] == pytest.approx(
            e["energy_to_sheath_j"], rel=1e-9
        )
    if helix:  # the helix stores heat from the first node and passes some of it to the air
        helix_t = res.sheath_helix_temperature_c[0]
        assert helix_t[-1] > t_amb + 0.5 and helix_t[-1] < res.sheath_temperature_c[0, -1]
        assert e["energy_sheath_convected_j"] > 0.0


def test_lossless_temperature_is_where_a_wire_without_losses_ends():
    # no convection, no sheath: every joule is stored or latent, so the bound is met exactly
    p = load_params("table41").replace(
        {"sheath.enabled": False, "thermal.h0_w_m2_c": 0.0, "thermal.h2_w_m2_c3": 0.0}
    )
    res = simulate(p, DT, current=scenarios.pulse_train(1.8, 1.8, DT))
    xi_end = res.martensite_fraction[0, -1]
    assert 1.0 - xi_end > 0.3
    mass = p.thermal.density_kg_m3 * p.wire.volume_m3
    bound = heat.lossless_temperature_c(
        res.energy_joule_j[0, -1],
        1.0 - xi_end,
        mass * p.thermal.specific_heat_j_kg_c,
        mass * p.thermal.latent_heat_j_kg,
        p.ambient_temperature_c,
    )
    assert res.wire_temperature_c[0, -1] == pytest.approx(bound, abs=0.05)
    # any loss leaves the wire cooler than the bound of its own energy and transformation
    lossy = simulate(load_params("table41"), DT, current=scenarios.pulse_train(1.8, 1.8, DT))
    xi_lossy = lossy.martensite_fraction[0, -1]
    assert (
        lossy.wire_temperature_c[0, -1]
        < heat.lossless_temperature_c(
            lossy.energy_joule_j[0, -1],
            1.0 - xi_lossy,
            mass * p.thermal.specific_heat_j_kg_c,
            mass * p.thermal.latent_heat_j_kg,
            p.ambient_temperature_c,
        )
        - 1.0
    )


def test_lossless_temperature_by_hand_and_bad_fraction():
    # 92.16 J (dissertation chapter 6, 1.6 s), 29 of 30 mm moved; Table 4.1 wire: rho V c_p
    # = 0.985 J/K, rho V dH = 28.46 J
    volume = math.pi / 4 * 0.508e-3**2 * 0.9
    c, latent = 6450 * volume * 837.4, 6450 * volume * 24183.52
    assert c == pytest.approx(0.985, abs=1e-3) and latent == pytest.approx(28.46, abs=0.01)
    assert heat.lossless_temperature_c(92.16, 29 / 30, c, latent, 22.0) == pytest.approx(
        87.6, abs=0.05
    )
    with pytest.raises(ValueError, match="transformed_fraction"):
        heat.lossless_temperature_c(92.16, 1.2, c, latent, 22.0)
