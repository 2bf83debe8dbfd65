"""Diagnosis extensions of the physics: supply sag, stiffening spring, warm start, sensor errors,
temperature drive and the batch's start temperature. Each is off at its default."""

import math

import numpy as np
import pytest

from hems_ros.control import make_controller
from hems_ros.experiments.lockstep import simulate_loop
from hems_ros.physics import ActuationUnit, electrical, rows, sensors, simulate
from hems_ros.physics.batch import CHANNELS
from hems_ros.physics.params import ParamError, Start, UnitParams, load_params, save_params

DT = 1e-3


def _pulses(n_steps, level):
    """Pulses of rising length every 2 s (reversals, minor loops, loop closures)."""
    t = np.arange(n_steps) * DT
    return np.where((t % 2.0) < 0.3 + 0.1 * np.floor(t / 2.0), level, 0.0)


def _step_all(unit, kind, values):
    """Every channel of the batch after each step of the stepping API, by name."""
    records = []
    for value in values:
        unit.advance(**{kind: float(value)})
        state = unit.state
        out = dict(zip(rows.OUT_NAMES, unit._out.tolist()))
        records.append([state[c] if c in state else out[c] for c in CHANNELS])
    return dict(zip(CHANNELS, np.array(records).T))


# ------------------------------------------------------------------ defaults change nothing
def test_defaults_are_off():
    p = UnitParams()
    assert p.drive.source_resistance_ohm == 0.0 and p.load.cubic_stiffness_n_per_m3 == 0.0
    assert p.start.temperature_offset_c == 0.0 and p.encoder.gain == 1.0
    assert p.force_sensor.offset_n == 0.0 and p.force_sensor.drift_n_per_s == 0.0


@pytest.mark.parametrize(
    "name, kind, level, expected",
    [
        # the last record (t = 9 s) of these runs by the code before the extensions (commit
        # 1806f8d): slider position m, wire force N, tendon force N, martensite fraction
        (
            "table41",
            "current",
            4.0,
            (0.019424383639433183, 29.46775037975571, 29.46775037975571, 0.3795301542257875),
        ),
        (
            "ch6_hems_index",
            "duty",
            80.0,
            (0.003218701441474955, 8.346385987851134, 2.7209891228903897, 0.8820876901893259),
        ),
    ],
)
def test_defaults_reproduce_the_trajectories_before_the_extensions(name, kind, level, expected):
    # bit for bit on the machine that recorded them (checked over every named set and drive);
    # 1e-9 leaves room for another CPU's multiply-add contraction
    res = simulate(load_params(name), DT, record_every=3, **{kind: _pulses(9000, level)})
    names = ("slider_position_m", "wire_force_n", "tendon_force_n", "martensite_fraction")
    got = [res[c][0, -1] for c in names]
    assert got == pytest.approx(expected, rel=1e-9)


# ------------------------------------------------------------------ 1. supply sag
def test_pwm_stage_with_source_resistance_closed_form():
    # 20 V over 4 + 2 ohm: 3.33 A on, below the 4 A limit; the wire gets I^2 R, not I^2 (R + R_s)
    i_on = 20.0 / 6.0
    assert electrical.pwm_stage(100.0, 4.0, 20.0, 4.0, 2.0) == pytest.approx(
        (i_on, i_on**2 * 4.0), rel=1e-15
    )
    quarter = (0.25 * i_on, 0.25 * i_on**2 * 4.0)
    assert electrical.pwm_stage(25.0, 4.0, 20.0, 4.0, 2.0) == pytest.approx(quarter, rel=1e-15)
    assert electrical.pwm_stage(100.0, 4.0, 20.0, 4.0, 0.5) == (4.0, 64.0)  # 4.44 A: limited


