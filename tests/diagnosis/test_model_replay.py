"""Open-loop replay of measured time series (hems_ros.diagnosis.replay): a run made from a
known truth replays to that truth at its sample instants, whatever its sampling."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from hems_ros.diagnosis import replay
from hems_ros.diagnosis.runs import DiagnosisInputError, TimeSeriesRun
from hems_ros.diagnosis.workflow import diagnose
from hems_ros.physics.batch import simulate
from hems_ros.physics.params import load_params

BASE = load_params("table41")
CHANNELS = ["slider_position_m", "wire_force_n", "tendon_force_n", "wire_temperature_c"]
OUTPUTS = {
    "position": "slider_position_m",
    "wire_force": "wire_force_n",
    "load_force": "tendon_force_n",
    "temperature": "wire_temperature_c",
}


def _duty_per_sample(n: int, seed: int = 1) -> np.ndarray:
    """Two pulses and some random levels: every sample's duty matters to the replay."""
    rng = np.random.default_rng(seed)
    duty = np.zeros(n)
    duty[10:170] = 100.0
    duty[250:300] = rng.uniform(40.0, 100.0, 50)
    return duty


def _truth_run(time: np.ndarray, duty: np.ndarray, params=BASE, dt: float = 1e-3) -> TimeSeriesRun:
    """The truth sampled at ``time`` (dt-aligned), each duty held from its sample to the next,
    simulated step by step here (not through replay.plan) so the test checks the alignment."""
    index = np.rint(time / dt).astype(int)
    per_step = np.zeros(index[-1])
    for k in range(time.size - 1):
        per_step[index[k] : index[k + 1]] = duty[k]
    res = simulate(params, dt, duty=per_step, channels=CHANNELS)
    rest = params.load.static_force_n()
    start = {
        "slider_position_m": 0.0,
        "wire_force_n": rest,
        "tendon_force_n": rest,
        "wire_temperature_c": params.ambient_temperature_c,
    }
    outputs = {
        name: np.concatenate([[start[ch]], res[ch][0][index[1:] - 1]])
        for name, ch in OUTPUTS.items()
    }
    return TimeSeriesRun("truth", "synthetic", "driven", time, "duty", duty, outputs)


def _assert_replays_truth(run: TimeSeriesRun, params=BASE) -> dict[str, np.ndarray]:
    out = replay.replay(replay.plan(run), [params])
    for name, truth in run.outputs.items():
        np.testing.assert_allclose(out[name][0], truth, rtol=1e-12, atol=1e-12, err_msg=name)
    return out


def test_regular_run_replays_its_truth_with_sample_zero_the_initial_state() -> None:
    time = np.arange(400) * 0.01
    run = _truth_run(time, _duty_per_sample(400))
    p = replay.plan(run)
    assert (p.dt, p.record_every, p.values.size) == (1e-3, 10, 3990)
    out = _assert_replays_truth(run)
    assert out["position"][0, 0] == 0.0
    assert out["wire_force"][0, 0] == pytest.approx(12.0, abs=1e-9)  # the 12 N pretension
    assert out["temperature"][0, 0] == 22.0
    assert out["position"][0].max() > 5e-3  # the pulses moved the wire


def test_a_duty_applies_from_its_sample_to_the_next() -> None:
    # one sample of 100 % at sample 20: the wire warms between samples 20 and 21 only
    duty = np.zeros(40)
    duty[20] = 100.0
    time = np.arange(40) * 0.01
    run = TimeSeriesRun(
        "one", "synthetic", "driven", time, "duty", duty, {"temperature": np.zeros(40)}
    )
    temp = replay.replay(replay.plan(run), [BASE])["temperature"][0]
    assert np.all(temp[:21] == 22.0)
    # 10 ms at 4 A (the current limit) into a 0.985 J/K wire of about 4.2 ohm: about 0.7 K
    assert 0.3 < temp[21] - 22.0 < 1.2
    assert np.all(np.diff(temp[21:]) < 0)  # cooling from then on


