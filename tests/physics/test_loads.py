"""Loads (eqs. 4.32-4.35), pulley, friction and the sign convention."""

import numpy as np
import pytest

from hems_ros.physics import ActuationUnit, scenarios, simulate
from hems_ros.physics.params import load_params

DT = 1e-3


def test_contraction_is_positive_displacement():
    p = load_params("table41")
    res = simulate(p, DT, current=scenarios.pulse_train(1.8, 2.0, DT))
    x, xi = res.slider_position_m[0], res.martensite_fraction[0]
    assert xi[-1] < 0.5 and x[-1] > 10e-3  # austenite: the wire shortened, x > 0
    assert res.strain[0, -1] == pytest.approx(x[-1] / 0.9)
    assert res.wire_force_n[0, -1] > 12.0  # the spring is stretched by the contraction


def test_massless_spring_force_balance_is_algebraic():
    p = load_params("table41").replace({"load.damping_n_s_per_m": 0.0})
    res = simulate(p, DT, current=scenarios.pulse_train(1.8, 6.0, DT))
    expected = p.load.pretension_n + p.load.stiffness_n_per_m * res.slider_position_m[0]
    assert np.max(np.abs(res.wire_force_n[0] - expected)) < 1e-6


def test_hanging_mass_rests_in_balance_and_stays_stable():
    for mass in (0.05, 3.0, 10.0):
        p = load_params("table41").replace(
            {
                "load.kind": "hanging_mass",
                "load.mass_kg": mass,
                "load.pretension_n": 0.0,
                "load.stiffness_n_per_m": 0.0,
            }
        )
        res = simulate(p, DT, current=scenarios.pulse_train(2.0, 20.0, DT))
        v, fw = res.slider_velocity_m_s[0], res.wire_force_n[0]
        assert np.all(np.isfinite(res.slider_position_m))
        assert fw[0] == pytest.approx(mass * 9.81, rel=0.01)
        # the wire force drives the mass: F = m (g + dv/dt) + b v at every step (eq. 4.33)
        accel = np.diff(v) / DT
        residual = fw[1:] - (mass * (9.81 + accel) + p.load.damping_n_s_per_m * v[1:])
        assert np.max(np.abs(residual)) < 1e-6 * max(fw.max(), 1.0)
        # no growing oscillation: the last seconds are quiet
        assert np.max(np.abs(v[-3000:])) < 2e-3


def test_pulley_doubles_displacement_and_halves_force():
    p = load_params("ch6_hems_index").replace(
        {"capstan.enabled": False, "glove_friction.enabled": False, "load.damping_n_s_per_m": 0.0}
    )
    res = simulate(p, DT, duty=np.where(np.arange(3000) < 2000, 100.0, 0.0))
    assert np.allclose(res.tendon_position_m[0], 2 * res.slider_position_m[0])
    assert np.allclose(res.tendon_force_n[0], res.wire_force_n[0] / 2, atol=1e-6)
    assert res.tendon_position_m[0].max() > 20e-3


def test_capstan_and_glove_friction_act_against_motion():
    p = load_params("ch6_hems_index").replace({"load.damping_n_s_per_m": 0.0})
    c, fc = np.exp(-0.04 * np.pi), p.glove_friction.force_n
    res = simulate(p, DT, duty=np.where(np.arange(12000) < 2000, 100.0, 0.0))
    v, fw, ft = res.slider_velocity_m_s[0], res.wire_force_n[0], res.tendon_force_n[0]
    pulling, paying_out, resting = v > 1e-5, v < -1e-5, v == 0.0
    assert pulling.any() and paying_out.any() and resting.any()
    assert np.allclose(ft[pulling], c * fw[pulling] / 2 - fc, atol=1e-6)
    assert np.allclose(ft[paying_out], fw[paying_out] / (2 * c) + fc, atol=1e-6)
    # stiction: at rest the tendon force lies inside the friction band
    band_lo, band_hi = c * fw[resting] / 2 - fc, fw[resting] / (2 * c) + fc
    assert np.all((ft[resting] >= band_lo - 1e-6) & (ft[resting] <= band_hi + 1e-6))


def test_glove_friction_gives_force_displacement_hysteresis():
    p = load_params("ch6_hems_index")
    unit = ActuationUnit(p)
    pts = [unit.step(current=4.0 if k % 6000 < 1000 else 0.0) for k in range(18000)]
    x = np.array([r.slider_position_m for r in pts])
    f = np.array([r.wire_force_n for r in pts])
    v = np.array([r.slider_velocity_m_s for r in pts])
    mid = (x > 0.4 * x.max()) & (x < 0.6 * x.max())
    up, down = f[mid & (v > 0)], f[mid & (v < 0)]
    assert up.size and down.size and up.mean() - down.mean() > 2 * p.glove_friction.force_n
