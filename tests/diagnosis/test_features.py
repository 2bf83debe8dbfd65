"""Tables of test figures (hems_ros.diagnosis.features): pulse figures the model made itself
are reproduced and explained, the cooling-time rules, and the closed-loop rows against the
lockstep experiments."""

from __future__ import annotations

import math

import numpy as np
import pytest

from hems_ros.diagnosis import dataset, features, localise
from hems_ros.diagnosis.runs import DiagnosisInputError, FeatureRun, FeatureTest
from hems_ros.diagnosis.workflow import diagnose
from hems_ros.experiments.lockstep import run_protocol
from hems_ros.physics.params import load_params

BASE = load_params("table41")
# (pulse s, current A): every row contracts the wire past the 4.5 mm cooled mark
ROWS = [(1.4, 4.0), (1.6, 4.0), (2.0, 3.5), (2.5, 3.5), (1.2, 5.0), (3.0, 3.0)]
SHEATH = {
    "sheath.enabled": True,
    "sheath.heat_capacity_j_per_k": 4.0,
    "sheath.gap_resistance_k_per_w": 2.0,
}


def _table(truth, rows=ROWS, name: str = "pulses") -> FeatureRun:
    shells = [FeatureTest(f"{p:g} s {a:g} A", {"pulse_s": p, "current_a": a}, {}) for p, a in rows]
    figures = features._pulse_figures([truth], shells, features.PULSE_DT)
    tests = tuple(FeatureTest(s.name, s.conditions, f) for s, f in zip(shells, figures))
    return FeatureRun(name, "synthetic", tests)


def test_pulse_figures_of_table_4_1() -> None:
    run = _table(BASE)
    figs = [t.figures for t in run.tests]
    assert all(set(f) == set(features.PULSE_FIGURES) for f in figs)
    peaks = [f["peak_displacement"] for f in figs]
    # more heat, more stroke (1.4 s at 4 A below 1.6 s at 4 A; 1.2 s at 5 A the most)
    assert peaks[0] < peaks[1] and max(peaks) == peaks[4]
    assert all(4.5e-3 < p < 0.038 * 0.9 for p in peaks)
    for f in figs:
        # the bias spring: 12 N + 900 N/m * stroke, plus the damping force while it moves
        assert 0.0 <= f["peak_force"] - (12.0 + 900.0 * f["peak_displacement"]) < 3.0
        assert 1.0 < f["cooling_time"] < features.COOLING_WINDOW_S
    # cooling_time is a whole number of pulse steps
    steps = [f["cooling_time"] / features.PULSE_DT for f in figs]
    assert all(abs(n - round(n)) < 1e-9 for n in steps)


def test_a_table_made_by_the_model_is_matched_by_it() -> None:
    truth = BASE.replace(SHEATH)
    data = features.prepare([_table(truth)], [])
    # every third row from the second selects; six rows are too few to test apart as well
    assert data.split.heldout[0].tolist() == [False, True, False, False, True, False]
    assert data.split.test[0].tolist() == data.split.heldout[0].tolist()
    assert data.split.description.endswith(dataset.NO_TEST)
    nine = features.prepare([_table(truth, ROWS + ROWS[:3])], []).split
    assert nine.heldout[0].tolist() == [False, True, False] * 3
    assert nine.test[0].tolist() == [False, False, True] * 3
    assert data.channels == ["peak_displacement", "peak_force", "cooling_time"] and data.drives == {
        "current"
    }
    own, other = data.predict([truth, BASE])
    assert np.all(own.train == 0.0) and np.all(own.heldout == 0.0)
    assert own.train.size == 12 and own.heldout.size == 6
    # the sheath is a heat sink: the bare wire takes seconds longer to cool on every row
    cooling = [
        o["cooling_time"] - t.figures["cooling_time"]
        for o, (_, t) in zip(other.outputs, data.tests)
    ]
    assert min(cooling) > 2.0
    assert data.headline(other) == "cooling_time"
    rows = {r.group: r for r in localise.table(data, other)}
    unc = [features.uncertainty("cooling_time", t.figures["cooling_time"]) for _, t in data.tests]
    assert rows["cooling_time"].cost == pytest.approx(
        np.mean((np.array(cooling) / unc) ** 2), rel=1e-12
    )
    assert rows["cooling_time"].rms == pytest.approx(
        np.sqrt(np.mean(np.square(cooling))), rel=1e-12
    )
    assert rows["cooling_time"].cost > 200 and rows["cooling_time"].unit == "s"


def test_a_hidden_sheath_is_recovered_from_pulse_figures() -> None:
    d = diagnose([_table(BASE.replace(SHEATH))], [], BASE)
    assert d.verdict == "named"
    assert [c.name for c in d.search.final.structure] == ["sheath_heat_sink"]
    c_s, r_gap = d.search.final.values
    assert c_s == pytest.approx(4.0, rel=0.02) and r_gap == pytest.approx(2.0, rel=0.02)
    # measured on the test rows, which chose nothing
    assert (
        d.gap.metric == "cooling_time" and d.gap.heldout_before > 1.0 and d.gap.heldout_after < 0.02
    )
    assert d.search.final.heldout < 1e-3


