"""Measured time series prepared for fitting: replay plans, phases, the held-out split and
the noise floor that weighs each channel.

Residuals are weighted by each channel's noise floor, so a model that matches the
measurement up to its noise has a mean squared weighted residual of 1 on every channel,
and position (m) and force (N) add up in one cost. The noise floor is read off the
starting model's residual: its high-frequency part (second differences, robust to the
few samples where the misfit bends fast) is the measurement's noise and quantisation,
because a smooth model cannot follow it.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np

from hems_ros.diagnosis import phases as phase_mod
from hems_ros.diagnosis.replay import ReplayPlan, plan, replay
from hems_ros.diagnosis.runs import OUTPUT_UNITS, DiagnosisInputError, TimeSeriesRun
from hems_ros.physics.params import UnitParams

#: Least noise floor each channel is credited with (SI): what no replay can promise to match.
NOISE_FLOOR = {
    "position": 0.5e-6,
    "strain": 0.5e-6,
    "wire_force": 2e-3,
    "load_force": 2e-3,
    "temperature": 0.02,
}
#: Outputs in the order the gap is reported by (the first one measured is the headline).
PRIMARY_ORDER = ("position", "strain", "wire_force", "load_force", "temperature")


#: A cycle shorter than this gives no floor of its own (the spread of the floor is read from
#: the cycles' floors).
MIN_CYCLE_SAMPLES = 100
#: Lags (samples) of the third differences the noise's correlation is read from.
NOISE_LAGS = np.array([1, 2, 3])
#: Correlations tried for the noise: a residual that wanders more slowly than AR(1) at 0.95 is
#: the model's, not the sensor's.
_RHOS = np.linspace(0.0, 0.95, 951)


def noise_floor(residual: np.ndarray, resolution: float, channel: str) -> float:
    """Standard deviation of the noise in ``residual``, white or coloured.

    Third differences remove what the model misses smoothly (an offset, a slope, a slow bend)
    and keep the noise. For AR(1) noise of correlation rho and deviation sigma, the third
    difference over k samples has the mean square 2 sigma^2 (1 - q)(10 - 5 q + q^2) with
    q = rho^k: the mean squares at lags 1-3 fix rho (least squares on their logarithms), then
    sigma. White noise gives rho 0 and the plain third-difference estimate. A noise filtered by
    the sensor (a 10 Hz low-pass sampled at 100 Hz is rho 0.53) is counted whole, not only its
    fast part. Measured on 4000 samples: within 5 % of the truth for white noise, 0.84-1.36 of
    it at rho 0.75 and 0.62-1.42 at rho 0.9 (twelve draws each); the suite's hidden effects
    leak into it by 1-7 % (capstan friction the most); second differences, whose two-sample
    ratio a missing damping's residual moves, read a fifth more than the white noise there."""
    squares = np.array([_mean_square(_third_difference(residual, lag)) for lag in NOISE_LAGS])
    sigma = 0.0
    if np.all(squares > 0.0):
        q = _RHOS[:, None] ** NOISE_LAGS[None, :]
        shape = 2.0 * (1.0 - q) * (10.0 - 5.0 * q + q * q)
        log_sigma2 = np.mean(np.log(squares)[None, :] - np.log(shape), axis=1)
        misfit = np.sum((np.log(squares)[None, :] - np.log(shape) - log_sigma2[:, None]) ** 2, 1)
        sigma = float(np.exp(0.5 * log_sigma2[int(np.argmin(misfit))]))
    return max(sigma, resolution / np.sqrt(12.0), NOISE_FLOOR[channel])


def _third_difference(r: np.ndarray, lag: int) -> np.ndarray:
    if r.size <= 3 * lag:
        return np.zeros(0)
    return r[3 * lag :] - 3.0 * r[2 * lag : -lag] + 3.0 * r[lag : -2 * lag] - r[: -3 * lag]


def _mean_square(d: np.ndarray) -> float:
    """Mean square of ``d`` without its outliers (a transformation's onset, a spike): the
    MAD alone is biased for readings quantised at a step comparable to the noise."""
    if not d.size:
        return 0.0
    centred = d - np.median(d)
    scale = float(np.median(np.abs(centred))) / 0.6745
    kept = centred[np.abs(centred) <= 5.0 * scale] if scale > 0 else centred
    return float(np.mean(kept**2))