def test_supply_sag_sets_the_mean_current_from_the_reported_resistance():
    p = load_params("table41").replace({"drive.source_resistance_ohm": 2.0})
    duty = np.r_[np.full(2000, 100.0), np.full(2000, 50.0)]
    res = simulate(p, DT, duty=duty)
    r, i, pw = res.resistance_ohm[0], res.current_a[0], res.electrical_power_w[0]
    assert np.all(i[:2000] < 4.0) and r.min() > 3.5
    np.testing.assert_allclose(i, duty / 100.0 * 20.0 / (r + 2.0), rtol=1e-14)
    np.testing.assert_allclose(pw, i * i * r / (duty / 100.0), rtol=1e-14)  # d I_on^2 R
    ideal = simulate(load_params("table41"), DT, duty=np.full(2000, 100.0))
    assert np.all(ideal.current_a[0] == 4.0)  # 20 V / 4.35 ohm: the limit
    assert res.wire_temperature_c[0, 1999] < ideal.wire_temperature_c[0, -1] - 10.0


def test_supply_sag_leaves_the_current_and_voltage_drives_alone():
    base = load_params("table41")
    sag = base.replace({"drive.source_resistance_ohm": 3.0})
    for kind, level in (("current", 3.0), ("voltage", 12.0)):
        a = simulate(base, DT, **{kind: _pulses(4000, level)})
        b = simulate(sag, DT, **{kind: _pulses(4000, level)})
        for name in CHANNELS:
            assert np.array_equal(a[name], b[name]), (kind, name)


# ------------------------------------------------------------------ 2. stiffening spring
def test_cubic_spring_static_balance_at_rest():
    k3 = 5e5
    p = load_params("table41").replace({"load.cubic_stiffness_n_per_m3": k3})
    linear = simulate(load_params("table41"), DT, current=np.full(60000, 2.4))
    res = simulate(p, DT, current=np.full(60000, 2.4))
    x, fw, ft, v = (
        res[c][0, -1]
        for c in ("slider_position_m", "wire_force_n", "tendon_force_n", "slider_velocity_m_s")
    )
    assert abs(v) < 1e-9 and 0.015 < x < linear.slider_position_m[0, -1] - 1e-3
    assert fw == pytest.approx(12.0 + 900.0 * x + k3 * x**3, abs=1e-6)  # k3 x^3 = 3.4 N of 33 N
    assert ft == pytest.approx(fw, abs=1e-6)


def test_cubic_spring_is_linearised_about_the_start_of_the_step():
    # massless spring: the wire force is the load law with k3 x^3 taken as k3 (x0^3 + 3 x0^2 dx),
    # so it misses the exact law by -k3 (3 x0 dx^2 + dx^3), at every step; the load force
    # reported is the exact law at the end of the step
    k3 = 5e5
    p = load_params("table41").replace({"load.cubic_stiffness_n_per_m3": k3})
    res = simulate(p, DT, current=_pulses(8000, 4.0))
    x, fw, v = res.slider_position_m[0], res.wire_force_n[0], res.slider_velocity_m_s[0]
    x0 = np.r_[0.0, x[:-1]]
    dx = x - x0
    law = 12.0 + 900.0 * x + k3 * x**3 + 65.0 * v
    np.testing.assert_allclose(fw - law, -k3 * (3.0 * x0 * dx**2 + dx**3), rtol=0, atol=1e-10)
    np.testing.assert_allclose(res.tendon_force_n[0], law, rtol=0, atol=1e-10)  # the exact law
    assert x.max() > 0.009 and np.max(k3 * 3.0 * x0 * dx**2) > 1e-8


def test_cubic_spring_acts_in_load_coordinates_behind_the_pulley():
    # n = 2: F_L = F_0 + k x_L + k3 x_L^3 + b x_L' with x_L = 2 x, and the wire pulls 2 F_L (with
    # the cubic term linearised about the step's start, as above)
    k3 = 2e5
    p = load_params("ch6_hems_index").replace(
        {
            "load.cubic_stiffness_n_per_m3": k3,
            "capstan.enabled": False,
            "glove_friction.enabled": False,
        }
    )
    res = simulate(p, DT, duty=np.where(np.arange(6000) < 2500, 100.0, 0.0))
    x, fw, ft, v = (
        res[c][0]
        for c in ("slider_position_m", "wire_force_n", "tendon_force_n", "slider_velocity_m_s")
    )
    x_l, x_l0 = 2.0 * x, 2.0 * np.r_[0.0, x[:-1]]
    dx_l = x_l - x_l0
    law = 2.0 + 112.0 * x_l + k3 * x_l**3 + 65.0 * 2.0 * v
    np.testing.assert_allclose(ft, law, rtol=0, atol=1e-10)
    np.testing.assert_allclose(
        fw / 2.0 - law, -k3 * (3.0 * x_l0 * dx_l**2 + dx_l**3), rtol=0, atol=1e-10
    )
    assert x_l.max() > 0.03 and k3 * x_l.max() ** 3 > 5.0


