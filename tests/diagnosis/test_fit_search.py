"""Fitting and selection (hems_ros.diagnosis.fit, search) on short synthetic runs with a known
truth, and the verdict rules on constructed fits."""

from __future__ import annotations

import dataclasses
import math
import re

import numpy as np
import pytest

from hems_ros.diagnosis import candidates as lib
from hems_ros.diagnosis import replay, search, suite
from hems_ros.diagnosis.csvload import load_table
from hems_ros.diagnosis.dataset import noise_floor
from hems_ros.diagnosis.fit import Coordinate, Fit, Space, fit_structures, near_bounds, pinned
from hems_ros.diagnosis.runs import DiagnosisInputError, TimeSeriesRun
from hems_ros.diagnosis.search import Step, _verdict
from hems_ros.diagnosis.workflow import diagnose
from hems_ros.physics.params import load_params
from hems_ros.reports.diagnosis import markdown, summary

BASE = load_params("table41")
# the first 40 s of the suite's pulse train: five pulses, cycle 2 of 4 held out
DUTY = suite.pulse_profile()[:4000]
CASES = {c.name: c for c in suite.CASES}


@pytest.fixture(scope="module")
def damping():
    run = suite.measure(CASES["load_damping"], DUTY, "low", 0, BASE)
    return diagnose([run], [], BASE)


def test_hidden_load_damping_is_named_and_recovered(damping) -> None:
    d = damping
    assert d.verdict == "named"
    assert [c.name for c in d.search.final.structure] == ["load_damping"]
    (b,) = d.search.final.values
    assert b == pytest.approx(400.0, rel=0.02)
    assert d.corrected.load.damping_n_s_per_m == pytest.approx(b, rel=1e-12)
    # the noise floor is the sensors': 2 um noise on 1 um steps, 0.02 N on 0.01 N steps
    assert d.data.sigma["position"] == pytest.approx(2.08e-6, rel=0.1)
    assert d.data.sigma["wire_force"] == pytest.approx(0.0208, rel=0.1)
    # the corrected model matches to the noise on data it was not fitted on
    assert d.search.start.heldout > 1e3 and d.search.final.heldout == pytest.approx(1.0, abs=0.15)
    assert d.gap.metric == "position" and d.gap.heldout_after < 0.01 * d.gap.heldout_before
    # named on the load relation (force against motion), which left nothing to explain
    assert d.search.first_ranked == "load_damping" and d.search.steps == []
    assert not d.search.dropped and not d.search.findings
    # a warm start fits to "absent" (0 degC, its lower bound): on a bound, but not pinned
    [warm] = fit_structures(d.data, BASE, [(lib.BY_NAME["warm_start"],)], {})
    assert warm.values[0] < 1e-3 and warm.pinned == []


def test_the_fits_convergence_is_recorded(damping) -> None:
    final = damping.search.final
    # the replay's refit from the load relation's value (one start), or the relation's own
    # fit (a start at the model's value and one at "absent") where the refit gained nothing
    refined = damping.search.load_relation.refined
    assert final.converged and final.starts == (1 if refined else 2)
    assert 0 < final.evaluations <= 30
    assert summary(damping)["fit"] == {
        "converged": True,
        "stop": final.stop,
        "starts": final.starts,
        "evaluations": final.evaluations,
    }
    # one evaluation allowed: the fit stops at the limit and says so
    [stopped] = fit_structures(
        damping.data, BASE, [(lib.BY_NAME["load_damping"],)], {}, max_evaluations=1
    )
    assert not stopped.converged and "maximum number of function evaluations" in stopped.stop
    unfinished = dataclasses.replace(
        damping,
        search=dataclasses.replace(
            damping.search,
            final=dataclasses.replace(final, converged=False, stop=stopped.stop, evaluations=30),
        ),
    )
    assert (
        "The corrected model's fit (load_damping) stopped after 30 evaluations without meeting "
        "its tolerances" in markdown(unfinished, [])
    )


def test_nothing_hidden_gives_none() -> None:
    run = suite.measure(CASES["nothing"], DUTY, "low", 0, BASE)
    d = diagnose([run], [], BASE)
    assert d.verdict == "none"
    assert d.search.steps == [] and d.search.final.structure == ()
    assert d.search.start.heldout - 1.0 < search.NOTHING
    assert d.corrected == BASE
    assert d.summary_line().startswith("none; held-out position RMSE")


