"""The load relation: the wire force that the measured motion of the load calls for.

Both ends of the load are measured, the slider's position by the encoder and the wire's force
by the load cell, and whatever the wire is made of its force must move the load as the
load's own law says (eqs. 4.32-4.35, with the transmission losses of friction.py):

    F_wire = (F_L - f) / a,   F_L = F_static + m n x'' + b n x' + k n x + k3 n^3 x^3

with (a, f) the transmission of the last direction of motion. So friction, a stiffening
spring and extra damping show in the measured force against the measured motion alone,
without any model of the wire: a wire model of another family than the truth's, whose misfit
swamps these effects in the replayed outputs, can neither hide nor fake them here. The
diagnosis uses the relation twice (search.run_search): it names the load's effects on it
first, with the search's own selection rules, and it accepts no later term that makes the
relation worse than the noise allows (a sensor scale that absorbs a wire's stroke misfit).

Velocity and acceleration come from a Savitzky-Golay fit over ``SMOOTH_S``. Only samples
where the slider moves count: at rest, dry friction holds any force within its band (the
wire's force rises through it before the load moves), so the relation fixes nothing there.
Moving means faster than ``SPEED_NOISE`` times the velocity's noise (the position's noise
floor through the derivative filter) over the whole smoothing window. A force offset or
drift (the load cell's, or a pretension other than the model's) and a spring rate other
than the model's (or an encoder's scale) look alike on the relation, so its fits and
costs leave them out (each run's residual taken apart from a constant, the time and the
position); the replay decides those. Costs are mean
squared residuals over the relation's own noise floor (dataset.noise_floor of the starting
model's residual).
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from typing import Callable, Sequence

import numpy as np
from scipy.ndimage import binary_erosion
from scipy.optimize import least_squares
from scipy.signal import savgol_coeffs, savgol_filter

from hems_ros.diagnosis.candidates import Candidate
from hems_ros.diagnosis.dataset import TimeSeriesData, noise_floor
from hems_ros.diagnosis.fit import Fit, Space, pinned
from hems_ros.diagnosis.intervals import Intervals, estimate_on, independence
from hems_ros.physics.friction import capstan_ratio
from hems_ros.physics.loads import referred_load, transmission
from hems_ros.physics.params import UnitParams

#: The load's effects the relation names (each changes the force the motion calls for).
NAMES = ("tendon_friction", "capstan_friction", "spring_stiffening", "load_damping")
#: Window of the velocity and acceleration estimate: long against the sensors' noise
#: correlation, short against a stroke (0.5-2 s).
SMOOTH_S = 0.2
#: The slider moves where its speed exceeds this many standard deviations of the velocity's
#: noise (white; a coloured noise's is larger, hence the wide margin) ...
SPEED_NOISE = 5.0
#: ... and at least this speed (m/s): an encoder count per ten samples at 1 ms.
MIN_SPEED_M_S = 1e-4
#: Runs of these kinds hold the wire in a frame or under a dead weight: no load law to check.
FRAME_KINDS = ("thermal_cycle", "prescribed_strain")


@dataclass(frozen=True)
class Motion:
    """One run's samples where the slider slides all through the smoothing window around
    them: the motion as measured and smoothed, and the force as measured."""

    time: np.ndarray
    position: np.ndarray  # m, as the encoder reads it (its gain in)
    velocity: np.ndarray
    acceleration: np.ndarray
    direction: np.ndarray  # +1 pulling in, -1 paying out
    force: np.ndarray  # N, as the load cell reads it
    train: np.ndarray  # bool masks of the data's split
    heldout: np.ndarray
    # orthonormal columns spanning what the relation cannot tell apart (``apart``)
    nuisance: np.ndarray


def predicted_force(params: UnitParams, m: Motion) -> np.ndarray:
    """The load cell's reading the load law of ``params`` calls for, for the motion ``m``."""
    load = params.load
    gain = params.encoder.gain
    x, v, a = m.position / gain, m.velocity / gain, m.acceleration / gain
    mass_n, damping_n, stiffness_n, cubic_n = referred_load(
        load.mass_kg,
        load.damping_n_s_per_m,
        load.stiffness_n_per_m,
        load.pulley_ratio,
        load.cubic_stiffness_n_per_m3,
    )
    to_load = load.static_force_n() + mass_n * a + damping_n * v + stiffness_n * x + cubic_n * x**3
    capstan = (
        capstan_ratio(params.capstan.friction_coefficient, params.capstan.bend_angle_rad)
        if params.capstan.enabled
        else 1.0
    )
    coulomb = params.glove_friction.force_n if params.glove_friction.enabled else 0.0
    a_in, f_in, a_out, f_out = transmission(capstan, load.pulley_ratio, coulomb)
    wire = np.where(m.direction > 0, (to_load - f_in) / a_in, (to_load - f_out) / a_out)
    sensor = params.force_sensor
    return wire + sensor.offset_n + sensor.drift_n_per_s * m.time