# ------------------------------------------------------------------ 3. warm start
def test_start_group_round_trips_and_older_files_load(tmp_path):
    p = load_params("table41").replace({"start.temperature_offset_c": 18.5})
    assert p.start == Start(temperature_offset_c=18.5)
    assert p.to_dict()["start"] == {"temperature_offset_c": 18.5}
    assert save_params(p, tmp_path / "warm.yaml") and load_params(tmp_path / "warm.yaml") == p
    older = {k: v for k, v in p.to_dict().items() if k != "start"}
    assert UnitParams.from_dict(older).start.temperature_offset_c == 0.0
    with pytest.raises(ParamError, match=r"start.temperature_offset_c = -1.0: must be >= 0"):
        p.replace({"start.temperature_offset_c": -1.0})


def test_warm_start_sets_wire_and_sheath_and_the_explicit_start_wins():
    p = load_params("sheathed_calibrated").replace(
        {
            "start.temperature_offset_c": 30.0,
            "sheath.helix_heat_capacity_j_per_k": 16.0,
            "sheath.liner_helix_resistance_k_per_w": 1.0,
        }
    )
    s = rows.initial_state(p)
    start = p.ambient_temperature_c + 30.0
    assert (s[rows.S_T], s[rows.S_TS], s[rows.S_TH]) == (start, start, start)
    assert rows.initial_state(p, 40.0)[rows.S_T] == 40.0
    assert ActuationUnit(p).state["sheath_helix_temperature_c"] == start
    with pytest.raises(ValueError, match="below As0 = 88 degC"):
        rows.initial_state(
            p.replace({"start.temperature_offset_c": 88.0 - p.ambient_temperature_c})
        )


def test_warm_wire_first_step_loses_its_convection_closed_form():
    # bare wire at 52 degC, no current, martensite far below As: C dT = -h(T) A (T - T_amb) dt
    p = load_params("table41").replace({"start.temperature_offset_c": 30.0})
    r = ActuationUnit(p, dt=DT).step(current=0.0)
    t0, th = 52.0, p.thermal
    loss = (th.h0_w_m2_c + th.h2_w_m2_c3 * t0**2) * p.wire.surface_area_m2 * (t0 - 22.0)
    assert r.martensite_fraction == 1.0
    assert r.wire_temperature_c == pytest.approx(
        t0 - loss * DT / p.wire_heat_capacity_j_per_k, rel=1e-14
    )
    assert loss == pytest.approx(2.79, abs=0.01)


# ------------------------------------------------------------------ 4. sensor errors
def test_sensor_error_functions():
    assert sensors.encoder_counts(0.010, 1e-6, 1.02) == 10200
    assert sensors.encoder_counts(0.010, 1e-6) == 10000
    np.testing.assert_array_equal(
        sensors.encoder_counts_array([0.010, -0.002], 1e-6, 1.02), [10200, -2040]
    )
    # 10 N + 0.5 N + 0.02 N/s * 30 s + 0.004 N noise, to 0.01 N
    assert sensors.force_reading(10.0, 0.004, 50.0, 0.01, 0.5, 0.02, 30.0) == (
        pytest.approx(11.1),
        False,
    )
    assert sensors.force_reading(10.0, 0.0, 50.0, 0.01, -12.0) == (0.0, True)
    reading, saturated = sensors.force_reading_array(
        np.array([[10.0, 10.0]]), 0.004, 50.0, 0.01, np.array([[0.5]]), 0.02, np.array([0.0, 30.0])
    )
    np.testing.assert_allclose(reading, [[10.5, 11.1]])
    assert not saturated.any()


