"""What a lab's sensor makes of a true signal: a lag filter, latency, drift, coloured noise,
spikes and a finite resolution, applied in that order (the converter quantises what the
sensor delivers).

Two kinds of drift: a steady creep (``drift_per_s``), and a warm-up, an offset that settles
exponentially after the sensor is switched on at the run's start (``warmup``, reached to
1 - 1/e after ``warmup_s``), as a strain-gauge bridge's does while it warms.

Noise is AR(1): each sample keeps ``rho`` of the one before, the innovations sized so that
the noise's own standard deviation is ``noise_sd`` at any ``rho``; white noise is rho 0.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy.signal import lfilter


@dataclass(frozen=True)
class Sensor:
    """One channel's imperfections, in the channel's units (per second for the drift)."""

    noise_sd: float = 0.0
    rho: float = 0.0
    latency_samples: int = 0
    spike_share: float = 0.0  # share of samples replaced by a spike
    spike_size: float = 0.0  # a spike adds this, either sign
    drift_per_s: float = 0.0
    warmup: float = 0.0  # the offset the warm-up settles at
    warmup_s: float = 60.0
    lag_s: float = 0.0  # a first-order filter's time constant; 0 for none
    quantum: float = 0.0  # resolution; 0 for none

    def __post_init__(self) -> None:
        problems = [
            text
            for bad, text in (
                (self.noise_sd < 0.0, f"noise_sd {self.noise_sd} is negative"),
                (not 0.0 <= self.rho < 1.0, f"rho {self.rho} is outside [0, 1)"),
                (self.latency_samples < 0, f"latency_samples {self.latency_samples} < 0"),
                (not 0.0 <= self.spike_share <= 1.0, f"spike_share {self.spike_share} not a share"),
                (self.quantum < 0.0, f"quantum {self.quantum} is negative"),
                (self.lag_s < 0.0, f"lag_s {self.lag_s} is negative"),
                (self.warmup_s <= 0.0, f"warmup_s {self.warmup_s} is not positive"),
            )
            if bad
        ]
        if problems:
            raise ValueError("sensor: " + "; ".join(problems))


def ar1_noise(count: int, sd: float, rho: float, rng: np.random.Generator) -> np.ndarray:
    """``count`` samples of stationary AR(1) noise with standard deviation ``sd``."""
    innovations = rng.normal(0.0, sd * math.sqrt(1.0 - rho * rho), count)
    start = rng.normal(0.0, sd)  # drawn from the stationary law: no start-up transient
    noise, _ = lfilter([1.0], [1.0, -rho], innovations, zi=[rho * start])
    return noise


def measure(
    true: np.ndarray, sample_s: float, sensor: Sensor, rng: np.random.Generator
) -> np.ndarray:
    """The readings ``sensor`` gives of ``true`` sampled every ``sample_s`` seconds."""
    if sensor.lag_s > 0.0:  # a first-order filter sampled exactly, settled at the start
        keep = math.exp(-sample_s / sensor.lag_s)
        true, _ = lfilter([1.0 - keep], [1.0, -keep], true, zi=[keep * true[0]])
    lag = min(sensor.latency_samples, true.size)
    # a late reading shows an older value; before the first one, the first
    reading = np.concatenate([np.full(lag, true[0]), true[: true.size - lag]])
    elapsed = sample_s * np.arange(true.size)
    reading = reading + sensor.drift_per_s * elapsed
    if sensor.warmup != 0.0:
        reading = reading + sensor.warmup * -np.expm1(-elapsed / sensor.warmup_s)
    if sensor.noise_sd > 0.0:
        reading = reading + ar1_noise(true.size, sensor.noise_sd, sensor.rho, rng)
    spikes = rng.random(true.size) < sensor.spike_share
    reading[spikes] += sensor.spike_size * rng.choice((-1.0, 1.0), spikes.sum())
    if sensor.quantum > 0.0:
        reading = sensor.quantum * np.round(reading / sensor.quantum)
    return reading
