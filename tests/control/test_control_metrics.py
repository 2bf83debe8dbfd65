"""Figures of merit against hand-computed values."""

import math

import numpy as np
import pytest

from hems_ros.control import metrics as m


def test_rmse_iae_on_a_short_record():
    t = [0.0, 0.5, 1.0, 1.5]
    r = [0.0, 1.0, 2.0, 3.0]
    y = [0.0, 0.0, 1.0, 4.0]
    # e = 0, 1, 1, -1
    assert m.rmse(r, y) == pytest.approx(math.sqrt(3 / 4))
    assert m.rmse(r, y, mask=[False, True, True, False]) == pytest.approx(1.0)
    assert math.isnan(m.rmse(r, y, mask=[False] * 4))
    assert m.iae_sum(r, y) == pytest.approx(3.0)
    assert m.iae_sum(r, y, scale=1e3) == pytest.approx(3000.0)
    # trapezoid: (0 + 1)/2 * 0.5 + (1 + 1)/2 * 0.5 + (1 + 1)/2 * 0.5
    assert m.iae_integral(t, r, y) == pytest.approx(0.25 + 0.5 + 0.5)


def test_macsi_and_apc():
    # |10 - 0|, |5 - 10|, |5 - 5| -> mean 5
    assert m.macsi([0, 10, 5, 5]) == pytest.approx(5.0)
    # sqrt(mean(u^2)) = sqrt(10000 / 4) = 50 -> 0.5 * 4^2 * 4.2
    assert m.apc([0, 0, 0, 100]) == pytest.approx(33.6)
    assert m.apc([100, 100]) == pytest.approx(67.2)
    assert m.apc([100, 100], current=2.0, resistance=3.6) == pytest.approx(14.4)


def test_unequal_lengths_rejected():
    with pytest.raises(ValueError):
        m.rmse([0, 1], [0, 1, 2])


def test_step_segments_skip_ramps():
    assert m.step_segments([0, 0, 1, 1, 1, 0, 0]) == [
        m.StepSegment(2, 5, 0.0, 1.0),
        m.StepSegment(5, 7, 1.0, 0.0),
    ]
    assert m.step_segments([0, 1, 2, 3, 3, 3]) == []


def test_step_figures_up():
    t = np.arange(8) * 0.1
    r = [0, 0, 1, 1, 1, 1, 1, 1]
    y = [0, 0, 0.05, 0.1, 0.5, 0.9, 1.05, 1.0]
    (seg,) = m.step_segments(r)
    # 10 % first reached at k = 3 (t 0.3), 90 % at k = 5 (t 0.5)
    assert m.rise_time(t, y, seg) == pytest.approx(0.2)
    assert m.overshoot(y, seg) == pytest.approx(0.05)
    # last 0.15 s: k = 6, 7 -> |mean(-0.05, 0)| = 0.025
    assert m.steady_state_error(t, r, y, seg, window=0.15) == pytest.approx(0.025)


def test_step_figures_down_and_not_reached():
    t = np.arange(8) * 0.1
    r = [1, 1, 0, 0, 0, 0, 0, 0]
    y = [1, 1, 0.95, 0.5, 0.05, -0.02, 0, 0]
    (seg,) = m.step_segments(r)
    # progress 1 - y: 10 % at k = 3, 90 % at k = 4
    assert m.rise_time(t, y, seg) == pytest.approx(0.1)
    assert m.overshoot(y, seg) == pytest.approx(0.02)
    assert math.isnan(m.rise_time(t, [1, 1, 0.95, 0.9, 0.8, 0.7, 0.6, 0.5], seg))
    assert m.overshoot([1, 1, 0.95, 0.9, 0.8, 0.7, 0.6, 0.5], seg) == 0.0


def test_overshoot_is_the_first_peak_and_hold_excursion_the_largest():
    r = [0, 0, 1, 1, 1, 1, 1, 1, 1, 1]
    # reaches the level at k = 3, peaks 0.04 over it, back short at k = 5; a later ripple of 0.07
    y = [0, 0, 0.6, 1.0, 1.04, 0.99, 1.0, 1.07, 0.98, 1.0]
    (seg,) = m.step_segments(r)
    assert m.overshoot(y, seg) == pytest.approx(0.04)
    assert m.hold_excursion(y, seg) == pytest.approx(0.07)
    # never back short of the level (held there): the whole rest of the segment counts
    held = [0, 0, 0.6, 1.0, 1.04, 1.02, 1.08, 1.05, 1.03, 1.01]
    assert m.overshoot(held, seg) == pytest.approx(0.08) == m.hold_excursion(held, seg)
    # downward: the first dip below 0 counts, the later one does not
    (down,) = m.step_segments([1, 1, 0, 0, 0, 0, 0])
    y_down = [1, 1, 0.2, -0.03, 0.01, -0.05, 0.0]
    assert m.overshoot(y_down, down) == pytest.approx(0.03)
    assert m.hold_excursion(y_down, down) == pytest.approx(0.05)
    assert m.overshoot([1, 1, 0.5, 0.2, 0.1, 0.1, 0.1], down) == 0.0


def test_ascending_mask():
    assert m.ascending_mask([0, 1, 1, 0.5, 2]).tolist() == [False, True, False, False, True]


def test_stationary_mask():
    t = np.arange(10.0)
    r = [0, 0, 0, 1, 1, 1, 1, 1, 1, 1]
    # constant since the start (k 0) or the jump (k 3) for >= 3 s: k >= 6
    assert m.stationary_mask(t, r, settle=3.0).tolist() == [False] * 6 + [True] * 4
    r = [0, 0, 0, 1, 1, 1, 1, 0, 0, 0]
    # changes at 0, 3, 7; >= 2 s after: k 2, 5, 6, 9; above 0.5: k 5, 6
    expected = [False] * 5 + [True, True] + [False] * 3
    assert m.stationary_mask(t, r, settle=2.0, min_level=0.5).tolist() == expected


def test_segment_mask_dispatch():
    t = np.arange(4.0)
    r = [0, 1, 1, 1]
    assert m.segment_mask("all", t, r).tolist() == [True] * 4
    assert m.segment_mask("ascending", t, r).tolist() == [False, True, False, False]
    assert m.segment_mask("stationary", t, r, settle=2.0).tolist() == [False, False, False, True]
    with pytest.raises(ValueError):
        m.segment_mask("descending", t, r)
