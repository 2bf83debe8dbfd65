"""Sensor models: slider encoder and wire-tension force sensor (dissertation chapter 6).

Encoder: incremental quadrature encoder on the slider, integer counts of ``resolution_m``
(default 1 um), nearest count, contraction positive. Force sensor: wire tension at the
fixed end with additive Gaussian noise from a seeded generator, quantised to
``resolution_n`` and limited to its range 0..range_max_n; a reading at a limit carries the
``saturated`` flag (the clip is the sensor's, and it is reported, never silent).

Sensor errors a measurement may carry (params.Encoder, params.ForceSensor): an encoder
scale error ``gain`` and a force zero error ``offset_n`` drifting at ``drift_n_per_s`` over
the time since the unit started. Their defaults (1, 0, 0) leave the readings unchanged.

Scalar functions serve the stepping API; the ``*_array`` versions serve the batch API and
give identical numbers.
"""

from __future__ import annotations

import numpy as np


def encoder_counts(position_m: float, resolution_m: float, gain: float = 1.0) -> int:
    """Integer counts of the slider position as an encoder of scale ``gain`` sees it
    (nearest count)."""
    return int(round(gain * position_m / resolution_m))


def encoder_counts_array(position_m: np.ndarray, resolution_m, gain=1.0) -> np.ndarray:
    """Vectorised :func:`encoder_counts` (int64); ``resolution_m`` and ``gain`` broadcast."""
    return np.rint(gain * np.asarray(position_m) / resolution_m).astype(np.int64)


def force_reading(
    force_n: float,
    noise_n: float,
    range_max_n: float,
    resolution_n: float,
    offset_n: float = 0.0,
    drift_n_per_s: float = 0.0,
    time_s: float = 0.0,
) -> tuple[float, bool]:
    """(reading, saturated) for a true wire force, the sensor's zero error at ``time_s`` (s since
    the unit started) and one noise sample."""
    raw = force_n + offset_n + drift_n_per_s * time_s + noise_n
    if raw >= range_max_n:
        return range_max_n, True
    if raw <= 0.0:
        return 0.0, True
    return min(round(raw / resolution_n) * resolution_n, range_max_n), False


def force_reading_array(
    force_n: np.ndarray,
    noise_n: np.ndarray,
    range_max_n,
    resolution_n,
    offset_n=0.0,
    drift_n_per_s=0.0,
    time_s=0.0,
) -> tuple[np.ndarray, np.ndarray]:
    """Vectorised :func:`force_reading`; the sensor constants and ``time_s`` broadcast."""
    raw = np.asarray(force_n) + offset_n + drift_n_per_s * time_s + noise_n
    saturated = (raw >= range_max_n) | (raw <= 0.0)
    reading = np.minimum(np.round(raw / resolution_n) * resolution_n, range_max_n)
    reading = np.where(raw >= range_max_n, range_max_n, np.where(raw <= 0.0, 0.0, reading))
    return reading, saturated


def noise_generator(seed: int) -> np.random.Generator:
    """The force sensor's generator; one standard-normal draw per simulation step (none when
    the sensor's noise is zero)."""
    return np.random.default_rng(seed)