def test_sensor_errors_in_both_apis():
    p = load_params("ch6_hems_index").replace(
        {
            "encoder.gain": 1.03,
            "force_sensor.offset_n": -0.7,
            "force_sensor.drift_n_per_s": 0.05,
            "force_sensor.noise_std_n": 0.0,
        }
    )
    duty = np.where(np.arange(6000) < 2500, 100.0, 0.0)
    unit = ActuationUnit(p)
    steps = [unit.step(duty=d) for d in duty]
    res = simulate(p, DT, duty=duty)
    counts = np.array([s.encoder_counts for s in steps])
    x = np.array([s.slider_position_m for s in steps])
    t = np.array([s.time_s for s in steps])
    np.testing.assert_array_equal(counts, np.rint(1.03 * x / 1e-6))
    f = np.array([s.wire_force_n for s in steps]) - 0.7 + 0.05 * t
    np.testing.assert_allclose(
        [s.force_reading_n for s in steps], np.round(f / 0.01) * 0.01, atol=1e-12
    )
    assert np.array_equal(res.time, t) and x.max() > 0.01
    assert np.array_equal(res.encoder_counts[0], counts)
    assert np.array_equal(res.encoder_position_m[0], counts * 1e-6)
    assert np.array_equal(res.force_reading_n[0], [s.force_reading_n for s in steps])
    noisy = p.replace({"force_sensor.noise_std_n": 0.3})
    unit = ActuationUnit(noisy)
    readings = [unit.step(duty=d).force_reading_n for d in duty[:3000]]
    assert np.array_equal(
        simulate(noisy, DT, duty=duty[:3000], record_every=7).force_reading_n[0], readings[6::7]
    )


def _stepping_loop(reference, mode, params):
    """The lockstep loop on the stepping API: controller every 10 ms, plant every 1 ms."""
    unit = ActuationUnit(params, dt=DT)
    c = make_controller("bpid", mode)
    fs = params.force_sensor
    y = (
        0.0
        if mode == "position"
        else sensors.force_reading(
            params.load.pulley_ratio * params.load.static_force_n(),
            0.0,
            fs.range_max_n,
            fs.resolution_n,
            fs.offset_n,
            fs.drift_n_per_s,
            0.0,
        )[0]
    )
    out = []
    for r in reference:
        u = c.update(r, y)
        out.append((y, u))
        unit.advance(duty=u, steps=10)
        step = unit.result()
        y = step.encoder_position_m if mode == "position" else step.force_reading_n
    return np.array(out)


@pytest.mark.parametrize("mode, rest, level", [("position", 0.0, 0.010), ("force", 4.0, 8.0)])
def test_lockstep_reads_the_sensor_errors_as_the_stepping_api(mode, rest, level):
    p = load_params("ch6_hems_index").replace(
        {"encoder.gain": 1.05, "force_sensor.offset_n": 0.8, "force_sensor.drift_n_per_s": 0.1}
    )
    ref = np.r_[np.full(50, rest), np.full(350, level)]
    y, u, pos, force, _, fault = simulate_loop(ref, "bpid", mode, p)
    expected = _stepping_loop(ref, mode, p)
    assert fault is None
    np.testing.assert_allclose(y, expected[:, 0], atol=1e-9)
    np.testing.assert_allclose(u, expected[:, 1], atol=1e-9)
    t = np.arange(ref.size) * 0.01
    if mode == "position":  # the loop regulates the scaled reading: the slider stops short of it
        assert np.all(np.abs(y - 1.05 * pos) <= 0.5e-6 + 1e-12) and pos[-1] < 0.0096
    else:
        assert np.all(np.abs(y - (force + 0.8 + 0.1 * t)) < 0.2)  # noise 0.03 N, 0.01 N steps
        # the loop regulates the reading: the true force stops short by offset + drift t
        assert np.mean(force[-50:] + 0.8 + 0.1 * t[-50:]) == pytest.approx(level, abs=0.1)
        assert force[-1] < level - 1.0