def test_a_truth_beyond_a_bound_is_a_finding_not_an_explanation() -> None:
    # gain 1.4: beyond the +-20 % the encoder_gain candidate allows (upper bound 1.25)
    run = suite.measure(CASES["nothing"], DUTY, "low", 0, BASE.replace({"encoder.gain": 1.4}))
    d = diagnose([run], [], BASE, candidates=["encoder_gain"])
    assert d.search.findings == ["encoder_gain: g_x at its upper bound 1.25"]
    assert d.search.final.structure == () and d.verdict == "unexplained"
    (step,) = d.search.steps
    assert step.chosen is None and step.ranked[0].pinned == d.search.findings
    assert step.ranked[0].values[0] == pytest.approx(1.25, abs=1e-3)
    # the pinned fit is far better than the start: rejected for the bound, not for its cost
    assert step.ranked[0].heldout < 0.2 * d.search.start.heldout
    assert d.corrected == BASE


def test_coordinates_map_bounds_to_the_unit_interval() -> None:
    lin = Coordinate(
        lib.BY_NAME["load_damping"], lib.BY_NAME["load_damping"].parameters[0], 65.0, 3000.0
    )
    assert (lin.value(0.0), lin.value(1.0), lin.value(0.5)) == (65.0, 3000.0, 1532.5)
    sheath = lib.BY_NAME["sheath_heat_sink"]
    log = Coordinate(sheath, sheath.parameters[0], 0.2, 30.0)
    assert log.value(0.5) == pytest.approx(math.sqrt(0.2 * 30.0), rel=1e-12)
    for c in (lin, log):
        for u in (0.0, 0.3, 1.0):
            assert c.unit(c.value(u)) == pytest.approx(u, abs=1e-12)


def test_space_builds_models_and_rejects_impossible_ones() -> None:
    space = Space(BASE, (lib.BY_NAME["heating_temperatures"], lib.BY_NAME["warm_start"]))
    assert space.size == 2
    m = space.params(np.array([0.5, 0.0]))
    assert (m.kinetics.as0_c, m.kinetics.af0_c, m.start.temperature_offset_c) == (85.0, 95.0, 0.0)
    # As0 60 with the warmest start (61 degC above 22): no martensite to start from
    assert space.params(np.array([0.0, 1.0])) is None
    # outside [0, 1] the values are clipped onto the bounds
    assert space.values(np.array([-1.0, 2.0])).tolist() == [60.0, 61.0]


def test_pinned_means_a_bound_away_from_where_the_candidate_is_absent() -> None:
    friction = Space(BASE, (lib.BY_NAME["tendon_friction"],))
    assert pinned(friction, np.array([0.0])) == []
    assert pinned(friction, np.array([0.999])) == ["tendon_friction: F_c at its upper bound 10 N"]
    assert pinned(friction, np.array([0.99])) == []
    gain = Space(BASE, (lib.BY_NAME["encoder_gain"],))
    assert pinned(gain, np.array([0.0])) == ["encoder_gain: g_x at its lower bound 0.8"]
    damping = Space(BASE, (lib.BY_NAME["load_damping"],))  # lower bound: the model's 65 N s/m
    assert pinned(damping, np.array([0.0])) == []


def _fit(names: tuple[str, ...], train: float, heldout: float, pinned=()) -> Fit:
    structure = tuple(lib.BY_NAME[n] for n in names)
    n = sum(len(c.parameters) for c in structure)
    return Fit(structure, np.zeros(n), BASE, train, heldout, 1000, list(pinned))


START = _fit((), 50.0, 40.0)


@pytest.mark.parametrize(
    "start_heldout, spread, verdict",
    [
        (1.0, 0.0, "none"),
        (1.2, 0.0, "none"),
        (1.21, 0.0, "unexplained"),
        (0.8, 0.0, "none"),
        (40.0, 0.0, "unexplained"),
        # a floor whose estimate spreads 0.3 in log: up to 1.2 e^(1.645 x 0.3) = 1.96 is noise
        (1.95, 0.3, "none"),
        (1.97, 0.3, "unexplained"),
    ],
)
def test_verdict_without_terms(start_heldout: float, spread: float, verdict: str) -> None:
    start = _fit((), 50.0, start_heldout)
    assert _verdict(start, start, [], spread) == verdict