def test_a_step_function_input_applies_each_change_from_the_next_plant_step() -> None:
    time = np.arange(400) * 0.01
    duty = _duty_per_sample(400)
    run = _truth_run(time, duty)
    sampled = replay.plan(run).values
    # the same input as a step function at the sample instants: the same per-step input
    same = dataclasses.replace(run, drive_steps=(time.copy(), duty.copy()))
    np.testing.assert_array_equal(replay.plan(same).values, sampled)
    # a command that arrives 4.5 ms after a sample applies from the step 5 ms after it; before
    # the first command the unit is off
    late = dataclasses.replace(
        run, drive_steps=(np.array([0.0345, 0.1, 0.2]), np.array([50.0, 80.0, 0.0]))
    )
    values = replay.plan(late).values
    assert np.all(values[:35] == 0.0) and np.all(values[35:100] == 50.0)
    assert np.all(values[100:200] == 80.0) and np.all(values[200:] == 0.0)
    early = dataclasses.replace(run, drive_steps=(np.array([0.5, 1.0]), np.array([30.0, 0.0])))
    values = replay.plan(early).values
    assert (
        np.all(values[:500] == 0.0)
        and np.all(values[500:1000] == 30.0)
        and np.all(values[1000:] == 0.0)
    )


@pytest.mark.parametrize("steps", [[1, 2, 3, 5, 7, 10], [20, 40, 60]])
def test_irregular_dt_aligned_sampling_replays_its_truth(steps: list[int]) -> None:
    rng = np.random.default_rng(3)
    gaps = rng.choice(steps, size=300) * 1e-3
    time = np.concatenate([[0.0], np.cumsum(gaps)])
    run = _truth_run(time, _duty_per_sample(time.size))
    p = replay.plan(run)
    assert p.dt == pytest.approx(1e-3, rel=1e-9)  # the smallest gap, to the rounding of the cumsum
    assert p.record_every == int(np.gcd.reduce(steps))
    assert p.records.size == time.size - 1
    _assert_replays_truth(run)


def _sampled(time: np.ndarray) -> TimeSeriesRun:
    """A run with nothing but its sample instants."""
    return TimeSeriesRun(
        "sampled", "s", "driven", time, "duty", np.zeros(time.size), {"position": time * 0}
    )


def test_fast_sampling_shrinks_the_step_and_too_fast_is_refused() -> None:
    p = replay.plan(_sampled(np.arange(300) * 0.5e-3))
    assert p.dt == pytest.approx(0.5e-3, rel=1e-9) and p.record_every == 1
    too_fast = r"samples 0\.05 ms apart; the replay needs them at least 0\.1 ms apart"
    with pytest.raises(DiagnosisInputError, match=too_fast):
        replay.plan(_sampled(np.arange(300) * 0.05e-3))
    with pytest.raises(DiagnosisInputError, match="a run needs more than one sample"):
        replay.plan(_sampled(np.zeros(1)))
    # instants off the 1 ms grid get a finer step that holds them (0.5 ms here)
    p = replay.plan(_sampled(np.array([0.0, 0.0015, 0.0025, 0.004])))
    assert p.dt == pytest.approx(0.5e-3, rel=1e-9) and p.records.tolist() == [2, 4, 7]


def test_samples_exactly_0_1_ms_apart_are_accepted() -> None:
    p = replay.plan(_sampled(np.arange(300) * 1e-4))
    assert p.record_every == 1


def test_samples_off_the_millisecond_grid_are_read_at_their_own_instants() -> None:
    time = np.arange(200) * 1.5e-3
    p = replay.plan(_sampled(time))
    read_at = (p.records + 1) * p.record_every * p.dt
    np.testing.assert_allclose(read_at, time[1:], atol=1e-9)


