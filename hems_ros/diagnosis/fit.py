"""Bounded least-squares fits of model structures (a starting model plus candidates).

A structure's parameters live in normalised coordinates u in [0, 1] (linear or log
between each parameter's physical bounds), which is what scipy's trust-region least
squares moves within its bounds. Each model evaluation also runs the sets one small step
along every coordinate, so the Jacobian (forward differences) comes from the same batch as
the residual. Every structure is fitted from several starts: the best points of a
quasi-random screen of its new parameters, evaluated as one batch.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Callable, Sequence

import numpy as np
from scipy.optimize import least_squares
from scipy.stats import qmc
from threadpoolctl import threadpool_limits

from hems_ros.diagnosis.batching import Barrier
from hems_ros.diagnosis.candidates import Candidate, Parameter
from hems_ros.physics.params import ParamError, UnitParams

#: Step of the forward differences, in normalised coordinates.
STEP = 1e-3
#: A parameter this close to a bound (normalised) sits on it.
AT_BOUND = 2e-3
#: Residual given to a set the model cannot run (invalid or non-finite), per sample.
PENALTY = 1e3
STARTS = 2
MAX_EVALUATIONS = 30
#: Whole plant steps either side of a fitted input timing that finish its fit.
TIMING_SCAN = 3
#: A fitted value this close to a bound, as a share of its range, is reported with the bound.
NEAR_BOUND = 0.05
Structure = tuple[Candidate, ...]


@dataclass(frozen=True)
class Coordinate:
    candidate: Candidate
    parameter: Parameter
    lower: float
    upper: float

    def value(self, u: float) -> float:
        if self.parameter.log:
            return math.exp(
                math.log(self.lower) + u * (math.log(self.upper) - math.log(self.lower))
            )
        return self.lower + u * (self.upper - self.lower)

    def unit(self, value: float) -> float:
        if self.parameter.log:
            return (math.log(value) - math.log(self.lower)) / (
                math.log(self.upper) - math.log(self.lower)
            )
        return (value - self.lower) / (self.upper - self.lower)


class Space:
    """The parameters of a structure on top of ``base``, in normalised coordinates."""

    def __init__(self, base: UnitParams, structure: Structure) -> None:
        self.base = base
        self.structure = structure
        self.coords = [
            Coordinate(c, par, lo, hi)
            for c in structure
            for par, (lo, hi) in zip(c.parameters, c.bounds(base))
        ]

    @property
    def size(self) -> int:
        return len(self.coords)

    def values(self, u: np.ndarray) -> np.ndarray:
        return np.array([c.value(float(x)) for c, x in zip(self.coords, np.clip(u, 0.0, 1.0))])

    def params(self, u: np.ndarray) -> UnitParams | None:
        """The model at ``u``, or None when the values make no valid parameter set."""
        values = iter(self.values(u))
        model = self.base
        try:
            for cand in self.structure:
                model = cand.apply(model, [next(values) for _ in cand.parameters])
        except (ParamError, ValueError):
            return None
        # a warm start and a lower As0 fitted together may leave no martensite to start from
        if model.ambient_temperature_c + model.start.temperature_offset_c >= model.kinetics.as0_c:
            return None
        return model

    def off(self) -> np.ndarray:
        """Each coordinate where it leaves its candidate without effect (clipped into
        the bounds)."""
        values = [v for cand in self.structure for v in cand.off_values(self.base)]
        return np.array(
            [
                np.clip(c.unit(v) if not (c.parameter.log and v <= 0) else 0.0, 0.0, 1.0)
                for c, v in zip(self.coords, values)
            ]
        )


@dataclass
class Fit:
    """A fitted structure: values (SI), the model, its costs and the parameters on a bound."""

    structure: Structure
    values: np.ndarray
    params: UnitParams
    train: float  # mean squared weighted residual on the training data
    heldout: float  # the same on the held-out data
    n_train: int
    pinned: list[str]  # parameters that ended on a bound other than "absent"
    evaluations: int = 0
    # the least-squares run of the start kept: did it meet its tolerances, and why it stopped
    converged: bool = True
    stop: str = ""
    starts: int = 0

    @property
    def n_parameters(self) -> int:
        return int(self.values.size)

    @property
    def bic(self) -> float:
        """Bayesian information criterion on the training data (Gaussian residuals)."""
        return self.n_train * math.log(max(self.train, 1e-300)) + self.n_parameters * math.log(
            self.n_train
        )

    @property
    def names(self) -> tuple[str, ...]:
        return tuple(c.name for c in self.structure)

    def describe(self, candidate: Candidate) -> list[str]:
        """``symbol = value unit`` of the candidate's parameters in this fit."""
        out, i = [], 0
        for cand in self.structure:
            for par in cand.parameters:
                if cand is candidate:
                    out.append(par.describe(float(self.values[i])))
                i += 1
        return out