def test_verdict_with_terms() -> None:
    # start 40: excess sqrt(39) = 6.24; explained when the final's excess is at most half of it
    half = 1.0 + (0.5 * math.sqrt(39.0)) ** 2  # 10.75
    damping = _fit(("load_damping",), 1.0, 1.0)
    assert _verdict(START, damping, [Step([damping], damping, [])], 0.0) == "named"
    worse = _fit(("load_damping",), 1.0, half + 0.01)
    assert _verdict(START, worse, [Step([worse], worse, [])], 0.0) == "unexplained"
    edge = _fit(("load_damping",), 1.0, half - 1e-9)
    assert _verdict(START, edge, [Step([edge], edge, [])], 0.0) == "named"
    recal = _fit(("ambient", "convection"), 1.0, 1.1)
    assert _verdict(START, recal, [], 0.0) == "recalibrated"
    mixed = _fit(("ambient", "load_damping"), 1.0, 1.1)
    assert _verdict(START, mixed, [], 0.0) == "named"


def test_verdict_ambiguous_only_for_a_named_effect_with_rivals() -> None:
    damping = _fit(("load_damping",), 1.0, 1.0)
    friction = _fit(("tendon_friction",), 1.02, 1.0)
    assert (
        _verdict(START, damping, [Step([damping, friction], damping, [friction])], 0.0)
        == "ambiguous"
    )
    # the rival's step chose a term the elimination dropped again: the final is not ambiguous
    both = _fit(("warm_start",), 1.0, 1.0)
    assert _verdict(START, both, [Step([damping, friction], damping, [friction])], 0.0) == "named"
    # a step that chose nothing has no rivals that count
    steps = [Step([damping], damping, []), Step([friction], None, [friction])]
    assert _verdict(START, damping, steps, 0.0) == "named"


def test_better_needs_held_out_gain_training_share_material_bic_and_no_bound() -> None:
    current = _fit((), 11.0, 5.0)
    good = _fit(("load_damping",), 1.0, 1.0)
    assert search._better(good, current, current)
    assert not search._better(
        _fit(("load_damping",), 1.0, 5.0 - search.MIN_GAIN / 2), current, current
    )  # half the held-out gain asked for
    assert not search._better(
        _fit(("load_damping",), 8.5, 1.0), current, current
    )  # 25 % of the 10 left
    assert search._better(_fit(("load_damping",), 7.9, 1.0), current, current)  # 31 %
    assert not search._better(_fit(("load_damping",), 1.0, 1.0, ["pinned"]), current, current)
    # BIC: one parameter costs ln(1000) = 6.9 against 1000 ln(train ratio)
    near = _fit(("load_damping",), 0.999 * 1.0, 1.0)
    flat = _fit((), 1.0, 3.0)
    assert not search._better(near, flat, flat) and search._better(
        _fit(("load_damping",), 0.99, 1.0), flat, flat
    )
    # material: the starting model left an excess RMS of 99 noise floors (cost 9802); a second
    # term that takes the held-out cost from 901 (excess 30) to 626 (excess 25) removes 5 % of
    # it, one that takes it to 2 (excess 1) 29 %
    start = _fit((), 9802.0, 9802.0)
    first = _fit(("supply_sag",), 100.0, 901.0)
    assert search.MATERIAL > 0.05
    assert not search._better(_fit(("supply_sag", "spring_stiffening"), 40.0, 626.0), first, start)
    assert search._better(_fit(("supply_sag", "spring_stiffening"), 40.0, 2.0), first, start)
    # the load relation's own thresholds, its gains an order of magnitude smaller
    assert search.RELATION_MIN_GAIN < search.MIN_GAIN
    assert search._better_on_relation(
        _fit(("load_damping",), 1.0, 5.0 - search.MIN_GAIN / 2), current, current
    )


