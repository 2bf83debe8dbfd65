"""Sensor imperfections applied to a true signal: each is what its parameter says."""

from __future__ import annotations

import numpy as np
import pytest

from hems_ros.truth.measurement import Sensor, ar1_noise, measure

RNG_SEED = 7


def test_ar1_noise_has_the_asked_spread_and_correlation():
    noise = ar1_noise(200_000, 0.05, 0.9, np.random.default_rng(RNG_SEED))
    assert noise.std() == pytest.approx(0.05, rel=0.05)
    assert np.corrcoef(noise[:-1], noise[1:])[0, 1] == pytest.approx(0.9, abs=0.01)


def test_latency_shows_older_values_and_drift_adds_its_ramp():
    true = np.arange(10.0)
    reading = measure(
        true, 0.5, Sensor(latency_samples=2, drift_per_s=0.2), np.random.default_rng()
    )
    assert reading[:3] == pytest.approx([0.0, 0.1, 0.2])  # held first value plus the drift
    assert reading[5] == pytest.approx(3.0 + 0.2 * 2.5)


def test_spikes_hit_their_share_of_samples_with_their_size():
    true = np.zeros(100_000)
    reading = measure(
        true, 0.01, Sensor(spike_share=0.01, spike_size=3.0), np.random.default_rng(1)
    )
    hit = reading != 0.0
    assert hit.mean() == pytest.approx(0.01, rel=0.1)
    assert set(np.abs(reading[hit])) == {3.0}


def test_readings_fall_on_the_resolution_grid():
    true = np.linspace(0.0, 1.0, 1001)
    reading = measure(true, 0.01, Sensor(noise_sd=0.01, quantum=0.025), np.random.default_rng(2))
    assert np.allclose(reading / 0.025, np.round(reading / 0.025))
    assert np.max(np.abs(reading - true)) < 0.0125 + 5 * 0.01


def test_an_impossible_sensor_is_refused_naming_every_problem():
    with pytest.raises(ValueError, match="rho 1.0 is outside.*quantum -1 is negative"):
        Sensor(rho=1.0, quantum=-1)


def test_a_lag_filter_reaches_63_percent_of_a_step_in_its_time_constant():
    true = np.r_[np.zeros(100), np.ones(1000)]
    reading = measure(true, 0.001, Sensor(lag_s=0.05), np.random.default_rng())
    assert reading[:100] == pytest.approx(0.0)
    assert reading[100 + 50] == pytest.approx(1.0 - np.exp(-1.0), abs=0.01)
    assert reading[-1] == pytest.approx(1.0, abs=1e-6)


def test_a_warm_up_offset_settles_exponentially_from_the_start():
    reading = measure(
        np.zeros(401), 0.1, Sensor(warmup=2.0, warmup_s=10.0), np.random.default_rng()
    )
    assert reading[0] == 0.0
    assert reading[100] == pytest.approx(2.0 * (1.0 - np.exp(-1.0)))
    assert reading[400] == pytest.approx(2.0, abs=0.04)
