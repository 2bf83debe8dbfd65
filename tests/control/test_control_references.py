"""Reference generators: shapes, levels and timing of the dissertation protocols."""

import numpy as np
import pytest

from hems_ros.control import metrics as m
from hems_ros.control import references as ref


def test_sine():
    t, r = ref.sine(0.125, 0.02, ts=0.01)
    assert t.shape == r.shape == (2000,)
    assert t[1] - t[0] == pytest.approx(0.01)
    assert r[0] == 0.0
    assert r[400] == pytest.approx(0.02)  # t = 4 s, half a period
    assert r[800] == pytest.approx(0.0, abs=1e-15)  # full period
    assert r.min() >= 0.0 and r.max() == pytest.approx(0.02)


def test_step_pair():
    t, r = ref.step_pair(0.02, ts=0.01)
    assert r.size == 7000
    assert (r[499], r[500], r[999], r[1000]) == (0.0, 0.02, 0.02, 0.0)
    assert (r[3499], r[3500], r[3999], r[4000]) == (0.0, 0.02, 0.02, 0.0)
    assert np.count_nonzero(r) == 1000
    assert [(s.start, s.after) for s in m.step_segments(r)] == [
        (500, 0.02),
        (1000, 0.0),
        (3500, 0.02),
        (4000, 0.0),
    ]


def test_staircase():
    t, r = ref.staircase(0.005, ts=0.01)
    assert r.size == 7000
    onsets = [500, 1250, 2000, 2750, 3500, 4250, 5000, 5750]
    levels = [0.005, 0.01, 0.015, 0.02, 0.015, 0.01, 0.005, 0.0]
    segs = m.step_segments(r)
    assert [s.start for s in segs] == onsets
    assert [s.after for s in segs] == pytest.approx(levels)
    assert r[:500].max() == 0.0 and r[5750:].max() == 0.0


def test_ramp():
    t, r = ref.ramp(0.027, 0.001, ts=0.01)
    # 2 s rest + 27 s up + 5 s hold + 27 s down + 10 s rest
    assert r.size == 7100
    assert r[200] == 0.0
    assert r[1200] == pytest.approx(0.010)
    assert np.diff(r[200:2901]) == pytest.approx(np.full(2700, 1e-5))
    assert np.all(r[2900:3401] == 0.027)
    assert r[6100:].max() == 0.0
    assert m.step_segments(r) == []


def test_protocol_table():
    names = {
        "ch5_sine_0.125",
        "ch5_sine_0.25",
        "ch5_sine_0.5",
        "ch5_step",
        "ch5_staircase",
        "ch6_position_sine_0.125",
        "ch6_position_ramp",
        "ch6_position_step",
        "ch6_position_staircase",
        "ch6_force_sine_0.125",
        "ch6_force_sine_0.25",
        "ch6_force_step",
        "ch6_force_staircase",
    }
    assert set(ref.PROTOCOLS) == names
    for p in ref.PROTOCOLS.values():
        t, r = p.generate(0.01)
        assert t.shape == r.shape
        assert p.segment in ("all", "ascending", "stationary")
        if p.chapter == 5:
            assert (p.mode, p.segment) == ("position", "all")
            assert (r.min(), r.max()) == (0.0, pytest.approx(0.02))
        elif p.mode == "position":
            assert (r.min(), r.max()) == (0.0, pytest.approx(0.027))
        else:
            assert (r.min(), r.max()) == (pytest.approx(2.0), pytest.approx(20.0))
    _, r = ref.PROTOCOLS["ch6_position_staircase"].generate()
    levels = [s.after for s in m.step_segments(r)][:4]
    assert levels == pytest.approx([0.00675, 0.0135, 0.02025, 0.027])
    assert ref.PROTOCOLS["ch6_force_step"].segment == "stationary"
    assert ref.PROTOCOLS["ch6_position_ramp"].segment == "ascending"


def test_other_sample_period():
    t, r = ref.PROTOCOLS["ch5_step"].generate(0.001)
    assert r.size == 70000
    assert r[4999] == 0.0 and r[5000] == 0.02