def _thermal_truth(start_c: float, wander: float = 0.0) -> TimeSeriesRun:
    """Three thermal cycles at 150 MPa (``wander``: the frame's stress swings by that share
    of it, with a 37 s period) of a wire whose As0 is 4 degC above the model's."""
    one = np.r_[np.arange(start_c, 140.0), np.arange(140.0, start_c, -1.0)]
    temps = np.r_[np.tile(one, 3), start_c]
    t = np.arange(temps.size) * 1.0
    stress = 150e6 * (1.0 + wander * np.sin(2 * np.pi * t / 37.0))
    shell = TimeSeriesRun(
        "tc",
        "synthetic",
        "thermal_cycle",
        t,
        "temperature",
        temps,
        {"strain": t * 0},
        stress_pa=float(stress[0]),
        stress_values=stress if wander else None,
    )
    truth = BASE.replace({"kinetics.as0_c": 92.0, "kinetics.af0_c": 102.0})
    strain = replay.replay(replay.plan(shell), [truth])["strain"][0]
    strain = strain + np.random.default_rng(0).normal(0.0, 2e-5, t.size)
    return dataclasses.replace(shell, outputs={"strain": strain})


def test_thermal_cycle_recalibrates_as0() -> None:
    d = diagnose([_thermal_truth(40.0)], [], BASE, candidates=["heating_temperatures"])
    assert d.verdict == "recalibrated"
    assert d.search.final.values[0] == pytest.approx(92.0, abs=0.3)


def test_thermal_cycle_starting_inside_the_as0_bounds() -> None:
    d = diagnose([_thermal_truth(65.0)], [], BASE, candidates=["heating_temperatures"])
    assert d.verdict == "recalibrated"


def test_thermal_cycle_whose_stress_wanders_15_percent_loads_and_diagnoses(tmp_path) -> None:
    truth = _thermal_truth(40.0, wander=0.15)
    table = np.column_stack(
        [truth.time, truth.drive_values, 100 * truth.outputs["strain"], truth.stress_values / 1e6]
    )
    path = tmp_path / "frame.csv"
    np.savetxt(path, table, delimiter=",", header="t,T,eps,sigma", comments="", fmt="%.9g")
    run = load_table(path, "time=t:s,temperature=T,strain=eps:%,stress=sigma:MPa")
    assert run.stress_values.min() == pytest.approx(127.5e6, rel=1e-3)
    assert run.stress_values.max() == pytest.approx(172.5e6, rel=1e-3)
    d = diagnose([run], [], BASE, candidates=["heating_temperatures"])
    assert d.verdict == "recalibrated"
    assert d.search.final.values[0] == pytest.approx(92.0, abs=0.3)
    # the same strains read as if the frame had held its mean stress: the fit cannot make
    # them up with As0 alone
    held = dataclasses.replace(run, stress_pa=150e6, stress_values=None)
    assert diagnose([held], [], BASE, candidates=["heating_temperatures"]).verdict == "unexplained"


def _frame_table(path, t, drive: str, heating, strain, preload_pa: float, truth, seed: int):
    """A frame's run of ``truth`` written as a lab table (force with 0.05 N of noise) and read
    back: ``drive`` (current in A or temperature in degC) and the strain in, the force out."""
    shell = TimeSeriesRun(
        "frame",
        "synthetic",
        "prescribed_strain",
        t,
        drive,
        heating,
        {"wire_force": t * 0},
        stress_pa=preload_pa,
        strain_values=strain,
    )
    force = replay.replay(replay.plan(shell), [truth])["wire_force"][0]
    assert 0.0 < force.min()  # in tension throughout
    force = force + np.random.default_rng(seed).normal(0.0, 0.05, t.size)
    table = np.column_stack([t, heating, 100 * strain, force])
    np.savetxt(path, table, delimiter=",", header="t,H,eps,F", comments="", fmt="%.9g")
    unit = "A" if drive == "current" else "degC"
    return load_table(
        path,
        f"time=t:s,{drive}=H:{unit},prescribed_strain=eps:%,wire_force=F:N",
        cross_section_m2=BASE.wire.cross_section_m2,
    )


