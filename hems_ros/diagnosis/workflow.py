"""The diagnosis from measured runs to a verdict: prepare, replay, search, localise.

:func:`diagnose` is the whole workflow on runs already loaded (csvload, bagload), and
returns a :class:`Diagnosis` that the report renders; nothing here writes files.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace
from typing import Callable, Mapping, Sequence, TypeVar

import numpy as np

from hems_ros.diagnosis import candidates as library
from hems_ros.diagnosis import dataset, features, intervals, localise, relation, replay
from hems_ros.diagnosis.fit import near_bounds
from hems_ros.diagnosis.intervals import Intervals
from hems_ros.diagnosis.runs import DiagnosisInputError, FeatureRun, Run, TimeSeriesRun
from hems_ros.diagnosis.search import Search, run_search
from hems_ros.physics.params import UnitParams

#: The input's timing is searched this many sample periods either way by default.
TIMING_PERIODS = 3


@dataclass
class Gap:
    """Headline disagreement: RMSE of the output the starting model misses most, on the fitted
    data and on the held-out data that chose nothing (Split.test), before and after."""

    metric: str
    unit: str
    train_before: float
    train_after: float
    heldout_before: float
    heldout_after: float
    noise: float = math.nan  # the output's noise floor (time series), same unit

    @property
    def change(self) -> float:
        return (
            (self.heldout_after / self.heldout_before - 1.0)
            if self.heldout_before > 0
            else math.nan
        )

    def beyond_noise(self, rmse: float) -> float:
        """The part of an RMSE the noise floor does not account for: sqrt(RMSE^2 - noise^2)."""
        return math.sqrt(max(rmse**2 - self.noise**2, 0.0)) if math.isfinite(self.noise) else rmse


@dataclass
class Diagnosis:
    model_name: str
    start: UnitParams
    corrected: UnitParams
    data: dataset.TimeSeriesData | features.FeatureData
    search: Search
    candidates: list[library.Candidate]
    gap: Gap
    phases_before: list[localise.Row]
    phases_after: list[localise.Row]
    unexplained: list[str]
    predictions: dict = field(default_factory=dict)  # "start" / "corrected" -> Prediction
    # groups the corrected model leaves above the noise (localise.left_above_noise) -> its RMS
    # over the noise floor
    left: dict[str, float] = field(default_factory=dict)
    # 95 % intervals and correlations of the corrected values (None: nothing fitted)
    intervals: Intervals | None = None

    @property
    def verdict(self) -> str:
        """The search's verdict, or ``partial`` where it accepted terms (timing, parameters,
        effects) and the corrected model still leaves a group above the noise."""
        if self.search.verdict in ("timing", "recalibrated", "named") and self.left:
            return "partial"
        return self.search.verdict

    def named(self) -> list[dict]:
        fit = self.search.final
        return [
            {"effect": c.name, "title": c.title, "parameters": _parameters(fit, c, self.intervals)}
            for c in self.search.effects
        ]

    def recalibrated(self) -> dict[str, dict]:
        fit = self.search.final
        out = {}
        for c in self.search.recalibrations:
            for entry in _parameters(fit, c, self.intervals).items():
                out[entry[0]] = entry[1]
        return out

    def timing(self) -> dict | None:
        """The input's timing: the range searched, the first step's fit of it on the starting
        model (the estimate every diagnosis of driven runs makes), and the value the corrected
        model takes (None: not accepted). None when the data have no timing to estimate."""
        timing = next((c for c in self.candidates if c.kind == "timing"), None)
        if timing is None:
            return None
        lower, upper = timing.bounds(self.start)[0]
        ranked = self.search.steps[0].ranked if self.search.steps else []
        estimate = next((f.values[0] for f in ranked if f.structure == (timing,)), None)
        final = self.search.final
        kept = [v for c, v in zip(final.structure, final.values) if c is timing]
        key = timing.parameters[0].key
        interval = self.intervals.of(key) if kept and self.intervals is not None else None
        return {
            "range_s": [lower, upper],
            "estimate_s": None if estimate is None else float(estimate),
            "accepted_s": float(kept[0]) if kept else None,
            "interval_s": None if interval is None else list(interval),
        }

    def summary_line(self) -> str:
        head = self.verdict
        timing = self.timing()
        accepted = None if timing is None else timing["accepted_s"]
        if self.verdict == "timing":
            assert accepted is not None  # the verdict says only timing was accepted
            head += (
                f": the input reaches the wire {abs(accepted) * 1e3:.3g} ms "
                f"{'after' if accepted > 0 else 'before'} its record; no physics changed"
            )
        elif accepted is not None:
            head += f" (input timing {accepted * 1e3:+.3g} ms)"
        effects = [
            f"{n['effect']} ({'; '.join(_short(p) for p in n['parameters'].values())})"
            for n in self.named()
        ]
        values = [_short(p) for p in self.recalibrated().values()]
        if self.verdict in ("named", "ambiguous"):
            head += ": " + ", ".join(effects)
        elif self.verdict == "recalibrated":
            head += ": " + ", ".join(values)
        elif self.verdict == "partial":
            head += (
                ": "
                + ", ".join(effects + values or ["the input timing"])
                + f"; left above {localise.LEFT_RMS:g}x the noise: "
                + ", ".join(f"{g} ({m:.2g}x)" for g, m in self.left.items())
            )
        elif self.verdict == "unexplained":
            where = ", ".join(self.unexplained) or "every phase"
            kept = self.search.final.structure
            head += (
                f": the residual in {where} stays after "
                + ", ".join(c.name for c in kept)
                + ", which remove(s) part of it"
                if kept
                else f": residual in {where} not removed by any candidate"
            )
        g = self.gap
        near = "".join(f"; {text}" for text in self.near_bounds())
        return (
            f"{head}; held-out {g.metric} RMSE {g.heldout_before:.3g} {g.unit} "
            f"-> {g.heldout_after:.3g} {g.unit} ({g.change * 100:+.0f} %){near}"
        )

    def near_bounds(self) -> list[str]:
        """The corrected values close to a bound of their range (fit.NEAR_BOUND)."""
        return near_bounds(self.start, self.search.final)


def _parameters(
    fit, candidate: library.Candidate, bounds: Intervals | None = None
) -> dict[str, dict]:
    out, i = {}, 0
    for cand in fit.structure:
        for par in cand.parameters:
            if cand is candidate:
                value = float(fit.values[i])
                entry = {
                    "symbol": par.symbol,
                    "value": par.display(value),
                    "unit": par.unit,
                    "si_value": value,
                }
                if bounds is not None:
                    lower, upper = bounds.of(par.key)
                    entry |= {
                        "lower": par.display(lower),
                        "upper": par.display(upper),
                        "si_lower": lower,
                        "si_upper": upper,
                    }
                out[par.key] = entry
            i += 1
    return out


def _short(p: dict) -> str:
    """``b = 259 N s/m [241, 277]``: the value and, when known, its 95 % interval."""
    interval = " [{}, {}]".format(*_apart(p["lower"], p["upper"])) if "lower" in p else ""
    return f"{p['symbol']} = {p['value']:.3g} {p['unit']}".rstrip() + interval


def _apart(low: float, high: float) -> tuple[str, str]:
    """Both ends with the fewest significant digits (3 to 6) that tell them apart."""
    for digits in range(3, 7):
        a, b = f"{low:.{digits}g}", f"{high:.{digits}g}"
        if a != b:
            break
    return a, b


_R = TypeVar("_R", TimeSeriesRun, FeatureRun)


def _of_kind(runs: Sequence[Run], kind: type[_R]) -> list[_R]:
    return [r for r in runs if isinstance(r, kind)]


def prepare(
    runs: Sequence[Run], heldout: Sequence[Run], dt: float | None = None
) -> dataset.TimeSeriesData | features.FeatureData:
    """The dataset of the runs' kind (all runs must be of one kind)."""
    everything = list(runs) + list(heldout)
    if not runs:
        raise DiagnosisInputError("no run given")
    if all(isinstance(r, TimeSeriesRun) for r in everything):
        return dataset.prepare(_of_kind(runs, TimeSeriesRun), _of_kind(heldout, TimeSeriesRun), dt)
    if all(isinstance(r, FeatureRun) for r in everything):
        return features.prepare(
            _of_kind(runs, FeatureRun), _of_kind(heldout, FeatureRun), dt or features.PULSE_DT
        )
    raise DiagnosisInputError(
        "all runs must be of one kind: time series (bags, driven runs, thermal cycles) "
        "or tables of test figures"
    )


