"""Chapter 5 points on the lockstep runs (docs/experiments.md).

Findings the simulation does not reproduce assert the documented outcome and its evidence.
"""

from __future__ import annotations

import pytest

from hems_ros.experiments.chapters import CH5_PARAMS
from hems_ros.experiments.dissertation import CH5_PROTOCOLS, CH5_RISE_TIME_S
from hems_ros.experiments.findings import (
    authority_split,
    bilinear_activity,
    filter_sweep,
    gain_grid,
    perturbation_spread,
    rate_check,
    ratios,
    repeated_ratios,
    table_4_1_stress_slope,
)
from hems_ros.physics import load_params
from hems_ros.physics.scenarios import characterization_rig, pulse_responses
from hems_ros.reports.findings import MARGIN

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


@pytest.fixture(scope="module")
def spread(ch5_runs):
    return perturbation_spread(ch5_runs, load_params(CH5_PARAMS))


@pytest.mark.parametrize("protocol", STEPS)
def test_bpid_runs_the_pid_loop(ch5_runs, ch5_found, spread, protocol):
    # Not reproduced: BPID clearly highest MACSI / lowest RMSE. With Table 5.1 gains in um
    # the eq. 5.36 factor almost never acts, so BPID and PID differ by no more than two runs
    # of one controller can (each moves by up to the perturbation spread)
    assert not ch5_found["bpid_lowest_rmse"].reproduced
    assert not ch5_found["bpid_highest_macsi"].reproduced
    assert bilinear_activity(ch5_runs[protocol, "bpid"]) < 0.01
    for metric in ("rmse", "macsi"):
        b, p = ch5_runs[protocol, "bpid"].metrics[metric], ch5_runs[protocol, "pid"].metrics[metric]
        assert abs(b - p) <= 2 * spread[metric] * p


def test_a_1e6_degc_change_moves_the_step_cells_by_a_few_per_cent(ch5_found, spread):
    # the run-to-run spread the BPID ranking findings quote (measured 6.0 % RMSE, 4.9 % MACSI):
    # the closed loop does amplify a difference that small
    assert 0.005 < spread["rmse"] < 2 * MARGIN
    assert 0.005 < spread["macsi"] < 2 * MARGIN
    assert (
        f"RMSE of the three controllers by up to {100 * spread['rmse']:.1f} %"
        in ch5_found["bpid_lowest_rmse"].evidence
    )


def test_rmse_within_factor_2_on_sine_0125_step_and_staircase(ch5_runs, ch5_found):
    # Table 5.2 reproduced since the sheath has its helix node (docs/validation.md)
    assert ch5_found["factor2_rmse"].reproduced
    for r in ratios(ch5_runs, "rmse").values():
        assert 0.5 <= r <= 2.0


def test_apc_within_factor_2_on_sine_0125_step_and_staircase(ch5_runs, ch5_found):
    assert ch5_found["factor2_apc_w"].reproduced
    for r in ratios(ch5_runs, "apc_w").values():
        assert 0.5 <= r <= 2.0


def test_iae_misses_are_documented_plant_differences(ch5_runs, ch5_found):
    # Not reproduced for a few cells: above 2 only on the sine, where the error is made at 0 %
    # duty above the reference (cooling-limited); below 0.5 only on the steps, where the model's
    # faster rise makes ours better than the dissertation's
    found = ch5_found["factor2_iae"]
    assert not found.reproduced
    for (p, s), r in ratios(ch5_runs, "iae").items():
        if r > 2.0:
            assert p == "ch5_sine_0.125" and f"{p[4:]}/{s} ({r:.2f})" in found.evidence
            assert authority_split(ch5_runs[p, s])["cooling_share"] > 0.9
        elif r < 0.5:
            assert p in STEPS and f"{p[4:]}/{s} ({r:.2f})" in found.evidence
            assert ch5_runs["ch5_step", s].metrics["rise_time_s"] < 0.5 * CH5_RISE_TIME_S[s]
    assert "rises faster" in found.evidence or "cooling-limited" in found.evidence


