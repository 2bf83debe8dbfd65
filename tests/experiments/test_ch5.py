"""Chapter 5 must-show points of issue 4 on the lockstep runs (docs/experiments.md).

Findings the simulation does not reproduce assert the documented outcome and its evidence.
"""

from __future__ import annotations

import pytest

from hems_ros.experiments.dissertation import CH5_PROTOCOLS, CH5_TABLES
from hems_ros.experiments.chapters import CH5_PARAMS
from hems_ros.experiments.findings import (MARGIN, authority_split, bilinear_activity, filter_sweep, perturbation_spread,
                                         rate_check, ratios, sheath_mass_check)
from hems_ros.physics import load_params
from hems_ros.physics.scenarios import characterization_rig, pulse_responses

STEPS = ("ch5_step", "ch5_staircase")


def test_all_runs_complete(ch5_runs):
    assert len(ch5_runs) == 15
    assert all(run.fault is None for run in ch5_runs.values())


@pytest.mark.parametrize("protocol", STEPS)
def test_bpid_steady_state_error_at_most_005_mm(ch5_runs, protocol):
    assert ch5_runs[protocol, "bpid"].metrics["ss_error"] <= 0.05


@pytest.mark.parametrize("protocol", STEPS)
def test_bpid_overshoot_documented_as_plant_coast(ch5_runs, ch5_found, protocol):
    # Not reproduced: the model's wire coasts past the target after the heater is cut.
    assert not ch5_found["bpid_overshoot"].reproduced
    assert ch5_runs[protocol, "bpid"].metrics["overshoot"] > 0.05
    assert "keeps moving" in ch5_found["bpid_overshoot"].evidence


@pytest.mark.parametrize("protocol", CH5_PROTOCOLS)
def test_pipd_has_the_lowest_macsi(ch5_runs, protocol):
    m = {s: ch5_runs[protocol, s].metrics["macsi"] for s in ("pid", "pipd", "bpid")}
    assert min(m, key=m.get) == "pipd"


@pytest.mark.parametrize("protocol", STEPS)
def test_bpid_runs_the_pid_loop(ch5_runs, ch5_found, protocol):
    # Not reproduced: BPID clearly highest MACSI / lowest RMSE. With Table 5.1 gains in um
    # the eq 5.36 factor almost never acts, so BPID and PID agree within a few per cent.
    assert not ch5_found["bpid_lowest_rmse"].reproduced
    assert not ch5_found["bpid_highest_macsi"].reproduced
    assert bilinear_activity(ch5_runs[protocol, "bpid"]) < 0.01
    for metric in ("rmse", "macsi"):
        b, p = ch5_runs[protocol, "bpid"].metrics[metric], ch5_runs[protocol, "pid"].metrics[metric]
        assert abs(b - p) <= 0.05 * p


def test_a_1e6_degc_change_moves_the_step_cells_by_a_few_per_cent(ch5_runs, ch5_found):
    # the run-to-run spread the BPID ranking findings quote (measured 3.3 % RMSE, 4.2 % MACSI):
    # the closed loop does amplify a difference that small, and by less than the margin a
    # ranking has to beat
    spread = perturbation_spread(ch5_runs, load_params(CH5_PARAMS))
    assert 0.005 < spread["rmse"] < MARGIN
    assert 0.005 < spread["macsi"] < MARGIN
    assert f"RMSE of the three controllers by up to {100 * spread['rmse']:.1f} %" in ch5_found["bpid_lowest_rmse"].evidence


@pytest.mark.parametrize("metric", ["rmse", "iae", "apc_w"])
def test_within_factor_2_on_step_and_staircase(ch5_runs, metric):
    for (p, s), r in ratios(ch5_runs, metric, STEPS).items():
        assert 0.5 <= r <= 2.0, (p, s, r)


def test_apc_within_factor_2_on_sine_0125(ch5_runs):
    for r in ratios(ch5_runs, "apc_w", ("ch5_sine_0.125",)).values():
        assert 0.5 <= r <= 2.0


@pytest.mark.parametrize("metric", ["rmse", "iae"])
def test_sine_0125_error_is_cooling_limited(ch5_runs, ch5_found, metric):
    # Not reproduced: ratio above 2. Documented: the error is made at 0 % duty above the
    # reference; where the actuator is not saturated the RMSE is below the dissertation's.
    assert not ch5_found[f"factor2_{metric}"].reproduced
    for s in ("pid", "pipd", "bpid"):
        assert ratios(ch5_runs, metric, ("ch5_sine_0.125",))["ch5_sine_0.125", s] > 2.0
        split = authority_split(ch5_runs["ch5_sine_0.125", s])
        assert split["cooling_share"] > 0.9
        assert split["rmse_unsaturated"] < 1.71


def test_sine_0125_misses_with_the_fast_sheath_node_and_the_whole_sheath_brackets_it(ch5_runs, ch5_found):
    # Evidence for the factor-2 miss: the lumped sheath warms through the run until the wire
    # stays above Mf; with the sheath's whole heat capacity the error falls below the
    # dissertation's, so its figures lie between the two (a slow sheath node is missing)
    mass = sheath_mass_check(ch5_runs, load_params(CH5_PARAMS))
    assert mass["sheath_end_c"] > mass["sheath_start_c"] + 30.0
    assert mass["wire_min_last_quarter_c"] > mass["mf_loaded_c"]
    for metric in ("rmse", "iae"):
        ours = ratios(ch5_runs, metric, ("ch5_sine_0.125",))
        _, _, table, _ = CH5_TABLES[metric]
        for s, v in mass[metric].items():
            assert v / table["ch5_sine_0.125", s] < 1.0 < ours["ch5_sine_0.125", s]
        assert "a two-node sheath" in ch5_found[f"factor2_{metric}"].evidence


def test_overshoot_is_not_the_derivative_filter(ch5_found):
    # N is not printed; no filter from 2 to 100 rad/s brings BPID under 0.05 mm
    # (measured minimum over N: 0.32 mm step, 0.96 mm staircase)
    least = filter_sweep(load_params(CH5_PARAMS))
    assert least["ch5_step"] > 0.05 and least["ch5_staircase"] > 0.05
    assert f"overshoots at least {least['ch5_step']:.2f} mm" in ch5_found["bpid_overshoot"].evidence


def test_overshoot_persists_at_the_dissertations_rise_speed(ch5_runs, ch5_found):
    # Evidence run: the wire refitted to Table 3.2 rises slower (nearer 1.2-1.4 s) but the
    # same BPID still overshoots; four times the load damping removes most of it on the step.
    rc = rate_check()
    assert rc["step_rise_time_s"] > 1.5 * ch5_runs["ch5_step", "bpid"].metrics["rise_time_s"]
    assert rc["step_overshoot"] > 0.05 and rc["staircase_overshoot"] > 0.05
    assert rc["step_overshoot_damped"] < 0.5 * rc["step_overshoot"]
    assert "ch5_straight_40n_table32" in ch5_found["bpid_overshoot"].evidence


def test_table32_set_reproduces_the_short_pulse_row():
    # The refit's reason: displacement after a 1.0 s pulse (Table 3.2: 5.94 mm) within 25 %,
    # where the calibrated set gives almost none.
    rig = characterization_rig(load_params("ch5_straight_40n_table32"), True)
    base = characterization_rig(load_params("ch5_straight_40n"), True)
    short, base_short = pulse_responses([rig, base], [1.0, 1.0], dt=2e-3)
    assert abs(short.max_displacement_m * 1e3 / 5.94 - 1) < 0.25
    assert base_short.max_displacement_m * 1e3 < 1.0
