"""Phase kinetics (eqs. 4.17-4.25) and the dissertation's qualitative figures (Table 4.1)."""

import numpy as np
import pytest

from hems_ros.physics import kinetics, simulate
from hems_ros.physics.params import load_params
from hems_ros.physics.validation import mass_loops, six_pulses

DT = 1e-3


def test_branches_and_stress_shift():
    zp, dzp = kinetics.heating_branch(93.0, 88.0, 98.0)
    zm, dzm = kinetics.cooling_branch(67.0, 72.0, 62.0)
    assert zp == pytest.approx(0.5) and zm == pytest.approx(0.5)
    assert dzp == pytest.approx(-0.1) and dzm == pytest.approx(-0.1)  # -sech^2(0) / 10 K
    ms, mf, a_s, a_f = kinetics.transformation_temperatures(6.89e7, 72, 62, 88, 98, 6.89e6, 6.89e6)
    assert (ms, mf, a_s, a_f) == pytest.approx((82, 72, 98, 108))


def test_slope_guard_outside_the_loop():
    # far below both branches z+ = z- = 1 exactly: 0/0 must not produce NaN
    s = kinetics.transformation_slope(-200.0, 1.0, True, 72, 62, 88, 98)
    assert s == 0.0
    # on the major heating branch the slope is the branch slope; on the cooling branch zero
    zp, dzp = kinetics.heating_branch(93.0, 88, 98)
    assert kinetics.transformation_slope(93.0, zp, True, 72, 62, 88, 98) == pytest.approx(dzp, rel=1e-6)
    zm, _ = kinetics.cooling_branch(93.0, 72, 62)
    assert kinetics.transformation_slope(93.0, zm, True, 72, 62, 88, 98) == pytest.approx(0.0, abs=1e-9)


def test_loops_move_right_with_load_and_5kg_is_incomplete():
    ml = mass_loops()
    onset = ml.heating_onset_c
    assert onset[0] + 5 < onset[1] and onset[1] + 5 < onset[2]
    assert ml.min_martensite[0] < 0.15          # 1 kg transforms (almost) completely
    assert ml.min_martensite[2] > 0.5            # 5 kg: the transformation no longer completes
    assert np.isnan(ml.heating_midpoint_c[2])


def test_latent_heat_plateau_on_cooling():
    ml = mass_loops()
    # apparent heat capacity = convective loss / |C dT/dt|: 1 without phase change
    assert all(r > 1.5 for r in ml.cooling_capacity_ratio)
    p = load_params("table41").replace({"thermal.latent_heat_j_kg": 0.0})
    no_latent = mass_loops(p)
    assert all(r < 1.1 for r in no_latent.cooling_capacity_ratio)


def test_six_pulses_nest_minor_loops():
    sp = six_pulses()
    xi_peak, xi_pause = sp.reversal_martensite, sp.pause_martensite
    # partial transformations: each pulse goes further, each pause recovers only part of it
    partial = [j for j in range(len(xi_pause)) if 0.02 < 1 - xi_peak[j] and xi_pause[j] < 0.99]
    assert len(partial) >= 3
    for j in partial:
        assert xi_peak[j] < xi_pause[j] < 1.0          # reversal inside the band: a minor loop
        assert xi_peak[j + 1] < xi_peak[j]              # the next loop reaches further: nested
    assert min(xi_peak) > 0.0 and max(xi_pause) <= 1.0


@pytest.mark.xfail(strict=True, reason="the printed Duhem/Likhachev law (eqs. 4.22-4.24) keeps no memory "
                   "of reversal points: re-heating from inside the band passes the previous reversal "
                   "temperature up to 0.045 lower in xi (docs/validation.md)")
def test_return_point_memory_within_002():
    sp = six_pulses()
    dev = [abs(d) for d in sp.return_deviation if np.isfinite(d)]
    assert max(dev) <= 0.02


def test_return_point_deviation_is_what_the_report_states():
    dev = [abs(d) for d in six_pulses().return_deviation if np.isfinite(d)]
    assert 0.02 < max(dev) < 0.06


def test_resistance_hysteresis_against_temperature():
    p = load_params("table41")
    n = int(10.0 / DT)
    res = simulate(p, DT, current=np.where(np.arange(n) < 1800, 4.0, 0.0))
    temp, r = res.wire_temperature_c[0], res.resistance_ohm[0]
    heat_mask = np.arange(n) < 1800
    grid = np.linspace(80.0, 100.0, 11)
    up = np.interp(grid, temp[heat_mask], r[heat_mask])
    cool_t, cool_r = temp[~heat_mask][::-1], r[~heat_mask][::-1]   # increasing temperature
    down = np.interp(grid, cool_t, cool_r)
    assert np.max(np.abs(up - down)) > 0.2   # ohm, same temperature, different phase mix