class Evaluator:
    """Weighted residuals of parameter sets on the data (what a Barrier round runs)."""

    def __init__(self, data) -> None:
        self.data = data
        self.sets = 0

    def __call__(
        self, models: list[UnitParams | None]
    ) -> list[tuple[np.ndarray, np.ndarray] | None]:
        valid = [m for m in models if m is not None]
        predictions = iter(self.data.predict(valid) if valid else [])
        self.sets += len(valid)
        out: list[tuple[np.ndarray, np.ndarray] | None] = []
        for m in models:
            if m is None:
                out.append(None)
            else:
                p = next(predictions)
                # a set that cannot run the data (a thermal cycle's start above its As0) is no fit
                out.append(
                    (p.train, p.heldout)
                    if np.isfinite(p.train).all() and np.isfinite(p.heldout).all()
                    else None
                )
        return out


def _cost(r: np.ndarray) -> float:
    return float(np.mean(r**2)) if r.size else 0.0


def _job(space: Space, u0: np.ndarray, n_train: int, n_heldout: int, max_evaluations: int):
    """A least-squares fit of one structure from ``u0``, evaluating through the barrier."""

    def run(barrier: Barrier):
        cache: dict[bytes, tuple[np.ndarray, np.ndarray, float]] = {}

        def evaluate(u: np.ndarray) -> tuple[np.ndarray, np.ndarray, float]:
            key = u.tobytes()
            if key not in cache:
                steps = [u.copy()]
                for j in range(space.size):
                    v = u.copy()
                    v[j] += STEP if v[j] + STEP <= 1.0 else -STEP
                    steps.append(v)
                results = barrier([space.params(v) for v in steps])
                rows = [np.full(n_train, PENALTY) if r is None else r[0] for r in results]
                jac = np.stack(
                    [(rows[j + 1] - rows[0]) / (steps[j + 1][j] - u[j]) for j in range(space.size)],
                    axis=1,
                )
                held = (
                    _cost(np.full(n_heldout, PENALTY))
                    if results[0] is None
                    else _cost(results[0][1])
                )
                cache[key] = (rows[0], jac, held)
            return cache[key]

        res = least_squares(
            lambda u: evaluate(u)[0],
            u0,
            jac=lambda u: evaluate(u)[1],
            bounds=(0.0, 1.0),
            method="trf",
            x_scale=1.0,
            max_nfev=max_evaluations,
            ftol=1e-6,
            xtol=1e-6,
        )
        r, _, held = evaluate(res.x)
        # status 0: the evaluation limit, before any tolerance was met
        return res.x, _cost(r), held, len(cache), res.status > 0, res.message

    return run


def screen_points(k: int, n: int) -> np.ndarray:
    """``n`` quasi-random points of [0, 1]^k (Halton, unscrambled: the same every run)."""
    return qmc.Halton(d=k, scramble=False).random(n + 1)[1:]


def fit_structures(
    data,
    base: UnitParams,
    structures: Sequence[Structure],
    warm: dict[str, float],
    progress: Callable[[str], None] | None = None,
    starts: int = STARTS,
    max_evaluations: int = MAX_EVALUATIONS,
) -> list[Fit]:
    """Fit every structure on ``data``; the result keeps each structure's best start.

    ``warm``: normalised values of parameters already fitted (by key), the starting point
    of those coordinates; new coordinates are screened.
    """
    evaluator = Evaluator(data)
    n_train, n_heldout = _sizes(data, base)
    spaces = [Space(base, s) for s in structures]
    starts_of = _screen(spaces, warm, evaluator, starts)
    jobs, owners = [], []
    for i, (space, points) in enumerate(zip(spaces, starts_of)):
        for u0 in points:
            jobs.append(_job(space, u0, n_train, n_heldout, max_evaluations))
            owners.append(i)
    barrier = Barrier(evaluator)
    if progress:
        progress(f"fitting {len(spaces)} structure(s) from {len(jobs)} start(s)")
    # tens of fits in threads, each with small matrices: a multithreaded BLAS under each of them
    # spends the cores waiting on itself (benchmarks/bench_diagnose.py: 59 s against 5 s)
    with threadpool_limits(limits=1, user_api="blas"):
        results = barrier.run(jobs)
    best: dict[int, tuple] = {}
    for owner, result in zip(owners, results):
        if owner not in best or result[1] < best[owner][1]:
            best[owner] = result
    for i, space in enumerate(spaces):
        best[i] = _on_whole_steps(space, best[i], evaluator, data)
    fits = []
    for i, space in enumerate(spaces):
        u, train, held, n_eval, converged, stop = best[i]
        fits.append(
            Fit(
                space.structure,
                space.values(u),
                space.params(u) or base,
                train,
                held,
                n_train,
                pinned(space, u),
                n_eval,
                converged,
                stop,
                owners.count(i),
            )
        )
    return fits