# ------------------------------------------------------------------ 5. temperature drive
def _dead_weight(stress_pa):
    """Bare wire under a hanging mass giving ``stress_pa``, no spring, no damper:
    constant stress."""
    p = UnitParams()
    mass = stress_pa * p.wire.cross_section_m2 / p.load.gravity_m_s2
    return p.replace(
        {
            "load.kind": "hanging_mass",
            "load.mass_kg": mass,
            "load.stiffness_n_per_m": 0.0,
            "load.pretension_n": 0.0,
            "load.damping_n_s_per_m": 0.0,
        }
    )


def _crossing(temperature, xi):
    """Temperature where xi first passes 0.5, linear between the two samples around it."""
    k = int(np.argmax(np.diff(np.sign(xi - 0.5)) != 0))
    return temperature[k] + (0.5 - xi[k]) * (temperature[k + 1] - temperature[k]) / (
        xi[k + 1] - xi[k]
    )


def test_static_force_steps_the_dead_weight_between_records():
    # a cold (martensite) wire held at 22 degC; the frame's stress goes 20 -> 30 MPa after 1 s
    sigma, dt, every = 20e6, 1e-2, 10
    p = _dead_weight(sigma)
    held = np.full(200, 22.0)
    weight = p.load.static_force_n()
    res = simulate(
        p,
        dt,
        temperature=held,
        record_every=every,
        static_force_n=np.repeat([1.0, 1.5], 100) * weight,
    )
    plain = simulate(p, dt, temperature=held, record_every=every)
    x, stress = res.slider_position_m[0], res.stress_pa[0]
    assert np.array_equal(x[:10], plain.slider_position_m[0][:10])
    assert stress[9] == pytest.approx(sigma, rel=1e-6)
    assert stress[-1] == pytest.approx(1.5 * sigma, rel=1e-6)
    # the wire stretches elastically: the slider goes out by L dsigma / E_M
    stretch = p.wire.length_m * 0.5 * sigma / p.constitutive.e_martensite_pa
    assert x[9] - x[-1] == pytest.approx(stretch, rel=1e-3)
    with pytest.raises(ValueError, match="inside a record of 10 steps"):
        simulate(
            p,
            dt,
            temperature=held,
            record_every=every,
            static_force_n=np.repeat([1.0, 1.5], [95, 105]) * weight,
        )
    with pytest.raises(ValueError, match=r"static_force_n\[0, 3\] = nan"):
        simulate(p, dt, temperature=held, static_force_n=np.r_[np.ones(3), np.full(197, np.nan)])


def test_temperature_drive_thermal_cycle_at_constant_stress():
    # 1 degC/s from 22 to 130 degC and back; 20 MPa dead weight
    sigma, dt = 20e6, 1e-2
    p = _dead_weight(sigma)
    up = np.arange(22.0, 130.0, 0.01)
    ramp = np.r_[up, up[::-1]]
    res = simulate(p, dt, temperature=ramp)
    temp, xi, x, stress = (
        res[c][0]
        for c in ("wire_temperature_c", "martensite_fraction", "slider_position_m", "stress_pa")
    )
    n = up.size
    assert np.array_equal(temp, ramp)  # imposed at the end of every step
    assert np.all(res.current_a == 0.0) and np.all(res.electrical_power_w == 0.0)
    assert np.all(res.energy_latent_j == 0.0) and res.resistance_ohm.min() > 3.5
    assert np.max(np.abs(stress - sigma)) < 1e-3 * sigma
    assert xi[n - 1] < 1e-5 and xi[-1] > 1 - 1e-7
    # contraction: eps_L L of transformation plus L alpha(xi) dT (Theta/E as printed, eq. 4.30)
    co, length = p.constitutive, p.wire.length_m
    xi0 = np.r_[1.0, xi[: n - 1]]  # each step's alpha is that of its start
    alpha = co.alpha_martensite_per_c * xi0 + co.alpha_austenite_per_c * (1 - xi0) * (
        1 + co.poisson_ratio
    )
    thermal = length * np.sum(alpha * np.diff(np.r_[22.0, temp[:n]]))
    assert x[n - 1] == pytest.approx(
        co.max_recoverable_strain * length * (1 - xi[n - 1]) + thermal, rel=1e-6
    )
    assert x[n - 1] - thermal == pytest.approx(co.max_recoverable_strain * length, rel=1e-4)
    assert thermal == pytest.approx(0.9e-3, abs=0.1e-3)
    # xi = 1/2 where z+(u_A) = 1/2 on heating, u_A = (As + Af)/2 (eq. 4.17), and z-(u_M) = 1/2 on
    # cooling, u_M = (Ms + Mf)/2 (eq. 4.18); the other branch is within 3e-5 of 0 or 1 there
    ki = p.kinetics
    heating_mid = (ki.as0_c + ki.af0_c) / 2 + sigma / ki.ca_pa_per_c  # 95.90 degC
    cooling_mid = (ki.ms0_c + ki.mf0_c) / 2 + sigma / ki.cm_pa_per_c  # 69.90 degC
    assert _crossing(temp[:n], xi[:n]) == pytest.approx(heating_mid, abs=0.02)
    assert _crossing(temp[n:], xi[n:]) == pytest.approx(cooling_mid, abs=0.02)


