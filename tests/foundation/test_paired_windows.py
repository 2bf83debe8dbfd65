"""The idle verdict of benchmarks/bench_graph.py: alternating windows, each set against the
other state's windows beside it, judged against their own spread (benchmarks/paired.py)."""

from __future__ import annotations

import pytest
from benchmark_modules import load

paired = load("paired")


def test_a_steady_drift_cancels_between_neighbours() -> None:
    # equal costs on a host slowing by 0.1 cores a window
    windows = [("idle", 1.0), ("enabled", 1.1), ("idle", 1.2), ("enabled", 1.3), ("idle", 1.4)]
    result = paired.excess(windows, "idle")
    assert result.differences == pytest.approx((-0.1, 0.0, 0.1))
    assert result.mean == pytest.approx(0.0)
    # t(0.975, 2 dof) = 4.303, standard error 0.1 / sqrt(3)
    assert result.allowance == pytest.approx(4.303 * 0.1 / 3**0.5, rel=1e-3)
    assert result.ratio < 1


def test_a_steady_excess_beyond_the_spread_is_costlier() -> None:
    windows = [
        ("idle", 1.05),
        ("enabled", 1.0),
        ("idle", 1.06),
        ("enabled", 1.0),
        ("idle", 1.04),
        ("enabled", 1.01),
        ("idle", 1.05),
    ]
    result = paired.excess(windows, "idle")
    assert result.differences == pytest.approx((0.05, 0.06, 0.035, 0.04))
    assert result.mean == pytest.approx(0.04625)
    assert result.allowance < result.mean
    assert result.ratio > 1
    # the other state judged the same way is cheaper, not costlier
    assert paired.excess(windows, "enabled").ratio < 1


def test_the_enabled_quarters_in_a_row_count_once_beside_each_idle_window() -> None:
    windows = [("idle", 0.5)] + [("enabled", 0.4)] * 3 + [("enabled", 0.7), ("idle", 0.5)]
    assert paired.excess(windows, "idle").differences == pytest.approx((0.1, -0.2))


def test_one_window_of_the_state_gives_no_verdict() -> None:
    with pytest.raises(ValueError, match="at least two idle windows"):
        paired.excess([("idle", 1.0), ("enabled", 1.0)], "idle")
