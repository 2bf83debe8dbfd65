"""Sensor models: slider encoder and wire-tension force sensor (digest section 1).

Encoder: incremental quadrature encoder on the slider, integer counts of ``resolution_m``
(default 1 um), nearest count, contraction positive. Force sensor: wire tension at the
fixed end with additive Gaussian noise from a seeded generator, quantised to
``resolution_n`` and limited to its range 0..range_max_n; a reading at a limit carries the
``saturated`` flag (the clip is the sensor's, and it is reported, never silent).

Scalar functions serve the stepping API; the ``*_array`` versions serve the batch API and
give identical numbers.
"""

from __future__ import annotations

import numpy as np


def encoder_counts(position_m: float, resolution_m: float) -> int:
    """Integer counts of the slider position (nearest count)."""
    return int(round(position_m / resolution_m))


def encoder_counts_array(position_m: np.ndarray, resolution_m: float) -> np.ndarray:
    """Vectorised :func:`encoder_counts` (int64)."""
    return np.rint(np.asarray(position_m) / resolution_m).astype(np.int64)


def force_reading(force_n: float, noise_n: float, range_max_n: float, resolution_n: float) -> tuple[float, bool]:
    """(reading, saturated) for a true wire force plus one noise sample."""
    raw = force_n + noise_n
    if raw >= range_max_n:
        return range_max_n, True
    if raw <= 0.0:
        return 0.0, True
    return min(round(raw / resolution_n) * resolution_n, range_max_n), False


def force_reading_array(force_n: np.ndarray, noise_n: np.ndarray, range_max_n: float,
                        resolution_n: float) -> tuple[np.ndarray, np.ndarray]:
    """Vectorised :func:`force_reading`."""
    raw = np.asarray(force_n) + noise_n
    saturated = (raw >= range_max_n) | (raw <= 0.0)
    reading = np.minimum(np.round(raw / resolution_n) * resolution_n, range_max_n)
    reading = np.where(raw >= range_max_n, range_max_n, np.where(raw <= 0.0, 0.0, reading))
    return reading, saturated


def noise_generator(seed: int) -> np.random.Generator:
    """The force sensor's generator; one standard-normal draw per simulation step (none when
    the sensor's noise is zero)."""
    return np.random.default_rng(seed)

