"""Chapter 6 points on the lockstep runs (docs/experiments.md)."""

from __future__ import annotations

import pytest

from hems_ros.control import FORCE_MODE_BPID
from hems_ros.experiments.chapters import CH6_PARAMS, force_protocol, rest_wire_tension
from hems_ros.experiments.dissertation import CH6_TABLES
from hems_ros.experiments.findings import (
    COLD_WIRE_PARAMS,
    FORCE_STEPS,
    WARM_START_C,
    authority_split,
    cold_start_floor,
    force_gain_sweep,
    force_noise_free,
    warm_start_ratios,
)
from hems_ros.experiments.lockstep import run_protocol
from hems_ros.physics import load_params


def test_all_runs_complete(ch6_runs):
    assert len(ch6_runs) == 8
    assert all(run.fault is None for run in ch6_runs.values())


@pytest.mark.parametrize("protocol", FORCE_STEPS)
def test_force_steady_state_error_at_most_01_n_with_noise(ch6_runs, protocol):
    run = ch6_runs[protocol]
    assert run.metrics["ss_error"] <= 0.1
    assert (run.measurement != run.wire_force_n).any()  # the controller saw the noisy sensor


@pytest.mark.parametrize("protocol", FORCE_STEPS)
def test_force_steps_do_not_overshoot(ch6_runs, ch6_found, protocol):
    # first peak of the wire force past each new level, with the sensor noise
    assert ch6_runs[protocol].metrics["overshoot"] <= 0.1
    assert ch6_found["force_no_overshoot"].reproduced


def test_force_steps_without_noise_do_not_overshoot():
    assert max(force_noise_free().values()) <= 0.1


@pytest.mark.parametrize("seed", [1, 2, 3])
def test_force_steps_do_not_overshoot_with_other_noise_seeds(seed):
    prm = load_params(CH6_PARAMS).replace({"force_sensor.seed": seed})
    rest = rest_wire_tension(prm)
    for name in FORCE_STEPS:
        assert (
            run_protocol(force_protocol(name, rest), "bpid", prm, FORCE_MODE_BPID).metrics[
                "overshoot"
            ]
            <= 0.1
        )


@pytest.mark.parametrize("protocol", FORCE_STEPS)
def test_force_hold_ripple_is_reported_apart(ch6_runs, ch6_found, protocol):
    # The noise-driven ripple over the plateau (the dissertation's "oscillation of about 0.1 N")
    # is larger than the first peak and shown in its own column and in the finding.
    m = ch6_runs[protocol].metrics
    assert 0.05 < m["excursion"] < 0.2
    assert m["excursion"] > 2 * m["overshoot"]
    assert "hold ripple" in ch6_found["force_no_overshoot"].evidence


def test_force_gain_sweep_shows_what_the_gains_trade():
    sweep = force_gain_sweep()
    ours, fast = sweep[(FORCE_MODE_BPID.kp, FORCE_MODE_BPID.ki)], sweep[(0.8, 0.5)]
    # the faster set passes a staircase level by more than 0.2 N without noise: the first samples
    # after a 4 N jump at full duty; it follows the step more closely in exchange
    assert fast["quiet"] > 0.2 and ours["quiet"] <= 0.06
    assert fast["rmse_step"] < ours["rmse_step"]
    assert ours["ss_error"] <= 0.06


@pytest.mark.parametrize("protocol", FORCE_STEPS + ("ch6_force_sine_0.125", "ch6_force_sine_0.25"))
def test_force_mode_duty_does_not_chatter(ch6_runs, protocol):
    # FORCE_MODE_BPID: with Table 5.1 gains the duty limit-cycled 0-100 % (MACSI 11-32 %/sample).
    assert ch6_runs[protocol].metrics["macsi"] < 4.0


def test_position_staircase_within_3x_table_6_1(ch6_runs):
    table = CH6_TABLES["position"][2]
    assert (
        ch6_runs["ch6_position_staircase"].metrics["rmse"]
        <= 3 * table["ch6_position_staircase"]["rmse"]
    )