#: The split's note when the data are too few for a test role of their own.
NO_TEST = "; too few for a test of their own: the gap is measured on the selecting data"


@dataclass
class Split:
    """The role of every sample of each run: ``train`` fits the parameters, ``heldout`` selects
    the terms and the verdict, ``test`` chose nothing and measures the gap (the selecting
    samples again, said in ``description``, when the data are too few for a third role)."""

    train: list[np.ndarray]
    heldout: list[np.ndarray]
    test: list[np.ndarray]
    description: str

    def role(self, which: str) -> list[np.ndarray]:
        return {"train": self.train, "heldout": self.heldout, "test": self.test}[which]


def three_roles(
    train: list[np.ndarray], select: list[np.ndarray], test: list[np.ndarray], description: str
) -> Split:
    """A Split, testing on the selecting samples (and saying so) when none are left to test."""
    if not any(m.any() for m in test):
        return Split(train, select, select, description + NO_TEST)
    return Split(train, select, test, description)


@dataclass
class Prediction:
    """One parameter set's outputs on every run, and its weighted residuals."""

    # per run: output -> (n_samples,) array; per row of a feature table: figure -> value
    outputs: list[dict[str, Any]]
    train: np.ndarray  # weighted residuals on the training samples
    heldout: np.ndarray


@dataclass
class TimeSeriesData:
    """Runs, how to replay them, their phases, split and per-channel noise floor."""

    runs: list[TimeSeriesRun]
    plans: list[ReplayPlan]
    segments: list[phase_mod.Segmentation]
    split: Split
    sigma: dict[str, float] = field(default_factory=dict)
    # standard deviation of the log of a perfect model's cost, from the spread of the noise
    # floor read cycle by cycle: wide under noise as coloured as a sensor's low-pass filter
    cost_spread: float = 0.0

    @property
    def channels(self) -> list[str]:
        return [c for c in PRIMARY_ORDER if any(c in r.outputs for r in self.runs)]

    @property
    def drives(self) -> frozenset:
        return frozenset(r.drive for r in self.runs)

    @property
    def measured(self) -> frozenset:
        return frozenset(self.channels)

    @property
    def n_train(self) -> int:
        return int(sum(m.sum() * len(r.outputs) for m, r in zip(self.split.train, self.runs)))

    def predict(self, sets: list[UnitParams]) -> list[Prediction]:
        """Replay every set on every run; weighted residuals split into train and held-out."""
        per_run = [replay(p, sets) for p in self.plans]
        out = []
        for i in range(len(sets)):
            outputs = [{name: sim[name][i] for name in sim} for sim in per_run]
            out.append(
                Prediction(
                    outputs,
                    self._weighted(outputs, self.split.train),
                    self._weighted(outputs, self.split.heldout),
                )
            )
        return out

    def _weighted(
        self, outputs: list[dict[str, np.ndarray]], masks: list[np.ndarray]
    ) -> np.ndarray:
        parts = []
        for run, sim, mask in zip(self.runs, outputs, masks):
            for name in self.channels:
                if name in run.outputs:
                    parts.append(
                        (sim[name][mask] - run.outputs[name][mask]) / self.sigma.get(name, 1.0)
                    )
        return np.concatenate(parts) if parts else np.zeros(0)

    def calibrate_noise(self, start: Prediction) -> None:
        """Noise floor per channel from the starting model's residual (all runs pooled), and
        how far a perfect model's cost may stray from 1 because the floor is only estimated
        (``cost_spread``)."""
        variances = []
        for name in self.channels:
            floors, cycles = [], []
            for run, sim, seg in zip(self.runs, start.outputs, self.segments):
                if name in run.outputs:
                    residual = run.outputs[name] - sim[name]
                    resolution = run.resolution.get(name, 0.0)
                    floors.append(noise_floor(residual, resolution, name))
                    sizes = np.bincount(seg.cycle, minlength=seg.n_cycles)
                    cycles += [
                        noise_floor(residual[seg.cycle == c], resolution, name)
                        for c in np.flatnonzero(sizes >= MIN_CYCLE_SAMPLES)
                    ]
            self.sigma[name] = float(np.median(floors))
            if len(cycles) >= phase_mod.MIN_CYCLES:
                logs = 2.0 * np.log(cycles)
                variances.append(float(np.var(logs, ddof=1)) / len(logs))
        # the cost averages the channels: its log varies by the mean of their floors' variances
        self.cost_spread = float(np.sqrt(np.sum(variances))) / len(variances) if variances else 0.0

    def headline(self, start: Prediction) -> str:
        """The output the starting model misses most on held-out data, in noise-floor units."""

        def cost(name: str) -> float:
            parts = [
                (sim[name][m] - run.outputs[name][m]) / self.sigma.get(name, 1.0)
                for run, sim, m in zip(self.runs, start.outputs, self.split.heldout)
                if name in run.outputs
            ]
            r = np.concatenate(parts) if parts else np.zeros(0)
            return float(np.mean(r**2)) if r.size else 0.0

        return max(self.channels, key=cost)

    def rmse(self, prediction: Prediction, name: str, which: str) -> float:
        """RMSE of one output over the samples of one role (Split.role), SI."""
        masks = self.split.role(which)
        sq, n = 0.0, 0
        for run, sim, mask in zip(self.runs, prediction.outputs, masks):
            if name in run.outputs and mask.any():
                sq += float(np.sum((sim[name][mask] - run.outputs[name][mask]) ** 2))
                n += int(mask.sum())
        return float(np.sqrt(sq / n)) if n else float("nan")

    def display(self, name: str) -> tuple[str, float]:
        unit = OUTPUT_UNITS[name]
        return unit[1], unit[2]


