"""Stepping and batch APIs: one kernel, same trajectory; sensors; errors for bad inputs."""

import math

import numpy as np
import pytest

from hems_ros.physics import ActuationUnit, block, simulate
from hems_ros.physics.batch import CHANNELS
from hems_ros.physics.params import load_params


def _drive(n):
    t = np.arange(n) * 1e-3
    return np.clip(50 + 50 * np.sin(2 * np.pi * 0.25 * t), 0, 100) * (t < 6)


@pytest.mark.parametrize("name", ["sheathed_calibrated", "ch6_hems_index", "table41"])
def test_step_and_batch_agree(name):
    p = load_params(name)
    duty = _drive(9000)
    res = simulate(p, 1e-3, duty=duty)
    unit = ActuationUnit(p, dt=1e-3)
    steps = [unit.step(duty=d) for d in duty]
    pairs = {
        "wire_temperature_c": "wire_temperature_c",
        "martensite_fraction": "martensite_fraction",
        "stress_pa": "stress_pa",
        "slider_position_m": "slider_position_m",
        "sheath_temperature_c": "sheath_temperature_c",
        "resistance_ohm": "resistance_ohm",
        "wire_force_n": "wire_force_n",
        "tendon_force_n": "tendon_force_n",
        "current_a": "current_a",
        "electrical_power_w": "electrical_power_w",
        "energy_joule_j": "energy_joule_j",
    }
    for batch_name, step_name in pairs.items():
        a = res[batch_name][0]
        b = np.array([getattr(s, step_name) for s in steps])
        span = max(np.ptp(a), 1e-12)
        assert np.max(np.abs(a - b)) <= 1e-6 * span, batch_name
    assert np.array_equal(res.encoder_counts[0], [s.encoder_counts for s in steps])
    assert np.array_equal(res.force_reading_n[0], [s.force_reading_n for s in steps])
    assert np.array_equal(res.force_saturated[0], [s.force_saturated for s in steps])
    assert unit.time == pytest.approx(9.0)


def test_batch_of_many_sets_matches_single_runs_and_record_every():
    base = load_params("sheathed_calibrated")
    sets = [base.replace({"sheath.heat_capacity_j_per_k": c}) for c in (2.0, 3.0, 6.0)]
    cur = np.where(np.arange(4000) < 1800, 4.0, 0.0)
    many = simulate(sets, 1e-3, current=cur, record_every=10)
    assert many.slider_position_m.shape == (3, 400) and many.time[0] == pytest.approx(0.01)
    for i, p in enumerate(sets):
        one = simulate(p, 1e-3, current=cur)
        assert np.array_equal(many.slider_position_m[i], one.slider_position_m[0, 9::10])
    assert many.slider_position_m[0].max() > many.slider_position_m[2].max()


def test_vectorised_blocks_match_set_by_set_runs_bit_for_bit():
    # 40 sets: one full SIMD block of block.BLOCK sets and a partial one, against each set
    # run alone (kernel.step set by set); pulses of rising length drive reversals, nested
    # minor loops and loop closures, over the three load kinds of the named sets
    names = ("sheathed_calibrated", "ch6_hems_index", "table41")
    sets = [
        load_params(names[i % 3]).replace({"kinetics.as0_c": 84.0 + 0.2 * i}) for i in range(40)
    ]
    t = np.arange(12000) * 1e-3
    duty = np.where((t % 2.0) < 0.3 + 0.1 * np.floor(t / 2.0), 80.0, 0.0)
    many = simulate(sets, 1e-3, duty=duty, record_every=3)
    for i, p in enumerate(sets):
        one = simulate(p, 1e-3, duty=duty, record_every=3)
        for name in CHANNELS:
            assert np.array_equal(many[name][i], one[name][0]), (i, name)
    assert np.ptp(many.martensite_fraction) > 0.5


def test_without_energy_channels_the_blocks_agree_to_rounding():
    # no energy channel recorded: the blocks skip the accumulators, and LLVM may then fuse a
    # multiply-add differently, so the agreement with step is to rounding, not to the bit
    names = ("sheathed_calibrated", "ch6_hems_index", "table41")
    sets = [
        load_params(names[i % 3]).replace({"kinetics.as0_c": 84.0 + 0.2 * i}) for i in range(40)
    ]
    t = np.arange(12000) * 1e-3
    duty = np.where((t % 2.0) < 0.3 + 0.1 * np.floor(t / 2.0), 80.0, 0.0)
    lean = ["wire_temperature_c", "martensite_fraction", "slider_position_m", "wire_force_n"]
    many = simulate(sets, 1e-3, duty=duty, record_every=3, channels=lean)
    for i, p in enumerate(sets):
        one = simulate(p, 1e-3, duty=duty, record_every=3, channels=lean)
        for name in lean:
            assert np.max(np.abs(many[name][i] - one[name][0])) <= 1e-12 * np.ptp(one[name][0]), (
                i,
                name,
            )


