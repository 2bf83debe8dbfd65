"""Phase kinetics (eqs. 4.17-4.25) and the dissertation's qualitative figures (Table 4.1)."""

import math

import numpy as np
import pytest

from hems_ros.physics import kinetics, simulate
from hems_ros.physics.params import load_params
from hems_ros.physics.validation import mass_loops, six_pulses

DT = 1e-3
TABLE41_TEMPERATURES = (72.0, 62.0, 88.0, 98.0)  # Ms0, Mf0, As0, Af0
BAND = kinetics.band(*TABLE41_TEMPERATURES)  # Mf0, 1/(Ms0 - Mf0), As0, 1/(Af0 - As0)


def test_branches_and_stress_shift():
    zp, dzp = kinetics.heating_branch(93.0, 88.0, 0.1)
    zm, dzm = kinetics.cooling_branch(67.0, 62.0, 0.1)
    assert zp == pytest.approx(0.5) and zm == pytest.approx(0.5)
    assert dzp == pytest.approx(-0.1) and dzm == pytest.approx(-0.1)  # -sech^2(0) / 10 K
    # eq. 4.25: 68.9 MPa shifts every temperature by 10 K; the branch at the effective
    # temperature T - sigma/C with zero-stress temperatures is the same number
    u_m, u_a = kinetics.effective_temperatures(103.0, 6.89e7, 1 / 6.89e6, 1 / 6.89e6)
    assert (u_m, u_a) == pytest.approx((93.0, 93.0))
    assert kinetics.heating_branch(u_a, 88.0, 0.1)[0] == pytest.approx(
        kinetics.heating_branch(103.0, 98.0, 0.1)[0]
    )
    assert kinetics.cooling_branch(u_m, 62.0, 0.1)[0] == pytest.approx(
        kinetics.cooling_branch(103.0, 72.0, 0.1)[0]
    )


def test_heating_branch_temperature_inverts_the_branch():
    # half transformed at the middle of the band; 80 % at As + 10 K (1/2 + atanh(0.6)/2)
    # = 96.47 degC
    assert kinetics.heating_branch_temperature(0.5, 88.0, 98.0) == pytest.approx(93.0)
    assert kinetics.heating_branch_temperature(0.8, 88.0, 98.0) == pytest.approx(96.466, abs=1e-3)
    for f in (0.01, 0.3, 0.97):
        t = kinetics.heating_branch_temperature(f, 95.4, 105.4)
        assert 1.0 - kinetics.heating_branch(t, 95.4, 0.1)[0] == pytest.approx(f, abs=1e-12)
    with pytest.raises(ValueError, match="transformed_fraction"):
        kinetics.heating_branch_temperature(1.0, 88.0, 98.0)


def test_slope_guard_outside_the_loop():
    # far below both branches z+ = z- = 1 exactly: 0/0 must not produce NaN
    s = kinetics.transformation_slope(-200.0, -200.0, 1.0, True, *BAND)
    assert math.isfinite(s) and abs(s) < 1e-40
    # the branches far outside their bands: exactly 0 / 1, slopes finite
    for u in (-1e4, 1e4):
        for z, dz in (kinetics.heating_branch(u, 88, 0.1), kinetics.cooling_branch(u, 62, 0.1)):
            assert z in (0.0, 1.0) and math.isfinite(dz)
    # on the major heating branch the slope is the branch slope; on the cooling branch zero
    zp, dzp = kinetics.heating_branch(93.0, 88, 0.1)
    assert kinetics.transformation_slope(93.0, 93.0, zp, True, *BAND) == pytest.approx(
        dzp, rel=1e-6
    )
    zm, _ = kinetics.cooling_branch(93.0, 62, 0.1)
    assert kinetics.transformation_slope(93.0, 93.0, zm, True, *BAND) == pytest.approx(
        0.0, abs=1e-9
    )


def _follow(u_path):
    """xi along a prescribed effective-temperature path (constant stress), kernel protocol."""
    memory = np.zeros(kinetics.POINT_SIZE * kinetics.MEMORY_DEPTH)
    n, direction, xi, xis = 0, 0, 1.0, [1.0]
    for u_old, u in zip(u_path[:-1], u_path[1:]):
        heating = u > u_old
        if direction and direction != (1 if heating else -1):
            n = kinetics.push_reversal(memory, n, u_old, u_old, xi, *BAND)
        direction = 1 if heating else -1
        slope0 = kinetics.transformation_slope(u_old, u_old, xi, heating, *BAND)
        xi, _, closed = kinetics.memory_branch(
            u, u, heating, memory, n, xi, u_old, u_old, slope0, *BAND
        )
        n -= 2 * closed
        xis.append(xi)
    return np.array(xis), n