def prepare(
    runs: list[TimeSeriesRun], heldout: list[TimeSeriesRun], dt: float | None = None
) -> TimeSeriesData:
    """Plans, phases and the split: the ``heldout`` runs (their odd cycles select, their even
    ones test), or cycles of each run (phases.cycle_roles)."""
    everything = list(runs) + list(heldout)
    plans = [plan(r, dt) for r in everything]
    segments = [phase_mod.segment(r) for r in everything]
    train, select, test = [], [], []
    if heldout:
        for run in runs:
            train.append(np.ones(run.n_samples, bool))
            select.append(np.zeros(run.n_samples, bool))
            test.append(np.zeros(run.n_samples, bool))
        for run, seg in zip(heldout, segments[len(runs) :]):
            even = np.isin(seg.cycle, np.arange(1, seg.n_cycles, 2))
            train.append(np.zeros(run.n_samples, bool))
            select.append(~even)
            test.append(even)
        description = (
            f"held-out runs: {', '.join(r.name for r in heldout)}, cycles 1, 3 ... selecting "
            f"the terms and 2, 4 ... testing them (fitted on {', '.join(r.name for r in runs)})"
        )
        return TimeSeriesData(
            everything, plans, segments, three_roles(train, select, test, description)
        )
    parts = []
    for run, seg in zip(runs, segments):
        selecting, testing = phase_mod.cycle_roles(seg.n_cycles)
        select.append(np.isin(seg.cycle, selecting))
        test.append(np.isin(seg.cycle, testing))
        train.append(~(select[-1] | test[-1]))
        parts.append(
            f"{run.name}: cycles {_numbers(selecting)} select"
            + (f", {_numbers(testing)} test" if testing else "")
            + f", of {seg.n_cycles}"
        )
    if not any(m.any() for m in select):
        counts = ", ".join(f"{r.name} {s.n_cycles}" for r, s in zip(runs, segments))
        raise DiagnosisInputError(
            f"too short to hold data out: {counts} cycle(s); a run needs at least "
            f"{phase_mod.MIN_CYCLES} actuation cycles, or give --heldout RUN"
        )
    description = "cycles held out of the fit, selecting the terms or testing them: " + "; ".join(
        parts
    )
    return TimeSeriesData(
        everything, plans, segments, three_roles(train, select, test, description)
    )


def _numbers(cycles: list[int]) -> str:
    return ", ".join(str(c + 1) for c in cycles) or "none"