def test_work_loop_in_a_frame_names_a_hidden_sheath(tmp_path) -> None:
    # a frame shortens the wire by 0.5 % and lets it back at 0.1 Hz from a 200 MPa preload,
    # 2.5 A while it shortens; the wire was in a Bowden sheath the model does not have
    t = np.arange(0.0, 40.0, 0.01)
    strain = -0.0025 * (1 - np.cos(2 * np.pi * 0.1 * t))
    current = np.where((np.sin(2 * np.pi * 0.1 * t) > 0) & (t >= 1.0), 2.5, 0.0)
    truth = BASE.replace({"sheath.enabled": True})
    run = _frame_table(tmp_path / "loop.csv", t, "current", current, strain, 200e6, truth, 1)
    assert 14.0 < run.outputs["wire_force"].min() and run.outputs["wire_force"].max() < 42.0
    d = diagnose([run], [], BASE)
    assert d.verdict == "named"
    assert [c.name for c in d.search.final.structure] == ["sheath_heat_sink"]
    capacity, gap = d.search.final.values
    assert capacity == pytest.approx(truth.sheath.heat_capacity_j_per_k, rel=0.05)
    assert gap == pytest.approx(truth.sheath.gap_resistance_k_per_w, rel=0.05)


def test_a_chamber_heated_wire_in_a_frame_recalibrates_as0(tmp_path) -> None:
    """A frame cycles the strain (0.2 % every 30 s) from a 150 MPa preload while a chamber
    takes the wire from 30 to 120 degC and back three times in 300 s: temperature in, force
    out. The wire's austenite band lies 4 degC above the model's."""
    t = np.arange(0.0, 300.0, 0.1)
    temperature = 75.0 - 45.0 * np.cos(2 * np.pi * t / 100.0)
    strain = -0.001 * (1 - np.cos(2 * np.pi * t / 30.0))
    truth = BASE.replace({"kinetics.as0_c": 92.0, "kinetics.af0_c": 102.0})
    path = tmp_path / "chamber.csv"
    run = _frame_table(path, t, "temperature", temperature, strain, 150e6, truth, 2)
    assert run.kind == "prescribed_strain" and run.drive == "temperature"
    d = diagnose([run], [], BASE, candidates=["heating_temperatures"])
    assert d.verdict == "recalibrated"
    assert d.search.final.values[0] == pytest.approx(92.0, abs=0.5)


def _damped_with_ripple(amplitude_m: float):
    """150 N s/m of damping and an encoder ripple of ``amplitude_m`` over a 2 mm pole pitch,
    diagnosed with the damping candidate alone."""
    case = suite.Case(
        "damped_ripple",
        "outside",
        (),
        {"load.damping_n_s_per_m": 150.0},
        distortion=lambda t, x, f: (x + amplitude_m * np.sin(2 * np.pi * x / 2e-3), f),
    )
    return diagnose(
        [suite.measure(case, DUTY, "low", 0, BASE)], [], BASE, candidates=["load_damping"]
    )


def test_a_partly_explained_run_does_not_say_no_candidate_helped() -> None:
    # 150 N s/m of damping (the candidate fits it) and a 0.3 mm encoder ripple (nothing fits it)
    d = _damped_with_ripple(0.3e-3)
    assert d.verdict == "unexplained" and [n["effect"] for n in d.named()] == ["load_damping"]
    assert "not removed by any candidate" not in d.summary_line()


def test_a_named_effect_that_leaves_phases_above_the_noise_is_partial() -> None:
    # 150 N s/m of damping and a 0.1 mm encoder ripple: the damping removes 73 % of the
    # held-out gap, the ripple stays at 10-26 times the 2 um noise in every phase
    d = _damped_with_ripple(0.1e-3)
    assert (d.search.verdict, d.verdict) == ("named", "partial")
    assert d.search.final.values[0] == pytest.approx(150.0, rel=0.03)
    assert {"transformation", "cooling", "rest"} <= set(d.left)
    assert min(d.left.values()) > 2.0
    assert re.match(
        r"partial: load_damping \(b = 1[45]\d N s/m \[[\d.]+, [\d.]+\]\); "
        r"left above 2x the noise: .*cooling \(\d+x\)",
        d.summary_line(),
    )
    assert summary(d)["left_above_noise"] == d.left and summary(d)["verdict"] == "partial"


