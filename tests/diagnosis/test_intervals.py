"""95 % intervals of the corrected values: coverage on hidden truths, the effective sample
count of a correlated residual, pairs the data cannot tell apart, and how they are reported."""

from __future__ import annotations

import re

import numpy as np
import pytest

from hems_ros.diagnosis import intervals, suite
from hems_ros.diagnosis.workflow import diagnose
from hems_ros.physics.params import load_params
from hems_ros.reports.diagnosis import summary

BASE = load_params("table41")
DUTY = suite.pulse_profile()[:4000]
CASES = {c.name: c for c in suite.CASES}


@pytest.mark.parametrize("rho", [0.0, 0.5, 0.9])
def test_an_ar1_residual_counts_its_independent_samples(rho: float) -> None:
    rng = np.random.default_rng(3)
    e = np.zeros(200_000)
    shocks = rng.standard_normal(e.size)
    for k in range(1, e.size):
        e[k] = rho * e[k - 1] + shocks[k]
    assert intervals.independence(e) == pytest.approx((1 - rho) / (1 + rho), abs=0.01)


@pytest.mark.parametrize("noise", ["low", "high"])
def test_the_hidden_damping_lies_in_its_interval(noise: str) -> None:
    case = CASES["load_damping"]
    d = diagnose([suite.measure(case, DUTY, noise, 1, BASE)], [], BASE)
    assert d.verdict == "named"
    low, high = d.intervals.of("load.damping_n_s_per_m")
    assert low < case.recover["load.damping_n_s_per_m"] < high
    assert 0.0 < high - low < 0.02 * case.recover["load.damping_n_s_per_m"]
    [named] = summary(d)["named"]
    entry = named["parameters"]["load.damping_n_s_per_m"]
    assert (entry["si_lower"], entry["si_upper"]) == (low, high)
    assert re.match(r"named: load_damping \(b = 400 N s/m \[[\d.]+, [\d.]+\]\)", d.summary_line())


def test_both_sheath_values_lie_in_their_intervals_with_their_correlation() -> None:
    case = CASES["sheath_heat_sink"]
    d = diagnose([suite.measure(case, DUTY, "mid", 0, BASE)], [], BASE)
    for key, truth in case.recover.items():
        low, high = d.intervals.of(key)
        assert low <= truth <= high, (key, low, high)
    r = d.intervals.correlation
    assert r.shape == (2, 2) and np.allclose(r, r.T) and np.allclose(np.diag(r), 1.0)
    assert abs(r[0, 1]) < intervals.UNIDENTIFIABLE and d.intervals.unidentifiable() == []


def test_pairs_beyond_095_are_not_separately_identifiable() -> None:
    iv = intervals.Intervals(
        ("a", "b", "c"),
        np.zeros(3),
        -np.ones(3),
        np.ones(3),
        np.array([[1.0, 0.97, 0.1], [0.97, 1.0, -0.96], [0.1, -0.96, 1.0]]),
        100,
        50.0,
    )
    assert iv.unidentifiable() == [("a", "b", 0.97), ("b", "c", -0.96)]


def test_nothing_fitted_has_no_intervals() -> None:
    d = diagnose([suite.measure(CASES["nothing"], DUTY, "low", 0, BASE)], [], BASE)
    assert d.verdict == "none" and d.intervals is None and summary(d)["intervals"] is None