def test_one_newton_step_per_step_keeps_first_order_accuracy_through_minor_loops():
    # kernel.step keeps the first Newton step of its kinetic solve; on a scaled branch that
    # leaves a second-order residual, which must not build up over many minor loops: at 1 ms
    # the trajectory stays as close to a 0.1 ms run as the time discretisation allows
    rng = np.random.default_rng(1)
    duty, k, on = (
        np.zeros(3000),
        0,
        True,
    )  # 30 s of 100 Hz decisions: 50-490 ms bursts, pauses to 1 s
    while k < duty.size:
        n = int(rng.integers(5, 50 if on else 100))
        duty[k : k + n] = 100.0 if on else 0.0
        k, on = k + n, not on
    p = load_params("sheathed_calibrated")
    coarse = simulate(
        p, 1e-3, duty=np.repeat(duty, 10), channels=["slider_position_m", "martensite_fraction"]
    )
    fine = simulate(
        p,
        1e-4,
        duty=np.repeat(duty, 100),
        record_every=10,
        channels=["slider_position_m", "martensite_fraction"],
    )
    x, x_fine = coarse.slider_position_m[0], fine.slider_position_m[0]
    stroke = np.ptp(x_fine)
    assert stroke > 0.02
    assert np.max(np.abs(x - x_fine)) <= 2e-3 * stroke  # measured 9.2e-4
    assert np.sqrt(np.mean((x - x_fine) ** 2)) <= 3e-4 * stroke  # measured 1.3e-4
    assert (
        np.max(np.abs(coarse.martensite_fraction[0] - fine.martensite_fraction[0])) <= 1e-3
    )  # 5.0e-4


def test_each_set_of_a_block_gets_its_own_drive_row():
    p = load_params("sheathed_calibrated")
    amps = np.linspace(2.0, 4.0, 40)
    cur = np.where(np.arange(3000) < 1500, 1.0, 0.0)[None, :] * amps[:, None]
    many = simulate(
        [p] * 40,
        1e-3,
        current=cur,
        record_every=10,
        channels=["wire_temperature_c", "energy_joule_j"],
    )
    for i in (0, 17, 39):
        one = simulate(p, 1e-3, current=cur[i], record_every=10, channels=["wire_temperature_c"])
        assert np.array_equal(many.wire_temperature_c[i], one.wire_temperature_c[0])
    assert many.wire_temperature_c[39].max() > many.wire_temperature_c[0].max() + 20.0


def test_a_failing_set_in_a_block_is_named():
    p = load_params("table41")
    volts = np.zeros((block.BLOCK, 100))
    volts[5] = 1e200
    with pytest.raises(FloatingPointError, match="parameter set 5"):
        simulate([p] * block.BLOCK, 1e-3, voltage=volts)


def test_sensors_quantise_and_flag_saturation():
    p = load_params("sheathed_calibrated")  # 50 N preload on a 0-50 N sensor
    r = ActuationUnit(p).step(current=0.0)
    assert isinstance(r.encoder_counts, int)
    assert r.encoder_position_m == r.encoder_counts * 1e-6
    assert r.force_saturated and r.force_reading_n in (0.0, 50.0)
    q = ActuationUnit(
        p.replace({"force_sensor.range_max_n": 100.0, "force_sensor.noise_std_n": 0.0})
    ).step(current=0.0)
    assert not q.force_saturated and q.force_reading_n == pytest.approx(50.0, abs=0.005)
    assert round(q.force_reading_n / 0.01) * 0.01 == pytest.approx(q.force_reading_n)


def test_force_noise_is_seeded():
    p = load_params("ch6_hems_index").replace({"force_sensor.noise_std_n": 0.5})
    first = ActuationUnit(p).step(current=0.0).force_reading_n
    u1, u2 = ActuationUnit(p), ActuationUnit(p.replace({"force_sensor.seed": 7}))
    s1 = [u1.step(current=0.0).force_reading_n for _ in range(50)]
    s2 = [u2.step(current=0.0).force_reading_n for _ in range(50)]
    u1.reset()
    assert [u1.step(current=0.0).force_reading_n for _ in range(50)] == s1
    assert s1 != s2 and first == s1[0]
    assert np.std(s1) > 0.2


