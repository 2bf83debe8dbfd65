"""The lockstep loop against a loop built on the physics stepping API, and its API."""

from __future__ import annotations

import math

import numpy as np
import pytest

from hems_ros.control import make_controller
from hems_ros.experiments.lockstep import run_protocol, simulate_loop
from hems_ros.physics import ActuationUnit, load_params


def _stepping_loop(reference, mode, params, n_sub=10):
    """What the node graph does: plant stepped every 1 ms, controller every 10 ms."""
    unit = ActuationUnit(params, dt=1e-3)
    c = make_controller("bpid", mode)
    res = params.encoder.resolution_m
    y = 0.0 if mode == "position" else params.load.pulley_ratio * params.load.static_force_n()
    out = []
    for r in reference:
        u = c.update(r, y)
        out.append((y, u))
        for _ in range(n_sub):
            step = unit.step(duty=u)
        y = step.encoder_counts * res if mode == "position" else step.force_reading_n
    return np.array(out)


@pytest.mark.parametrize("mode, level", [("position", 0.010), ("force", 15.0)])
def test_lockstep_matches_the_stepping_api(mode, level):
    params = load_params("ch6_hems_index")
    ref = np.r_[np.full(50, 0.0 if mode == "position" else 4.0), np.full(250, level)]
    y, u, *_ = simulate_loop(ref, "bpid", mode, params)
    expected = _stepping_loop(ref, mode, params)
    np.testing.assert_allclose(y, expected[:, 0], atol=1e-9)
    np.testing.assert_allclose(u, expected[:, 1], atol=1e-9)


def test_run_protocol_returns_arrays_and_metrics():
    run = run_protocol("ch6_position_step", "bpid", "ch6_hems_index")
    n = run.time.size
    assert n == 7000 and run.fault is None
    for a in (
        run.reference,
        run.measurement,
        run.duty,
        run.position_m,
        run.wire_force_n,
        run.power_w,
    ):
        assert a.shape == (n,)
    assert run.reference.max() == pytest.approx(0.027)
    assert ((run.duty >= 0) & (run.duty <= 100)).all()
    assert set(run.metrics) >= {
        "rmse",
        "iae",
        "macsi",
        "apc_w",
        "rise_time_s",
        "overshoot",
        "ss_error",
    }
    assert all(math.isfinite(run.metrics[k]) for k in ("rmse", "iae", "macsi", "apc_w"))


def test_nan_measurement_source_stops_the_run_with_zero_duty():
    ref = np.r_[np.full(10, 0.005), np.nan, np.full(10, 0.005)]
    y, u, *_, fault = simulate_loop(ref, "pid", "position", "ch5_straight_40n")
    assert u.size == 11 and u[-1] == 0.0
    assert "reference is nan" in fault


def test_ts_must_be_a_multiple_of_the_plant_step():
    with pytest.raises(ValueError, match="whole number"):
        simulate_loop(np.zeros(5), "pid", "position", "ch5_straight_40n", ts=0.0105)