def diagnose(
    runs: Sequence[Run],
    heldout: Sequence[Run],
    model: UnitParams,
    *,
    candidates: list[str] | None = None,
    bounds: Mapping[str, object] | None = None,
    timing_range_s: float | None = None,
    dt: float | None = None,
    progress: Callable[[str], None] | None = None,
) -> Diagnosis:
    """Replay, localise, explain (timing, recalibration, then missing effects) and measure
    the gap.

    ``bounds``: parameter key -> range replacing the library's (``candidates.with_bounds``).
    ``timing_range_s``: the largest input delay either way that driven runs are searched
    for (default TIMING_PERIODS sample periods)."""
    say = progress or (lambda message: None)
    series = [run for run in list(runs) + list(heldout) if isinstance(run, TimeSeriesRun)]
    reasons = [
        r
        for check in (replay.cannot_start, replay.beyond_sensor)
        for r in (check(model, run) for run in series)
        if r
    ]
    if reasons:
        raise DiagnosisInputError(reasons[0])
    data = prepare(runs, heldout, dt)
    say(f"{_describe(data)}; {data.split.description}")
    start_prediction = data.predict([model])[0]
    if isinstance(data, dataset.TimeSeriesData):
        data.calibrate_noise(start_prediction)
        start_prediction = data.predict([model])[0]
        say(
            "noise floor: "
            + ", ".join(
                f"{c} {data.sigma[c] * data.display(c)[1]:.3g} {data.display(c)[0]}"
                for c in data.channels
            )
        )
    pool = _with_timing_range(
        library.applicable(model, data.drives, data.measured, candidates), data, timing_range_s
    )
    if bounds:
        try:
            pool = library.with_bounds(pool, model, bounds)
        except ValueError as error:
            raise DiagnosisInputError(f"--bounds: {error}") from None
    say(f"candidates: {', '.join(c.name for c in pool)}")
    search = run_search(data, model, pool, progress=say, relation=relation.of(data, model))
    corrected = search.final.params
    final_prediction = data.predict([corrected])[0]
    headline = data.headline(start_prediction)
    unit, scale = localise.display(data, headline)
    gap = Gap(
        headline,
        unit,
        data.rmse(start_prediction, headline, "train") * scale,
        data.rmse(final_prediction, headline, "train") * scale,
        data.rmse(start_prediction, headline, "test") * scale,
        data.rmse(final_prediction, headline, "test") * scale,
        data.sigma[headline] * scale if isinstance(data, dataset.TimeSeriesData) else math.nan,
    )
    before, after = localise.table(data, start_prediction), localise.table(data, final_prediction)
    unexplained = localise.unexplained(
        data, final_prediction, force=search.verdict == "unexplained"
    )
    return Diagnosis(
        model.name,
        model,
        corrected,
        data,
        search,
        pool,
        gap,
        before,
        after,
        unexplained,
        {"start": start_prediction, "corrected": final_prediction},
        localise.left_above_noise(data, before, after),
        _intervals(data, model, search),
    )