def test_advance_then_result_is_step():
    p = load_params("ch6_hems_index")
    stepped, advanced = ActuationUnit(p), ActuationUnit(p)
    for d in _drive(500):
        last = stepped.step(duty=d)
        advanced.advance(duty=d)
    assert advanced.result() == last
    with pytest.raises(ValueError, match="0-100"):
        advanced.advance(duty=101.0)


def test_readings_are_the_results_sensor_values():
    unit = ActuationUnit(load_params("ch6_hems_index"))
    seen = set()
    for d in _drive(4000):
        unit.advance(duty=d)
        r = unit.result()
        assert unit.readings() == (r.encoder_counts, r.encoder_position_m, r.wire_force_n)
        assert type(unit.readings()[0]) is int
        seen.add(r.encoder_counts)
    assert len(seen) > 50


def test_a_noiseless_force_sensor_has_no_generator_and_a_snapshot_still_repeats():
    unit = ActuationUnit(load_params("ch6_hems_index").replace({"force_sensor.noise_std_n": 0.0}))
    assert unit._rng is None
    unit.advance(duty=40.0, steps=50)
    snapshot = unit.snapshot()
    unit.advance(duty=40.0)
    first = unit.result()
    unit.restore(snapshot)
    unit.advance(duty=40.0)
    assert unit.result() == first
    assert first.force_reading_n == round(first.wire_force_n / 0.01) * 0.01 or first.force_saturated


def test_advance_in_blocks_is_the_same_steps_one_by_one():
    # the node integrates a sample period per call; noise draws and state must not notice
    p = load_params("ch6_hems_index").replace({"force_sensor.noise_std_n": 0.5})
    single, blocks = ActuationUnit(p), ActuationUnit(p)
    for d in (0.0, 80.0, 100.0, 35.0, 0.0):
        for _ in range(137):
            single.advance(duty=d)
        blocks.advance(duty=d, steps=100)
        blocks.advance(duty=d, steps=37)
        assert blocks.result() == single.result()
    assert np.array_equal(blocks.snapshot()[0], single.snapshot()[0]) and blocks.steps == 5 * 137
    for bad in (0, -3, 2.5, True):
        with pytest.raises(ValueError, match="steps"):
            blocks.advance(duty=10.0, steps=bad)


def test_reset_and_state():
    u = ActuationUnit(load_params("table41"))
    for _ in range(500):
        u.step(current=4.0)
    assert u.state["wire_temperature_c"] > 40 and u.time == pytest.approx(0.5)
    u.reset()
    assert (
        u.time == 0.0
        and u.state["wire_temperature_c"] == 22.0
        and u.state["martensite_fraction"] == 1.0
    )


@pytest.mark.parametrize(
    "kwargs, pattern",
    [
        ({"duty": math.nan}, "must be finite"),
        ({"current": math.inf}, "must be finite"),
        ({"duty": 100.5}, "within 0-100"),
        ({"duty": -1.0}, "within 0-100"),
        ({}, "exactly one"),
        ({"duty": 10.0, "current": 1.0}, "exactly one"),
    ],
)
def test_step_rejects_bad_drive(kwargs, pattern):
    with pytest.raises(ValueError, match=pattern):
        ActuationUnit().step(**kwargs)


def test_simulate_rejects_bad_input():
    p = load_params("table41")
    with pytest.raises(ValueError, match=r"current\[0, 3\] = nan"):
        simulate(p, 1e-3, current=np.array([0, 0, 0, np.nan]))
    with pytest.raises(ValueError, match="within 0-100"):
        simulate(p, 1e-3, duty=np.array([0.0, 120.0]))
    with pytest.raises(ValueError, match="exactly one"):
        simulate(p, 1e-3)
    with pytest.raises(ValueError, match="shape"):
        simulate([p, p], 1e-3, current=np.zeros((3, 10)))
    with pytest.raises(ValueError, match="unknown channel"):
        simulate(p, 1e-3, current=np.zeros(10), channels=["nope"])
    with pytest.raises(ValueError, match="dt"):
        ActuationUnit(p, dt=0.0)
    assert "slider_position_m" in CHANNELS


def test_runaway_state_raises_instead_of_returning_nan():
    p = load_params("table41")
    with pytest.raises(FloatingPointError, match="non-finite"):
        simulate(p, 1e-3, voltage=np.full(100, 1e200))