@pytest.mark.parametrize(
    "protocol", ["ch6_position_sine_0.125", "ch6_position_ramp", "ch6_position_step"]
)
def test_position_rmse_misses_documented_as_saturated_actuator(ch6_runs, ch6_found, protocol):
    # Not reproduced (3x Table 6.1): the error is made at 0 % or 100 % duty.
    assert not ch6_found["position_rmse_3x"].reproduced
    split = authority_split(ch6_runs[protocol])
    assert split["cooling_share"] + split["heating_share"] > 0.85  # step: 0.89
    # the dead time at full duty is the model's late transformation onset, bounded by energy
    assert "even with no heat loss" in ch6_found["position_rmse_3x"].evidence


@pytest.mark.parametrize(
    "protocol, floor_mm", [("ch6_position_ramp", 0.0666), ("ch6_position_sine_0.125", 0.2554)]
)
def test_cold_wire_cannot_reach_3x_on_the_ascending_parts(ch6_runs, ch6_found, protocol, floor_mm):
    # An idealised cold wire with Table 4.1's band (80 W, no loss, no latent heat, 3.8 % stroke)
    # already stays more than 3x Table 6.1 behind; the model, with losses, does worse still.
    floor = cold_start_floor(protocol)
    assert floor["rmse_mm"] == pytest.approx(floor_mm, abs=5e-4)
    assert floor["ratio"] > 3.0
    assert 0.7 < floor["catch_up_s"] < 0.9
    assert ch6_runs[protocol].metrics["rmse"] >= floor["rmse_mm"]
    assert (
        f"{floor['rmse_mm']:.3f} mm on the {protocol[13:]}"
        in ch6_found["position_rmse_3x"].evidence
    )


def test_cold_start_floor_falls_with_a_warm_wire():
    # The floor is the start temperature's doing: a wire 18 K warmer at the start is not
    # bound above 3x.
    warm = load_params(COLD_WIRE_PARAMS).replace({"ambient_temperature_c": 40.0})
    assert cold_start_floor("ch6_position_ramp", warm)["ratio"] < 2.0
    assert cold_start_floor("ch6_position_sine_0.125", warm)["ratio"] < 1.2


def test_cold_start_floor_refuses_plateau_protocols():
    with pytest.raises(
        ValueError, match="ch6_position_step: the cold-start floor bounds ascending-part RMSE"
    ):
        cold_start_floor("ch6_position_step")


def test_no_warm_start_brings_the_missed_references_within_3x(ch6_runs, ch6_found):
    # A rig warm from earlier work is the other reading of the cold-start floor; with the model's
    # wire it helps the ramp only: the step stays above 3x and the sine's slow descents get worse.
    missed = ("ch6_position_sine_0.125", "ch6_position_ramp", "ch6_position_step")
    warm = warm_start_ratios(missed)
    assert list(warm) == list(WARM_START_C)
    for temp, row in warm.items():
        assert max(row.values()) > 3.0, temp
        assert row["ch6_position_step"] > 3.5, temp
        assert row["ch6_position_sine_0.125"] > 90.0, temp
    assert warm[70.0]["ch6_position_ramp"] == pytest.approx(2.58, abs=0.05)
    assert warm[40.0]["ch6_position_step"] == pytest.approx(3.85, abs=0.1)
    cold = {p: ch6_runs[p].metrics["rmse"] / CH6_TABLES["position"][2][p]["rmse"] for p in missed}
    assert cold["ch6_position_sine_0.125"] < min(
        row["ch6_position_sine_0.125"] for row in warm.values()
    )
    evidence = ch6_found["position_rmse_3x"].evidence
    assert "no start temperature brings them all within 3x" in evidence
    assert "ramp 2.6x at 70 degC" in evidence


def test_a_start_temperature_must_leave_the_wire_martensite():
    with pytest.raises(ValueError, match="below As0 = 88 degC"):
        run_protocol("ch6_position_step", "bpid", CH6_PARAMS, start_temperature_c=90.0)
    with pytest.raises(ValueError, match="start temperature must be finite"):
        run_protocol("ch6_position_step", "bpid", CH6_PARAMS, start_temperature_c=float("nan"))
