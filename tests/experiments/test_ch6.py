"""Chapter 6 must-show points of issue 4 on the lockstep runs (docs/experiments.md)."""

from __future__ import annotations

import pytest

from hems_ros.experiments.dissertation import CH6_TABLES
from hems_ros.experiments.findings import authority_split, force_gain_sweep, force_noise_free

FORCE_STEPS = ("ch6_force_step", "ch6_force_staircase")


def test_all_runs_complete(ch6_runs):
    assert len(ch6_runs) == 8
    assert all(run.fault is None for run in ch6_runs.values())


@pytest.mark.parametrize("protocol", FORCE_STEPS)
def test_force_steady_state_error_at_most_01_n_with_noise(ch6_runs, protocol):
    run = ch6_runs[protocol]
    assert run.metrics["ss_error"] <= 0.1
    assert (run.measurement != run.wire_force_n).any()  # the controller saw the noisy sensor


@pytest.mark.parametrize("protocol", FORCE_STEPS)
def test_force_overshoot_documented(ch6_runs, ch6_found, protocol):
    # Not reproduced: 0.18-0.24 N past the level, the first samples after the staircase's jumps and
    # the hold ripple of the sensor noise (docs/experiments.md); 1-2 N with the Table 5.1 gains.
    assert not ch6_found["force_no_overshoot"].reproduced
    assert 0.1 < ch6_runs[protocol].metrics["overshoot"] < 0.3
    evidence = ch6_found["force_no_overshoot"].evidence
    assert "Without sensor noise" in evidence and "No force gain set of a sweep" in evidence


def test_force_step_without_noise_does_not_overshoot():
    assert force_noise_free()["ch6_force_step"] <= 0.1


def test_no_force_gain_set_of_the_sweep_keeps_the_noisy_steps_within_01_n():
    sweep = force_gain_sweep()
    assert min(v["noisy"] for v in sweep.values()) > 0.1
    # without the noise some sets approach with at most 0.06 N, so what the noise adds is the ripple
    assert min(v["quiet"] for v in sweep.values()) <= 0.06
    assert sweep[(0.8, 0.5)]["quiet"] > 0.2     # FORCE_MODE_BPID: the first samples after a 4 N jump


@pytest.mark.parametrize("protocol", FORCE_STEPS + ("ch6_force_sine_0.125", "ch6_force_sine_0.25"))
def test_force_mode_duty_does_not_chatter(ch6_runs, protocol):
    # FORCE_MODE_BPID: with Table 5.1 gains the duty limit-cycled 0-100 % (MACSI 11-32 %/sample).
    assert ch6_runs[protocol].metrics["macsi"] < 4.0


def test_position_staircase_within_3x_table_6_1(ch6_runs):
    table = CH6_TABLES["position"][2]
    assert ch6_runs["ch6_position_staircase"].metrics["rmse"] <= 3 * table["ch6_position_staircase"]["rmse"]


@pytest.mark.parametrize("protocol", ["ch6_position_sine_0.125", "ch6_position_ramp", "ch6_position_step"])
def test_position_rmse_misses_documented_as_saturated_actuator(ch6_runs, ch6_found, protocol):
    # Not reproduced (3x Table 6.1): the error is made at 0 % or 100 % duty.
    assert not ch6_found["position_rmse_3x"].reproduced
    split = authority_split(ch6_runs[protocol])
    assert split["cooling_share"] + split["heating_share"] > 0.85   # step: 0.89
    # the dead time at full duty is the model's late transformation onset, bounded by energy
    assert "even with no heat loss" in ch6_found["position_rmse_3x"].evidence