def test_sets_differing_in_sensor_keys_share_one_simulation(monkeypatch) -> None:
    time = np.arange(300) * 0.01
    run = _truth_run(time, _duty_per_sample(300))
    run = TimeSeriesRun(
        "s",
        "s",
        "driven",
        time,
        "duty",
        run.drive_values,
        {k: run.outputs[k] for k in ("position", "wire_force")},
    )
    damped = BASE.replace({"load.damping_n_s_per_m": 400.0})
    sets = [
        BASE,
        BASE.replace({"encoder.gain": 1.1}),
        damped,
        BASE.replace({"force_sensor.offset_n": 0.5, "force_sensor.drift_n_per_s": 0.02}),
        damped.replace({"encoder.gain": 0.9}),
    ]
    sizes = []
    real = replay.simulate

    def spy(params, *args, **kwargs):
        sizes.append(len(params))
        return real(params, *args, **kwargs)

    monkeypatch.setattr(replay, "simulate", spy)
    out = replay.replay(replay.plan(run), sets)
    assert sizes == [2]
    x, f = out["position"], out["wire_force"]
    np.testing.assert_allclose(x[0], run.outputs["position"], rtol=1e-12, atol=1e-15)
    np.testing.assert_allclose(x[1], 1.1 * x[0], rtol=1e-12, atol=0)
    np.testing.assert_array_equal(f[1], f[0])  # the gain is the encoder's only
    np.testing.assert_allclose(f[3], f[0] + 0.5 + 0.02 * time, rtol=1e-12, atol=1e-12)
    np.testing.assert_array_equal(x[3], x[0])
    np.testing.assert_allclose(x[4], 0.9 * x[2], rtol=1e-12, atol=0)
    # damping slows the contraction: the damped rows are a different simulation
    assert np.max(np.abs(x[2] - x[0])) > 1e-4


THERMAL_STRESS = 150e6


def _thermal_run(temps: np.ndarray, spacing_s: float = 1.0) -> TimeSeriesRun:
    time = np.arange(temps.size) * spacing_s
    return TimeSeriesRun(
        "tc",
        "synthetic",
        "thermal_cycle",
        time,
        "temperature",
        temps,
        {"strain": np.zeros(temps.size), "temperature": temps},
        stress_pa=THERMAL_STRESS,
    )


def test_thermal_cycle_replay_contracts_by_the_transformation_strain() -> None:
    temps = np.r_[np.arange(40.0, 140.0), np.arange(140.0, 39.0, -1.0)]
    run = _thermal_run(temps)
    p = replay.plan(run)
    assert (p.dt, p.record_every, p.thermal) == (replay.THERMAL_DT, 100, True)
    out = replay.replay(p, [BASE])
    strain = out["strain"][0]
    np.testing.assert_allclose(out["temperature"][0], temps, atol=1e-9)
    rig = replay.thermal_cycle_rig(BASE, THERMAL_STRESS)
    assert rig.load.mass_kg * 9.81 / rig.wire.cross_section_m2 == pytest.approx(
        THERMAL_STRESS, rel=1e-12
    )
    res = simulate(
        rig,
        p.dt,
        temperature=p.values,
        record_every=p.record_every,
        start_temperature_c=40.0,
        channels=["martensite_fraction"],
    )
    xi = np.concatenate([[1.0], res.martensite_fraction[0][p.records]])
    eps_l = BASE.constitutive.max_recoverable_strain
    # at constant stress d(eps) = eps_L d(xi) - alpha dT: the thermal part stays under 0.1 % here
    np.testing.assert_allclose(strain, -eps_l * (1.0 - xi), atol=1e-3)
    assert xi.min() < 0.01 and strain.min() == pytest.approx(-eps_l, abs=1e-3)
    assert strain[0] == 0.0 and abs(strain[-1]) < 1e-3 and xi[-1] > 0.99
    # half transformed mid-band, the band shifted by stress / C (21.8 degC at 150 MPa)
    top = int(temps.argmax())
    shift = THERMAL_STRESS / BASE.kinetics.ca_pa_per_c
    heat_half = np.interp(0.5, xi[: top + 1][::-1], temps[: top + 1][::-1])
    cool_half = np.interp(0.5, xi[top:], temps[top:])
    assert heat_half == pytest.approx((88.0 + 98.0) / 2 + shift, abs=2.0)
    assert cool_half == pytest.approx((72.0 + 62.0) / 2 + shift, abs=2.0)


