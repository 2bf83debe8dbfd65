"""95 % intervals and correlations of the corrected values.

The fit minimises the training residual r (each channel in units of its noise floor). Near
the optimum r(u) ~ r0 + J du, so the values' covariance is s^2 (J^T J)^-1 with s^2 the
residual's mean square (1 at the noise, more where the model still misses). Samples of a
measured run are not independent: a residual that wanders slowly (coloured noise, a model
error) carries fewer independent samples than it has. Each run and channel counts
n (1 - rho) / (1 + rho) effective samples, rho its residual's lag-one autocorrelation (the
variance of a mean of AR(1) samples), and the covariance grows by the total count over the
effective one. J comes from central differences over a hundredth of each range: wide enough
to step over the jumps a plant step puts into the outputs (a transformation starting one
step later), narrow beside the ranges.

Intervals are taken in the fit's normalised coordinates and mapped back, so a parameter
fitted on a log scale gets an interval symmetric in its logarithm; they stop at the bounds.
Pairs whose correlation exceeds ``UNIDENTIFIABLE`` are reported as not separately
identifiable: the data fix a combination of them, not each.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Callable

import numpy as np

from hems_ros.diagnosis.dataset import Prediction, TimeSeriesData
from hems_ros.diagnosis.fit import Fit, Space
from hems_ros.physics.params import UnitParams

Z95 = 1.959964
STEP = 0.01
UNIDENTIFIABLE = 0.95
#: A residual correlated beyond this from sample to sample counts as this (n_eff stays > 0).
MAX_RHO = 0.999


@dataclass(frozen=True)
class Intervals:
    """Per fitted coordinate (in the fit's order): key, value, 95 % bounds (SI), and the
    correlation matrix; the sample counts behind them."""

    keys: tuple[str, ...]
    values: np.ndarray
    lower: np.ndarray
    upper: np.ndarray
    correlation: np.ndarray
    n_samples: int
    n_effective: float

    def of(self, key: str) -> tuple[float, float]:
        i = self.keys.index(key)
        return float(self.lower[i]), float(self.upper[i])

    def unidentifiable(self) -> list[tuple[str, str, float]]:
        """Pairs correlated beyond UNIDENTIFIABLE: (key, key, r)."""
        out = []
        for i in range(len(self.keys)):
            for j in range(i + 1, len(self.keys)):
                r = float(self.correlation[i, j])
                if np.isfinite(r) and abs(r) > UNIDENTIFIABLE:
                    out.append((self.keys[i], self.keys[j], r))
        return out


def effective_count(data, prediction: Prediction) -> tuple[int, float]:
    """(training samples, effective independent samples) of the residual of ``prediction``."""
    n = int(prediction.train.size)
    if not isinstance(data, TimeSeriesData):
        return n, float(n)
    effective = 0.0
    for run, sim, mask in zip(data.runs, prediction.outputs, data.split.train):
        for name in data.channels:
            if name in run.outputs and mask.any():
                r = (sim[name] - run.outputs[name])[mask]
                effective += r.size * independence(r)
    return n, effective


def independence(r: np.ndarray) -> float:
    """(1 - rho) / (1 + rho) of a residual series, rho its lag-one autocorrelation."""
    power = float(np.dot(r, r))
    if r.size < 3 or power == 0.0:
        return 1.0
    rho = min(max(float(np.dot(r[1:], r[:-1])) / power, 0.0), MAX_RHO)
    return (1.0 - rho) / (1.0 + rho)


#: Training residuals of parameter sets, and the effective sample count of the first one's.
Residuals = Callable[[list[UnitParams]], tuple[list[np.ndarray], float]]


def estimate(data, base: UnitParams, fit: Fit) -> Intervals | None:
    """The intervals of ``fit``'s values on ``data`` (None for a fit with no values)."""

    def replayed(sets: list[UnitParams]) -> tuple[list[np.ndarray], float]:
        predictions = data.predict(sets)
        return [p.train for p in predictions], effective_count(data, predictions[0])[1]

    return estimate_on(replayed, base, fit)


def estimate_on(residuals: Residuals, base: UnitParams, fit: Fit) -> Intervals | None:
    """The intervals of ``fit``'s values from the training ``residuals`` it was fitted to."""
    if not fit.structure:
        return None
    space = Space(base, fit.structure)
    u = np.array([c.unit(float(v)) for c, v in zip(space.coords, fit.values)])
    plus, minus = [], []
    for j in range(space.size):
        up, down = u.copy(), u.copy()
        up[j] = min(1.0, u[j] + STEP)
        down[j] = max(0.0, u[j] - STEP)
        plus.append(up)
        minus.append(down)
    sets = [space.params(v) for v in [u] + plus + minus]
    if any(s is None for s in sets):
        return _unknown(space, fit)
    trains, n_eff = residuals([s for s in sets if s is not None])
    r0 = trains[0]
    if not np.all([np.isfinite(r).all() for r in trains]):
        return _unknown(space, fit)
    k = space.size
    jac = np.stack(
        [(trains[1 + j] - trains[1 + k + j]) / (plus[j][j] - minus[j][j]) for j in range(k)],
        axis=1,
    )
    n = int(r0.size)
    s2 = float(np.dot(r0, r0)) / max(1, n - k)
    cov = s2 * (n / max(n_eff, 1.0)) * np.linalg.pinv(jac.T @ jac)
    sd = np.sqrt(np.clip(np.diag(cov), 0.0, None))
    identified = np.linalg.matrix_rank(jac) == k
    with np.errstate(invalid="ignore", divide="ignore"):
        correlation = cov / np.outer(sd, sd)
    if not identified:
        sd = np.where(np.abs(jac).sum(axis=0) > 0, sd, np.inf)
    lower_u = np.clip(u - Z95 * sd, 0.0, 1.0)
    upper_u = np.clip(u + Z95 * sd, 0.0, 1.0)
    return Intervals(
        tuple(c.parameter.key for c in space.coords),
        np.asarray(fit.values, dtype=float),
        np.array([c.value(float(x)) for c, x in zip(space.coords, lower_u)]),
        np.array([c.value(float(x)) for c, x in zip(space.coords, upper_u)]),
        correlation,
        n,
        n_eff,
    )


def joined(first: Intervals | None, second: Intervals | None) -> Intervals | None:
    """Intervals of values fitted apart (the load relation's, then the replay's on top of
    them), as one: their correlations across the two are unknown (NaN); the sample counts
    are the second's, which fitted the most."""
    if first is None or second is None:
        return first or second
    k1, k2 = len(first.keys), len(second.keys)
    correlation = np.full((k1 + k2, k1 + k2), np.nan)
    correlation[:k1, :k1] = first.correlation
    correlation[k1:, k1:] = second.correlation
    return Intervals(
        first.keys + second.keys,
        np.concatenate([first.values, second.values]),
        np.concatenate([first.lower, second.lower]),
        np.concatenate([first.upper, second.upper]),
        correlation,
        second.n_samples,
        second.n_effective,
    )


def _unknown(space: Space, fit: Fit) -> Intervals:
    """Intervals over the whole ranges: the neighbourhood of the fit does not run."""
    k = space.size
    return Intervals(
        tuple(c.parameter.key for c in space.coords),
        np.asarray(fit.values, dtype=float),
        np.array([c.lower for c in space.coords]),
        np.array([c.upper for c in space.coords]),
        np.full((k, k), np.nan),
        int(fit.n_train),
        float("nan"),
    )
