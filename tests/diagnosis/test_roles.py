"""Three roles of the data: the fit, the selection of terms, and a test that chose nothing."""

from __future__ import annotations

import numpy as np
import pytest

from hems_ros.diagnosis import dataset, suite
from hems_ros.diagnosis.workflow import diagnose
from hems_ros.physics.params import load_params

BASE = load_params("table41")
CASE = {c.name: c for c in suite.CASES}["load_damping"]


@pytest.fixture(scope="module")
def runs():
    fitted, held = suite.profile("pulses", BASE)
    return (
        suite.measure(CASE, fitted, "low", 0, BASE, "fitted"),
        suite.measure(CASE, held, "low", 0, BASE, "held"),
    )


def _disjoint_and_whole(split: dataset.Split) -> None:
    for train, select, test in zip(split.train, split.heldout, split.test):
        roles = train.astype(int) + select.astype(int) + test.astype(int)
        assert np.all(roles == 1)


def test_a_held_out_run_selects_on_its_odd_cycles_and_tests_on_its_even_ones(runs) -> None:
    fitted, held = runs
    data = dataset.prepare([fitted], [held])
    _disjoint_and_whole(data.split)
    assert data.split.train[0].all() and not data.split.train[1].any()
    seg = data.segments[1]
    assert seg.n_cycles == 5
    assert sorted(set(seg.cycle[data.split.heldout[1]])) == [0, 2, 4]
    assert sorted(set(seg.cycle[data.split.test[1]])) == [1, 3]


def test_a_long_run_gets_a_test_of_its_own_and_a_short_one_says_it_has_none(runs) -> None:
    fitted, held = runs
    long = suite.measure(
        CASE, np.concatenate([suite.profile("pulses", BASE)[1]] * 3), "low", 0, BASE, "long"
    )
    data = dataset.prepare([long], [])
    _disjoint_and_whole(data.split)
    seg = data.segments[0]
    assert seg.n_cycles >= 8
    assert sorted(set(seg.cycle[data.split.heldout[0]])) == list(range(1, seg.n_cycles, 3))
    assert sorted(set(seg.cycle[data.split.test[0]])) == list(range(2, seg.n_cycles, 3))
    short = dataset.prepare([fitted], []).split
    assert all((s == t).all() for s, t in zip(short.heldout, short.test))
    assert short.description.endswith(dataset.NO_TEST)


def test_the_gap_is_measured_on_the_test_cycles(runs) -> None:
    fitted, held = runs
    d = diagnose([fitted], [held], BASE)
    assert d.verdict == "named"
    start, corrected = d.predictions["start"], d.predictions["corrected"]
    scale = 1e3  # position in mm
    assert d.gap.metric == "position"
    assert d.gap.heldout_before == pytest.approx(d.data.rmse(start, "position", "test") * scale)
    assert d.gap.heldout_after == pytest.approx(d.data.rmse(corrected, "position", "test") * scale)
    assert d.gap.heldout_before != pytest.approx(
        d.data.rmse(start, "position", "heldout") * scale, rel=1e-3
    )