def test_a_wire_outside_the_librarys_band_recalibrates_within_bounds_around_its_model() -> None:
    """A low-temperature alloy: its datasheet's As0 (50 degC) lies below the library's NiTi
    range (60-110 degC), the wire's own is 44. The library's range cannot reach it; a range
    around the starting model can."""
    user = load_params("table41").replace(
        {
            "kinetics.as0_c": 50.0,
            "kinetics.af0_c": 60.0,
            "kinetics.ms0_c": 40.0,
            "kinetics.mf0_c": 30.0,
        }
    )
    case = suite.Case(
        "low_alloy", "parameter", (), {"kinetics.as0_c": 44.0, "kinetics.af0_c": 54.0}
    )
    run = suite.measure(case, suite.pulse_profile()[:4000], "low", 0, user)
    library_only = diagnose([run], [], user, candidates=["heating_temperatures"])
    assert library_only.search.verdict == "unexplained"
    assert library_only.corrected.kinetics.as0_c == 50.0
    around = diagnose(
        [run],
        [],
        user,
        candidates=["heating_temperatures"],
        bounds={"kinetics.as0_c": {"around_model": [15, 15]}},
    )
    assert around.search.verdict == "recalibrated"
    assert around.corrected.kinetics.as0_c == pytest.approx(44.0, abs=0.2)
    assert around.summary_line().startswith("recalibrated: As0 = 44 degC")
    with pytest.raises(DiagnosisInputError, match=r"--bounds: kinetics.as0_c: the starting model"):
        diagnose([run], [], user, bounds={"kinetics.as0_c": [60, 110]})


def test_a_value_near_a_bound_is_named_in_the_summary_line() -> None:
    """As0 recalibrated to 62 degC, 4 % of its 60-110 range above the lower bound."""
    case = suite.Case("as0_low", "parameter", (), {"kinetics.as0_c": 62.0, "kinetics.af0_c": 72.0})
    run = suite.measure(case, suite.pulse_profile()[:4000], "low", 0, BASE)
    d = diagnose([run], [], BASE, candidates=["heating_temperatures"])
    assert d.verdict == "recalibrated"
    [near] = d.near_bounds()
    assert re.fullmatch(r"As0 = 62(\.0\d)? degC within 5% of its lower bound 60 degC", near)
    assert d.summary_line().endswith("; " + near)
    # a value well inside its range is not named
    inside = dataclasses.replace(d.search.final, values=np.array([85.0]))
    assert near_bounds(BASE, inside) == []


def _recorded_one_period_late(run: TimeSeriesRun) -> TimeSeriesRun:
    """The run as a logger records it that stamps each input sample with the end of the
    period it held (the past 10 ms): every record one period after what the wire received."""
    late = np.concatenate([run.drive_values[:1], run.drive_values[:-1]])
    return dataclasses.replace(run, drive_values=late)


def _current_run(params, seed: int) -> TimeSeriesRun:
    """The model driven by 3 A pulses logged at 100 Hz, read with 2 um and 0.02 N noise."""
    time = np.arange(4000) * 0.01
    current = np.where((time % 8.0 >= 0.5) & (time % 8.0 < 1.7), 3.0, 0.0)
    blank = TimeSeriesRun(
        "current_pulses",
        "test",
        "driven",
        time,
        "current",
        current,
        {"position": np.zeros(time.size), "wire_force": np.zeros(time.size)},
    )
    truth = replay.replay(replay.plan(blank), [params])
    rng = np.random.default_rng(seed)
    outputs = {
        "position": truth["position"][0] + rng.normal(0.0, 2e-6, time.size),
        "wire_force": truth["wire_force"][0] + rng.normal(0.0, 0.02, time.size),
    }
    return dataclasses.replace(blank, outputs=outputs)


@pytest.mark.parametrize("drive", ["duty", "current"])
def test_a_late_input_record_is_named_as_timing_not_physics(drive: str) -> None:
    """The starting model is the truth; only the input's record is a period late."""
    run = (
        suite.measure(CASES["nothing"], DUTY, "low", 0, BASE)
        if drive == "duty"
        else _current_run(BASE, 0)
    )
    assert diagnose([run], [], BASE).verdict == "none"
    d = diagnose([_recorded_one_period_late(run)], [], BASE)
    assert d.verdict == "timing"
    assert d.timing()["accepted_s"] == pytest.approx(-0.010, abs=3e-4)
    assert d.summary_line().startswith(
        "timing: the input reaches the wire 10 ms before its record; no physics changed; "
    )
    # no physics moved: the corrected model is the starting one but for the input's timing
    assert d.corrected.replace({"drive.input_delay_s": 0.0}) == BASE
    assert d.search.final.heldout == pytest.approx(1.0, abs=0.15)
    assert summary(d)["timing"]["range_s"] == pytest.approx([-0.03, 0.03])
    assert summary(d)["timing"]["accepted_s"] == pytest.approx(-0.010, abs=3e-4)
    assert "-10 ms, taken into the corrected model" in markdown(d, [])
    narrow = diagnose([_recorded_one_period_late(run)], [], BASE, timing_range_s=0.004)
    assert narrow.timing()["range_s"] == pytest.approx([-0.004, 0.004])
    assert narrow.verdict != "timing"