@pytest.mark.parametrize(
    "x, end, cooled, seconds",
    [
        (
            [0, 1, 2, 3, 3, 2, 1, 0, 0],
            3,
            1.5,
            3 * 0.5,
        ),  # first sample at or below 1.5 after the pulse
        ([0, 1, 2, 3, 3, 2, 1.5, 0, 0], 3, 1.5, 3 * 0.5),  # "back" includes the cooled mark itself
        ([0, 1, 1.4, 1.5, 1.2, 0], 3, 1.5, 0.0),  # never passed the mark: 0
        ([0, 2, 3, 3, 3, 3], 2, 1.5, 4 * 0.5),  # never back: the rest of the window
        ([0, 3, 1, 0, 0], 2, 1.5, 0.0),  # back before the pulse ended
    ],
)
def test_cooling_time_rules(x, end: int, cooled: float, seconds: float) -> None:
    assert features._cooling_time(np.array(x, dtype=float), end, 0.5, cooled) == pytest.approx(
        seconds
    )


def test_figure_uncertainty_and_a_missing_figure() -> None:
    assert features.uncertainty("peak_force", 20.0) == pytest.approx(1.0)  # 5 %
    assert features.uncertainty("peak_force", 2.0) == 0.5  # the 0.5 N floor
    assert features.uncertainty("cooling_time", -10.0) == pytest.approx(0.5)
    run = _table(BASE, ROWS[:3])
    data = features.prepare([run], [])
    held = data._weighted([{}, {}, {}], np.array([True, True, True]))
    # a figure the model cannot give weighs 1e3 uncertainties
    assert held.tolist() == [1e3] * 9


def test_feature_tables_need_conditions_and_rows() -> None:
    rows = tuple(FeatureTest(f"r{i}", {"energy_j": 1.0}, {"peak_force": 20.0}) for i in range(3))
    bare = FeatureRun("t", "s", rows)
    with pytest.raises(DiagnosisInputError, match="r0: a test needs its conditions"):
        features.prepare([bare], [])
    with pytest.raises(DiagnosisInputError, match="2 test row"):
        features.prepare([_table(BASE, ROWS[:2])], [])
    data = features.prepare([_table(BASE, ROWS[:2])], [_table(BASE, ROWS[2:3], name="other")])
    assert data.split.heldout[0].tolist() == [False, False, True]
    # one held-out row cannot both select and test: the gap is measured on it, and said so
    assert data.split.test[0].tolist() == [False, False, True]
    assert data.split.description.startswith("held-out tables: other")
    assert data.split.description.endswith(dataset.NO_TEST)


@pytest.fixture(scope="module")
def loops():
    base = load_params("ch5_straight_40n")
    sets = [base, base.replace({"load.damping_n_s_per_m": 300.0, "encoder.gain": 1.05}), base]
    return sets, features._loop_figures("ch5_step", "bpid", sets)


def test_closed_loop_rows_are_the_lockstep_figures(loops) -> None:
    sets, figures = loops
    for params, figs in zip(sets, figures):
        ref = run_protocol("ch5_step", "bpid", params).metrics
        for name in ("rmse", "overshoot", "ss_error", "rise_time_s", "apc_w"):
            assert figs[name] == pytest.approx(ref[name], rel=1e-12, abs=1e-12), name
    # the two sets differ (the test could tell a set mixed up with the other)
    assert abs(figures[0]["overshoot"] - figures[1]["overshoot"]) > 0.1
    assert 4.0 < figures[0]["rmse"] < 7.0
    assert figures[2] is figures[0]  # the same set runs once


def test_closed_loop_rows_run_once_per_protocol_and_controller(monkeypatch) -> None:
    calls = []

    def fake(protocol, strategy, sets):
        calls.append((protocol, strategy, len(sets)))
        # figures in the dissertation's units (mm, s, W), one per set; pid leaves out ss_error
        return [
            {
                "rmse": 2.0 + i,
                "overshoot": 0.5,
                "rise_time_s": 0.4,
                "apc_w": 12.0,
                **({} if strategy == "pid" else {"ss_error": 0.01}),
            }
            for i in range(len(sets))
        ]

    monkeypatch.setattr(features, "_loop_figures", fake)
    rows = [
        ("ch5_step", "bpid"),
        ("ch5_step", "pid"),
        ("ch5_step", "bpid"),
        ("ch5_sine_0.25", "bpid"),
    ]
    tests = tuple(
        FeatureTest(f"r{i}", {"protocol": p, "controller": c}, {"rmse": 2e-3})
        for i, (p, c) in enumerate(rows)
    )
    data = features.prepare([FeatureRun("loop", "s", tests)], [])
    assert data.drives == {"duty"}
    figs = data._figures([BASE, BASE])
    assert calls == [("ch5_step", "bpid", 2), ("ch5_step", "pid", 2), ("ch5_sine_0.25", "bpid", 2)]
    assert figs[1][0] == {
        "rmse": 3e-3,
        "overshoot": 0.5e-3,
        "ss_error": 0.01e-3,
        "rise_time": 0.4,
        "mean_power": 12.0,
    }
    assert math.isnan(figs[0][1]["ss_error"]) and figs[0][1]["rmse"] == 2e-3