def test_iae_misses_over_three_repetitions(ch5_runs, ch5_found):
    # The dissertation averaged three repetitions. With the ambient 0.1 degC lower and higher
    # the sine cell's 2.03 is the worst of three (mean within 2); the staircase cell
    # stays below 0.5.
    rep = repeated_ratios(
        ch5_runs,
        load_params(CH5_PARAMS),
        "iae",
        [("ch5_sine_0.125", "bpid"), ("ch5_staircase", "pid")],
    )
    sine, stair = rep["ch5_sine_0.125", "bpid"], rep["ch5_staircase", "pid"]
    assert sine[1] == pytest.approx(ratios(ch5_runs, "iae")["ch5_sine_0.125", "bpid"])
    assert sine[1] > 2.0 and max(sine[0], sine[2]) < 1.8 and sine[3] < 2.0
    assert max(stair[:3]) < 0.5 and stair[3] == pytest.approx(0.459, abs=0.005)
    assert (
        f"sine_0.125/bpid {sine[0]:.2f}, {sine[1]:.2f}, {sine[2]:.2f} (mean {sine[3]:.2f})"
        in ch5_found["factor2_iae"].evidence
    )


def test_overshoot_is_not_the_derivative_filter(ch5_found):
    # N is not printed; no filter from 2 to 100 rad/s brings BPID under 0.05 mm
    # (measured minimum over N: 0.32 mm step, 0.96 mm staircase)
    least = filter_sweep(load_params(CH5_PARAMS))
    assert least["ch5_step"] > 0.05 and least["ch5_staircase"] > 0.05
    assert f"overshoots at least {least['ch5_step']:.2f} mm" in ch5_found["bpid_overshoot"].evidence


def test_overshoot_is_not_table_5_1s_gains(ch5_found):
    # Over Kp 0.05-0.8 %/um x Kd 0.02-0.5 % s/um the sets that hold the levels within 0.05 mm
    # (the dissertation's steady-state claim) all overshoot; those that do not overshoot droop.
    grid = gain_grid(load_params(CH5_PARAMS))
    step, stair = grid["ch5_step"], grid["ch5_staircase"]
    assert step["holding"][:2] == pytest.approx((0.107, 0.031), abs=2e-3)
    assert stair["holding"][:2] == pytest.approx((0.669, 0.024), abs=2e-3)
    assert step["holding"][0] > 0.05 and stair["holding"][0] > 0.05
    # the least overshoot of any set: within 0.05 mm on the step, not on the staircase, and
    # both far off the 0.05 mm steady-state error
    assert step["least"][0] < 0.05 < stair["least"][0]
    assert step["least"][1] > 0.15 and stair["least"][1] > 0.15
    assert (
        f"overshoot at least {step['holding'][0]:.3f} mm on the step"
        in ch5_found["bpid_overshoot"].evidence
    )


def test_overshoot_persists_at_the_dissertations_rise_speed(ch5_runs, ch5_found):
    # Evidence run: the wire refitted to Table 3.2 rises slower (nearer 1.2-1.4 s) but the
    # same BPID still overshoots; four times the load damping removes most of it on the step.
    rc = rate_check()
    assert rc["step_rise_time_s"] > 1.5 * ch5_runs["ch5_step", "bpid"].metrics["rise_time_s"]
    assert rc["step_overshoot"] > 0.05 and rc["staircase_overshoot"] > 0.05
    assert rc["step_overshoot_damped"] < 0.5 * rc["step_overshoot"]
    assert "ch5_straight_40n_table32" in ch5_found["bpid_overshoot"].evidence


def test_table_4_1_stress_slope_damps_the_overshoot_but_leaves_some(ch5_runs, ch5_found):
    # Evidence run: the smaller C of Table 4.1 lets the mass's swing drive the transformation
    # (damping inside the wire), which cuts the overshoot yet does not bring it to 0.05 mm.
    slope = table_4_1_stress_slope(load_params("ch5_straight_40n"))
    for p in ("ch5_step", "ch5_staircase"):
        assert 0.05 < slope[p] < 0.8 * ch5_runs[p, "bpid"].metrics["overshoot"]
    assert "C_M = C_A = 6.89 MPa/degC" in ch5_found["bpid_overshoot"].evidence


def test_table32_set_reproduces_the_short_pulse_row():
    # The refit's reason: displacement after a 1.0 s pulse (Table 3.2: 5.94 mm) within 25 %,
    # where the calibrated set gives almost none.
    rig = characterization_rig(load_params("ch5_straight_40n_table32"), True)
    base = characterization_rig(load_params("ch5_straight_40n"), True)
    short, base_short = pulse_responses([rig, base], [1.0, 1.0], dt=2e-3)
    assert abs(short.max_displacement_m * 1e3 / 5.94 - 1) < 0.25
    assert base_short.max_displacement_m * 1e3 < 1.0