@dataclass(frozen=True)
class Named:
    """What the load relation named: the starting model's fit on it, one fit per effect named
    (in order), every effect's fit at the first step (best BIC first) and the relation's
    noise floor (N)."""

    start: Fit
    steps: tuple[Fit, ...]
    ranked: tuple[Fit, ...]
    sigma_n: float
    intervals: Intervals | None
    # the values refitted on the replayed outputs (search.run_search), where the wire's model
    # replays the runs well enough to leave the relation as good; False: the relation's values
    refined: bool = False

    @property
    def final(self) -> Fit:
        return self.steps[-1] if self.steps else self.start


class LoadRelation:
    """The relation's residuals for parameter sets, on the data's training and held-out
    samples, in units of its noise floor."""

    def __init__(
        self, motions: Sequence[Motion], base: UnitParams, wider: LoadRelation | None = None
    ) -> None:
        self.motions = list(motions)
        self.wider = wider
        residual = np.concatenate([m.force - predicted_force(base, m) for m in self.motions])
        self.sigma = noise_floor(residual, 0.0, "wire_force")
        self.n_train = int(sum(m.train.sum() for m in self.motions))

    def _parts(self, params: UnitParams, apart: bool) -> list[np.ndarray]:
        """Each run's residual in noise-floor units; ``apart``: with what the relation cannot
        tell apart removed (a force offset and drift, a spring rate)."""
        parts = [(m.force - predicted_force(params, m)) / self.sigma for m in self.motions]
        if apart:
            parts = [r - m.nuisance @ (m.nuisance.T @ r) for r, m in zip(parts, self.motions)]
        return parts

    def residuals(self, params: UnitParams, apart: bool = True) -> tuple[np.ndarray, np.ndarray]:
        """(training, held-out) residuals (``_parts``)."""
        parts = self._parts(params, apart)
        return (
            np.concatenate([r[m.train] for r, m in zip(parts, self.motions)]),
            np.concatenate([r[m.heldout] for r, m in zip(parts, self.motions)]),
        )

    def training(self, sets: list[UnitParams]) -> tuple[list[np.ndarray], float]:
        """Training residuals of each set, and the effective sample count of the first's
        (intervals.estimate_on): the force's noise is coloured."""
        first = [r[m.train] for r, m in zip(self._parts(sets[0], True), self.motions)]
        trains = [np.concatenate(first)] + [self.residuals(p)[0] for p in sets[1:]]
        return trains, float(sum(r.size * independence(r) for r in first))

    def costs(self, params: UnitParams, apart: bool = True) -> tuple[float, float]:
        """(training, held-out) mean squared residual (``residuals``)."""
        train, heldout = self.residuals(params, apart)
        return float(np.mean(train**2)), float(np.mean(heldout**2))

    def fit(self, base: UnitParams, structure: tuple[Candidate, ...], warm: Fit | None) -> Fit:
        """The structure's values that fit the relation best (training samples)."""
        space = Space(base, structure)
        known = 0 if warm is None else warm.values.size  # the terms already named: kept as start
        off = space.off()
        u0 = np.full(space.size, 0.5)
        if warm is not None:
            u0[:known] = [c.unit(v) for c, v in zip(space.coords, warm.values)]
        absent = np.concatenate([u0[:known], off[known:]])

        def residual(u: np.ndarray) -> np.ndarray:
            params = space.params(u)
            return self.residuals(params)[0] if params is not None else np.full(self.n_train, 1e3)

        runs = [least_squares(residual, s, bounds=(0.0, 1.0), x_scale=0.1) for s in (u0, absent)]
        best = min(runs, key=lambda r: r.cost)
        params = space.params(best.x) or base
        train, heldout = self.costs(params)
        return Fit(
            structure,
            space.values(best.x),
            params,
            train,
            heldout,
            self.n_train,
            pinned(space, best.x),
            sum(r.nfev for r in runs),
            bool(best.success),
            str(best.message),
            len(runs),
        )