def test_thermal_cycle_must_start_below_as0() -> None:
    as0 = BASE.kinetics.as0_c
    for start in (as0, as0 + 5.0):
        run = _thermal_run(np.linspace(start, start + 40.0, 41))
        assert f"starts at {start:g} degC, at or above As0 = 88 degC" in replay.cannot_start(
            BASE, run
        )
        # a set that cannot start the run has no outputs (a fit counts it out); the starting
        # model's is an input error (workflow.diagnose)
        assert np.isnan(replay.replay(replay.plan(run), [BASE])["strain"]).all()
        with pytest.raises(
            DiagnosisInputError, match=f"starts at {start:g} degC, at or above As0 = 88 degC"
        ):
            diagnose([run], [], BASE)
    run = _thermal_run(np.linspace(as0 - 0.5, as0 + 40.0, 41))
    assert replay.cannot_start(BASE, run) is None and replay.start_temperature(run) == as0 - 0.5
    assert replay.start_temperature(_truth_run(np.arange(30) * 0.01, np.zeros(30))) is None
    with pytest.raises(DiagnosisInputError, match="must be > 0"):
        replay.thermal_cycle_rig(BASE, 0.0)


def test_thermal_cycle_replay_ignores_heat_transfer_and_the_start_offset() -> None:
    # the imposed temperature leaves convection, ambient and a warm start nothing to change,
    # although candidates.applicable still offers them for thermal cycles (see the report)
    run = _thermal_run(np.r_[np.arange(40.0, 140.0), np.arange(140.0, 39.0, -1.0)])
    sets = [
        BASE,
        BASE.replace({"thermal.h0_w_m2_c": 55.0}),
        BASE.replace({"ambient_temperature_c": 35.0}),
        BASE.replace({"start.temperature_offset_c": 30.0}),
        BASE.replace({"constitutive.max_recoverable_strain": 0.045}),
    ]
    strain = replay.replay(replay.plan(run), sets)["strain"]
    for row in strain[1:4]:
        np.testing.assert_array_equal(row, strain[0])
    assert strain[4].min() == pytest.approx(strain[0].min() * 0.045 / 0.038, rel=0.03)


@pytest.mark.parametrize("steps", [0.0, 2.0, 3.7, -2.25, 0.5, 1e-9, 9.5, 25.3, -40.2])
def test_a_delayed_input_takes_each_steps_record_minus_the_delay(steps: float) -> None:
    values = np.random.default_rng(7).random(20)
    expected = []
    for i in range(values.size):
        position = i - steps
        below = int(np.floor(position))
        share = position - below
        low, high = (values[min(max(k, 0), values.size - 1)] for k in (below, below + 1))
        expected.append((1.0 - share) * low + share * high)
    assert np.allclose(replay.delayed(values, steps), expected, rtol=0.0, atol=1e-12)
    assert replay.delayed(values[:0], steps).size == 0


def test_a_delayed_input_stays_within_its_records() -> None:
    """With weights (1 - s, s) for a small share s, a step between two records of 100 % came
    out at 100.00000000000001 %, which the batch refuses as a duty."""
    duty = np.array([0.0, 100.0, 100.0, 100.0, 37.5, 37.5, 0.0] * 50)
    # a lead of a small fraction of a step leaves exactly that fraction as the share
    for share in 10.0 ** np.random.default_rng(3).uniform(-12, -1, 400):
        shifted = replay.delayed(duty, -share)
        assert shifted.min() >= 0.0 and shifted.max() <= 100.0, share