def _ar1(rng, n: int, rho: float, sd: float) -> np.ndarray:
    """AR(1) noise of deviation ``sd``: a sensor's low-pass filter sampled faster than it."""
    e = np.zeros(n)
    shocks = rng.standard_normal(n) * sd * np.sqrt(1.0 - rho**2)
    e[0] = rng.standard_normal() * sd
    for k in range(1, n):
        e[k] = rho * e[k - 1] + shocks[k]
    return e


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_a_late_record_under_coloured_noise_is_timing_not_physics(seed: int) -> None:
    """The starting model as truth, its current recorded a period late, read through noise
    correlated at rho 0.9 from sample to sample (2 um, 0.02 N)."""
    run = _current_run(BASE, 0)
    truth = replay.replay(replay.plan(run), [BASE])
    rng = np.random.default_rng(100 + seed)
    outputs = {
        "position": truth["position"][0] + _ar1(rng, run.time.size, 0.9, 2e-6),
        "wire_force": truth["wire_force"][0] + _ar1(rng, run.time.size, 0.9, 0.02),
    }
    d = diagnose([_recorded_one_period_late(dataclasses.replace(run, outputs=outputs))], [], BASE)
    assert d.verdict == "timing"
    assert d.timing()["accepted_s"] == pytest.approx(-0.010, abs=5e-4)
    assert d.corrected.replace({"drive.input_delay_s": 0.0}) == BASE


def test_the_starting_model_under_noise_as_coloured_as_rho_0_9_is_at_the_noise() -> None:
    """No lag, no effect: the noise floor read under AR(1) noise at rho 0.9 strays 0.6-1.5
    times the truth from draw to draw; the verdict allows for what its spread from cycle to
    cycle says, so the perfect model is `none` in nearly every draw and never names physics."""
    run = _current_run(BASE, 0)
    truth = replay.replay(replay.plan(run), [BASE])
    verdicts = []
    for seed in range(10):
        rng = np.random.default_rng(100 + seed)
        outputs = {
            "position": truth["position"][0] + _ar1(rng, run.time.size, 0.9, 2e-6),
            "wire_force": truth["wire_force"][0] + _ar1(rng, run.time.size, 0.9, 0.02),
        }
        d = diagnose([dataclasses.replace(run, outputs=outputs)], [], BASE)
        verdicts.append(d.verdict)
        assert d.corrected == BASE
        assert d.data.cost_spread > 0.1
    assert verdicts.count("none") >= 8, verdicts


@pytest.mark.parametrize("rho, low, high", [(0.0, 0.95, 1.05), (0.53, 0.85, 1.15)])
def test_the_noise_floor_counts_coloured_noise_whole(rho: float, low: float, high: float) -> None:
    for seed in range(4):
        noise = _ar1(np.random.default_rng(seed), 4000, rho, 1.0)
        assert low < noise_floor(noise, 0.0, "position") / noise.std() < high


def test_a_physical_change_is_not_taken_for_timing() -> None:
    """As0 4 degC higher delays the stroke too; the timing cannot explain it and is not kept."""
    case = suite.Case(
        "as0_high", "parameter", (), {"kinetics.as0_c": 92.0, "kinetics.af0_c": 102.0}
    )
    d = diagnose([suite.measure(case, DUTY, "low", 0, BASE)], [], BASE)
    assert d.verdict == "recalibrated" and d.timing()["accepted_s"] is None
    assert d.corrected.kinetics.as0_c == pytest.approx(92.0, abs=0.2)
    assert d.timing()["estimate_s"] is not None  # estimated all the same, in the first step