def of(data, base: UnitParams) -> LoadRelation | None:
    """The relation on the data's runs that measure both position and wire force under the
    load's own law, or None when there are none. Its ``wider`` twin smooths the motion over
    twice the window: how far a value moves between the two is how far the smoothing (its
    lag, and the noise it leaves in the velocity, which pulls a fitted coefficient towards
    zero) can have moved it."""
    motions = _motions(data, SMOOTH_S)
    wider = _motions(data, 2.0 * SMOOTH_S)
    if not (_usable(motions) and _usable(wider)):
        return None
    return LoadRelation(motions, base, LoadRelation(wider, base))


def _usable(motions: list[Motion]) -> bool:
    return any(m.train.any() for m in motions) and any(m.heldout.any() for m in motions)


def _motions(data, smooth_s: float) -> list[Motion]:
    if not isinstance(data, TimeSeriesData):
        return []
    motions = []
    for run, train, heldout in zip(data.runs, data.split.train, data.split.heldout):
        if run.kind in FRAME_KINDS or not {"position", "wire_force"} <= run.outputs.keys():
            continue
        step = float(np.median(np.diff(run.time)))
        window = 2 * int(round(smooth_s / step / 2)) + 1
        if run.n_samples <= 2 * window:
            continue
        x = run.outputs["position"]
        inner = slice(window // 2, run.n_samples - window // 2)  # the window lies inside
        velocity = savgol_filter(x, window, 3, deriv=1, delta=step)
        speed_noise = data.sigma.get("position", 0.0) * float(
            np.linalg.norm(savgol_coeffs(window, 3, deriv=1, delta=step))
        )
        fast = np.zeros(run.n_samples, bool)
        fast[inner] = np.abs(velocity[inner]) > max(SPEED_NOISE * speed_noise, MIN_SPEED_M_S)
        # a window that reaches into a stop smears the stop into its derivatives
        moving = binary_erosion(fast, np.ones(window, bool))
        position = savgol_filter(x, window, 3)[moving]
        time = run.time[moving]
        motions.append(
            Motion(
                time,
                position,
                velocity[moving],
                savgol_filter(x, window, 3, deriv=2, delta=step)[moving],
                np.sign(velocity[moving]),
                run.outputs["wire_force"][moving],
                train[moving],
                heldout[moving],
                np.linalg.qr(np.column_stack([np.ones(time.size), time, position]))[0],
            )
        )
    return motions


def name_effects(
    relation: LoadRelation,
    base: UnitParams,
    candidates: Sequence[Candidate],
    better: Callable[[Fit, Fit, Fit], bool],
    say: Callable[[str], None],
) -> Named:
    """Forward selection of the load's effects on the relation alone, by ``better``."""
    train, heldout = relation.costs(base)
    start = Fit((), np.zeros(0), base, train, heldout, relation.n_train, [])
    current, chosen, first = start, [], list[Fit]()
    pool = [c for c in candidates if c.name in NAMES]
    say(f"load relation: held-out cost {heldout:.3g} (1 = its noise floor, {relation.sigma:.3g} N)")
    while pool:
        fits = sorted(
            (relation.fit(base, current.structure + (c,), current) for c in pool),
            key=lambda f: f.bic,
        )
        first = first or fits
        best = next((f for f in fits if better(f, current, start)), None)
        if best is None:
            break
        say(
            f"  load relation names {best.structure[-1].name} "
            f"({', '.join(best.describe(best.structure[-1]))}): held-out cost "
            f"{current.heldout:.3g} -> {best.heldout:.3g}"
        )
        chosen.append(best)
        pool = [c for c in pool if c is not best.structure[-1]]
        current = best
    return Named(
        start, tuple(chosen), tuple(first), relation.sigma, _intervals(relation, base, current)
    )


def _intervals(relation: LoadRelation, base: UnitParams, fit: Fit) -> Intervals | None:
    """The fit's intervals from the relation's residual, widened either way by how far the
    values move when the motion is smoothed over twice the window (``of``)."""
    found = estimate_on(relation.training, base, fit)
    if found is None or relation.wider is None:
        return found
    moved = np.abs(relation.wider.fit(base, fit.structure, fit).values - fit.values)
    space = Space(base, fit.structure)
    return replace(
        found,
        lower=np.maximum(found.lower - moved, [c.lower for c in space.coords]),
        upper=np.minimum(found.upper + moved, [c.upper for c in space.coords]),
    )