def _intervals(data, model: UnitParams, search: Search) -> Intervals | None:
    """The load relation's values with its intervals (unless the replay refitted them), the
    steps' with the replay's, made on top of the relation's values."""
    fixed, named = search.fixed, search.load_relation
    if fixed is None or named is None or named.refined:
        return intervals.estimate(data, model, search.final)
    return intervals.joined(named.intervals, intervals.estimate(data, fixed.params, search.free))


def _with_timing_range(pool: list, data, range_s: float | None) -> list:
    """The timing candidate over +-``range_s`` (default TIMING_PERIODS of the runs' median
    sample period); out of the pool for data without a recorded electrical input (tables of
    tests, thermal cycles)."""
    driven = isinstance(data, dataset.TimeSeriesData) and all(
        r.drive != "temperature" for r in data.runs
    )
    if not driven:
        return [c for c in pool if c.kind != "timing"]
    if range_s is None:
        range_s = TIMING_PERIODS * float(np.median([np.median(np.diff(r.time)) for r in data.runs]))
    return [
        replace(c, bound_overrides={"drive.input_delay_s": (-range_s, range_s)})
        if c.kind == "timing"
        else c
        for c in pool
    ]


def _describe(data) -> str:
    if isinstance(data, dataset.TimeSeriesData):
        n = sum(r.n_samples for r in data.runs)
        return f"{len(data.runs)} run(s), {n} samples, outputs {', '.join(data.channels)}"
    return f"{len(data.tests)} test row(s), figures {', '.join(data.channels)}"


def total_seconds(runs: list[Run]) -> float:
    """Measured time covered by the time-series runs (0 for tables)."""
    return float(np.sum([r.duration_s for r in runs if isinstance(r, TimeSeriesRun)]))