def test_temperature_drive_same_in_both_apis_and_in_blocks():
    ramp = np.r_[
        np.linspace(22.0, 120.0, 1500), np.linspace(120.0, 80.0, 500), np.linspace(80.0, 110.0, 500)
    ]
    sets = [_dead_weight(s) for s in np.linspace(5e6, 80e6, 12)]
    unit = ActuationUnit(sets[3], dt=DT)
    stepped = _step_all(unit, "temperature", ramp)
    one = simulate(sets[3], DT, temperature=ramp)
    many = simulate(sets, DT, temperature=ramp)  # 12 sets: the vectorised block path
    for name in CHANNELS:
        assert np.array_equal(one[name][0], stepped[name]), name
        assert np.array_equal(many[name][3], stepped[name]), name
    assert np.ptp(stepped["martensite_fraction"]) > 0.9
    # the unit switches between drives: heat balance again after the imposed temperature
    r = unit.step(current=3.0)
    assert r.current_a == 3.0 and r.wire_temperature_c > ramp[-1]
    for bad in (math.nan, math.inf):
        with pytest.raises(ValueError, match="temperature = .*must be finite"):
            unit.step(temperature=bad)
        with pytest.raises(ValueError, match="must be finite"):
            simulate(sets[0], DT, temperature=np.r_[22.0, bad])
    with pytest.raises(ValueError, match="exactly one of duty, current, voltage, temperature"):
        unit.step(duty=10.0, temperature=50.0)


# ------------------------------------------------------------------ 6. batch start temperature
def test_batch_start_temperature_overrides_each_sets_start():
    p = load_params("table41")
    warm = p.replace({"start.temperature_offset_c": 28.0})
    cur = _pulses(3000, 3.0)
    a = simulate(p, DT, current=cur, start_temperature_c=50.0)
    b = simulate(warm, DT, current=cur)
    for name in CHANNELS:
        assert np.array_equal(a[name], b[name]), name
    mixed = simulate(
        [p, warm, p],
        DT,
        current=cur,
        start_temperature_c=[40.0, None, 22.0],
        channels=["wire_temperature_c"],
    )
    assert np.array_equal(mixed.wire_temperature_c[1], b.wire_temperature_c[0])
    assert np.array_equal(
        mixed.wire_temperature_c[2], simulate(p, DT, current=cur).wire_temperature_c[0]
    )
    assert 40.0 < mixed.wire_temperature_c[0, 0] < 40.05  # one step of 3 A from 40 degC
    with pytest.raises(ValueError, match="one value per set"):
        simulate([p, p], DT, current=cur, start_temperature_c=[40.0])
    with pytest.raises(ValueError, match="below As0"):
        simulate(p, DT, current=cur, start_temperature_c=95.0)