def _on_whole_steps(space: Space, result: tuple, evaluator: Evaluator, data) -> tuple:
    """A fit with the input's timing, finished on the whole plant steps around it.

    The replay holds the input per plant step and moves it between steps in proportion, so
    the cost has a kink at every whole step, where a gradient step can stall (a 10 ms lag
    fitted as 8 ms). The timing at each whole step within TIMING_SCAN steps of the fit's,
    the other values kept, is tried; the best training cost wins."""
    timing = [j for j, c in enumerate(space.coords) if c.candidate.kind == "timing"]
    plans = getattr(data, "plans", None)
    if not timing or not plans:
        return result
    u, train, held, n_eval, converged, stop = result
    (j,) = timing
    coord, step = space.coords[j], plans[0].dt
    centre = round(coord.value(float(u[j])) / step)
    tried = []
    for k in range(centre - TIMING_SCAN, centre + TIMING_SCAN + 1):
        v = u.copy()
        v[j] = coord.unit(k * step)
        if 0.0 <= v[j] <= 1.0:
            tried.append(v)
    for v, r in zip(tried, evaluator([space.params(v) for v in tried])):
        if r is not None and _cost(r[0]) < train:
            u, train, held = v, _cost(r[0]), _cost(r[1])
    return u, train, held, n_eval + len(tried), converged, stop


def _sizes(data, base: UnitParams) -> tuple[int, int]:
    p = data.predict([base])[0]
    return p.train.size, p.heldout.size


def _screen(
    spaces: list[Space], warm: dict[str, float], evaluator: Evaluator, starts: int
) -> list[list[np.ndarray]]:
    """Start points of each structure: its screen's best, the known coordinates warm."""
    batch, owner, points = [], [], []
    for i, space in enumerate(spaces):
        known = np.array([c.parameter.key in warm for c in space.coords])
        base_u = np.array([warm.get(c.parameter.key, 0.5) for c in space.coords])
        new = int((~known).sum())
        grid = screen_points(new, 4 * new + 4) if new else np.zeros((1, 0))
        for g in grid:
            u = base_u.copy()
            u[~known] = g
            batch.append(space.params(u))
            owner.append(i)
            points.append(u)
    results = evaluator(batch)
    scored: dict[int, list] = {}
    for i, u, r in zip(owner, points, results):
        scored.setdefault(i, []).append((math.inf if r is None else _cost(r[0]), u))
    return [
        [u for _, u in sorted(scored[i], key=lambda x: x[0])[:starts]] for i in range(len(spaces))
    ]


def near_bounds(base: UnitParams, fit: Fit) -> list[str]:
    """Each fitted value within NEAR_BOUND of a bound (a share of its range) that is not where
    its candidate is absent, with that bound: the data may ask for more than the range holds."""
    space = Space(base, fit.structure)
    u = np.array(
        [
            c.unit(float(v)) if not (c.parameter.log and v <= 0) else 0.0
            for c, v in zip(space.coords, fit.values)
        ]
    )
    return [
        f"{c.parameter.describe(float(fit.values[j]))} within {NEAR_BOUND:.0%} of its {side}"
        for j, c, side in _at_bounds(space, u, NEAR_BOUND)
    ]


def pinned(space: Space, u: np.ndarray) -> list[str]:
    """Parameters at a bound that is not where the starting model has them."""
    return [
        f"{c.candidate.name}: {c.parameter.symbol} at its {side}"
        for _, c, side in _at_bounds(space, u, AT_BOUND)
    ]


def _at_bounds(space: Space, u: np.ndarray, within: float) -> list[tuple[int, Coordinate, str]]:
    """(index, coordinate, "lower|upper bound <value> <unit>") of each coordinate of ``u``
    within ``within`` of a bound where its candidate is not absent."""
    out = []
    for j, (c, x, off) in enumerate(zip(space.coords, u, space.off())):
        for bound, name in ((0.0, "lower"), (1.0, "upper")):
            if name == "lower" and c.parameter.lower_is_limit:
                continue
            if abs(x - bound) <= within and abs(off - bound) > within:
                side = f"{name} bound {c.parameter.display(c.value(bound)):.4g} {c.parameter.unit}"
                out.append((j, c, side.rstrip()))
    return out