def test_memory_closes_nested_minor_loops_exactly():
    legs = [(22.0, 93.0), (93.0, 70.0), (70.0, 90.0), (90.0, 76.0), (76.0, 110.0)]
    u = np.concatenate([np.linspace(a, b, 400, endpoint=False) for a, b in legs] + [[110.0]])
    xi, n = _follow(u)
    at = [int(np.flatnonzero(np.isclose(u, v))[0]) for v in (93.0, 90.0)]
    outer = xi[at[0]]  # first reversal, on the printed heating branch
    inner = xi[at[1]]  # second reversal, inside the first loop
    assert 0.2 < outer < 0.8 and outer < inner
    last = np.arange(u.size) >= 1600  # final heating from 76 degC
    for target, value in ((90.0, inner), (93.0, outer)):
        k = int(np.flatnonzero(last & (u >= target))[0])
        assert xi[k] == pytest.approx(value, abs=2e-3)  # one 0.085 K sample past the point
    assert n == 0  # both loops wiped out
    # continuing past the outer reversal follows the uninterrupted heating branch
    straight, _ = _follow(np.concatenate([np.linspace(22.0, 93.0, 400, endpoint=False), u[1600:]]))
    assert xi[-1] == pytest.approx(straight[-1], abs=1e-3)


def test_memory_depth_forgets_the_innermost_loop():
    memory = np.zeros(kinetics.POINT_SIZE * kinetics.MEMORY_DEPTH)
    n = 0
    for k in range(kinetics.MEMORY_DEPTH):
        n = kinetics.push_reversal(memory, n, float(k), float(k), 0.5, *BAND)
    assert n == kinetics.MEMORY_DEPTH
    n = kinetics.push_reversal(memory, n, 99.0, 99.0, 0.4, *BAND)
    assert n == kinetics.MEMORY_DEPTH - 1
    top = kinetics.POINT_SIZE * (n - 1)
    assert list(memory[top : top + 3]) == [99.0, 99.0, 0.4]
    assert memory[top + 3] == kinetics.heating_branch(99.0, 88.0, 0.1)[0]
    assert memory[top - kinetics.POINT_SIZE] == kinetics.MEMORY_DEPTH - 3


def test_loops_move_right_with_load_and_5kg_is_incomplete():
    ml = mass_loops()
    onset = ml.heating_onset_c
    assert onset[0] + 5 < onset[1] and onset[1] + 5 < onset[2]
    assert ml.min_martensite[0] < 0.15  # 1 kg transforms (almost) completely
    assert ml.min_martensite[2] > 0.5  # 5 kg: the transformation no longer completes
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
        assert xi_peak[j] < xi_pause[j] < 1.0  # reversal inside the band: a minor loop
        assert xi_peak[j + 1] < xi_peak[j]  # the next loop reaches further: nested
    assert min(xi_peak) > 0.0 and max(xi_pause) <= 1.0


def test_return_point_memory_within_002():
    # 12 N spring: the stress changes along the loop, the memory is kept in T - sigma/C
    dev = six_pulses().return_deviation
    assert len(dev) == 5 and all(np.isfinite(dev))
    for j, d in enumerate(dev):
        assert abs(d) < 0.02, (j, d)


def test_resistance_hysteresis_against_temperature():
    p = load_params("table41")
    n = int(10.0 / DT)
    res = simulate(p, DT, current=np.where(np.arange(n) < 1800, 4.0, 0.0))
    temp, r = res.wire_temperature_c[0], res.resistance_ohm[0]
    heat_mask = np.arange(n) < 1800
    grid = np.linspace(80.0, 100.0, 11)
    up = np.interp(grid, temp[heat_mask], r[heat_mask])
    cool_t, cool_r = temp[~heat_mask][::-1], r[~heat_mask][::-1]  # increasing temperature
    down = np.interp(grid, cool_t, cool_r)
    assert np.max(np.abs(up - down)) > 0.2  # ohm, same temperature, different phase mix


def test_vectorisable_exp_is_within_one_ulp_of_libm():
    # kinetics' own exp replaces libm's inside the batch's vector loops (see its comment)
    rng = np.random.default_rng(1)
    xs = np.concatenate(
        [-rng.uniform(0.0, 708.0, 20000), -rng.uniform(0.0, 1.0, 20000), [0.0, -1e-300, -708.0]]
    )
    got = np.array([kinetics.exp_nonpositive(x) for x in xs])
    ref = np.array([math.exp(x) for x in xs])
    assert np.max(np.abs(got - ref) / np.spacing(ref)) <= 1.0
    assert np.mean(got == ref) > 0.85
    assert kinetics.exp_nonpositive(-709.0) == 0.0 and kinetics.exp_nonpositive(-1e308) == 0.0
