"""Closed-form facts of the dissertation: h(T), Churchill-Chu, Table 3.1 resistances,
capstan, resistance."""

import math

import pytest

from hems_ros.physics import electrical, heat, sheath
from hems_ros.physics.friction import capstan_ratio
from hems_ros.physics.params import UnitParams, load_params


def test_h_at_22_degc():
    p = UnitParams().thermal
    assert heat.convection_coefficient(22.0, p.h0_w_m2_c, p.h2_w_m2_c3) == pytest.approx(
        42.51, abs=0.005
    )


def test_churchill_chu_at_appendix_conditions():
    nu, h = heat.appendix_free_convection()
    assert nu == pytest.approx(0.840, rel=0.01)
    assert h == pytest.approx(42.5, rel=0.01)
    assert heat.churchill_chu_nusselt(1.0013, 0.591) == pytest.approx(0.8403, abs=5e-4)
    # from geometry: the appendix Gr corresponds to nu_air = 1.322e-5 m2/s with beta = 1/T_air
    gr = heat.grashof_number(0.508e-3, 90.0, 22.0, 1.322e-5)
    assert gr == pytest.approx(1.6947, rel=0.01)
    with pytest.raises(ValueError):
        heat.churchill_chu_nusselt(-1.0, 0.7)


def test_sheath_resistances_table_31():
    r = sheath.sheath_resistances(UnitParams().sheath, 0.9)
    assert r.ptfe_conduction == pytest.approx(0.4038, rel=2e-3)
    assert r.steel_conduction == pytest.approx(4.73e-3, rel=1e-2)
    assert r.outer_convection == pytest.approx(7.48, rel=2e-3)
    assert r.sheathed_total == pytest.approx(7.89, rel=2e-3)


def test_capstan_ratio():
    assert capstan_ratio(0.04, math.pi) == pytest.approx(0.88, abs=0.005)


def test_cold_resistance_near_measured():
    p = load_params("table41")
    e = p.electrical
    sig = 12.0 / p.wire.cross_section_m2
    rho = electrical.mixture_resistivity(
        1.0,
        electrical.phase_resistivity(
            e.rho0_martensite_ohm_m,
            e.t0_martensite_c,
            e.drho_dt_martensite_ohm_m_per_c,
            e.drho_dsigma_martensite_ohm_m_per_pa,
            22.0,
            sig,
        ),
        0.0,
    )
    r = electrical.wire_resistance(rho, p.wire.length_m, 1.0 / p.wire.cross_section_m2)
    assert 4.0 < r < 4.5  # chapter 3: mean 4.17 ohm over a pulse


def test_pwm_stage_limits_current_and_averages():
    i, pw = electrical.pwm_stage(100.0, 4.0, 20.0, 4.0)
    assert (i, pw) == (4.0, 64.0)  # 20 V / 4 ohm = 5 A, limited to 4 A
    i, pw = electrical.pwm_stage(50.0, 8.0, 20.0, 4.0)
    assert i == pytest.approx(1.25) and pw == pytest.approx(0.5 * 2.5**2 * 8.0)
    i, pw = electrical.voltage_source(12.0, 4.0)
    assert (i, pw) == (3.0, 36.0)
