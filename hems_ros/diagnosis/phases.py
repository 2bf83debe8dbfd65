"""Phases and cycles of a measured run, from its input and its motion.

Phases (candidates.PHASES) say where in an actuation cycle a sample lies:

- ``heating``: the drive is on and the wire has not started to move (it warms towards As);
- ``transformation``: the wire contracts (or, in a thermal cycle, its strain changes fast);
- ``hold``: the drive is on and the wire stays contracted (a controller holding a level);
- ``cooling``: the drive is off (or the wire extends) and it has not come back to rest;
- ``rest``: the drive is off and the wire is back at rest.

A cycle starts where the drive comes on again after the wire was back near rest with the
drive off (or, in a run that never gets back to rest, after the drive was off for a second);
when no held-out run is given, whole cycles are kept from the fit (every third from the
second to select the terms, every third from the third to test them in a run long enough),
so that early cycles (a warm start) and late ones (heat building up) are in every role.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from hems_ros.diagnosis.candidates import COOLING, HEATING, HOLD, PHASES, REST, TRANSFORMATION
from hems_ros.diagnosis.runs import TimeSeriesRun

#: Drive above which a run counts as heated (% duty, A, V).
ON_THRESHOLD = {"duty": 0.5, "current": 0.05, "voltage": 0.1}
SMOOTHING_S = 0.1
#: A motion slower than this share of the stroke per second is no motion.
STILL_FRACTION_PER_S = 0.03
#: Near rest: within this share of the stroke of the lowest level.
REST_FRACTION = 0.1
MIN_OFF_S = 0.3
#: Without returns to rest, a cycle starts after the drive was off this long.
LONG_OFF_S = 1.0
MIN_CYCLES = 3
#: A test role of its own only when it leaves this many cycles (or table rows) to fit: fitted
#: on two cycles, a hidden damping's estimate scattered three times as much as on three.
MIN_FIT_CYCLES = 3
#: A thermal cycle turns where the temperature reverses by this share of its range.
TURN_FRACTION = 0.1


@dataclass(frozen=True)
class Segmentation:
    """Phase index (into PHASES) and cycle number of every sample of one run."""

    phase: np.ndarray
    cycle: np.ndarray

    @property
    def n_cycles(self) -> int:
        return int(self.cycle.max()) + 1 if self.cycle.size else 0

    def mask(self, phase: str) -> np.ndarray:
        return self.phase == PHASES.index(phase)


def motion(run: TimeSeriesRun) -> np.ndarray:
    """The run's measure of contraction: position, else minus the strain, else the force."""
    for name, sign in (
        ("position", 1.0),
        ("strain", -1.0),
        ("wire_force", 1.0),
        ("load_force", 1.0),
        ("temperature", 1.0),
    ):
        if name in run.outputs:
            return sign * run.outputs[name]
    raise ValueError(f"{run.name}: no output to segment")


def _smooth(t: np.ndarray, y: np.ndarray, window_s: float) -> np.ndarray:
    """Moving average over ``window_s`` (in samples of the median spacing)."""
    spacing = float(np.median(np.diff(t))) if t.size > 1 else 1.0
    n = max(1, int(round(window_s / spacing)))
    if n <= 1 or y.size < n:
        return y.astype(float)
    kernel = np.ones(n) / n
    padded = np.concatenate([np.full(n // 2, y[0]), y, np.full(n - 1 - n // 2, y[-1])])
    return np.convolve(padded, kernel, mode="valid")


def segment(run: TimeSeriesRun) -> Segmentation:
    """Phases and cycles of ``run``."""
    if run.drive == "temperature":
        return _segment_thermal(run)
    t = run.time
    m = _smooth(t, motion(run), SMOOTHING_S)
    v = np.gradient(m, t)
    low, high = np.percentile(m, 1), np.percentile(m, 99)
    stroke = max(high - low, 1e-12)
    still = STILL_FRACTION_PER_S * stroke
    near_rest = m <= low + REST_FRACTION * stroke
    on = run.drive_values > ON_THRESHOLD[run.drive]
    phase = np.full(t.size, PHASES.index(REST))
    phase[on & near_rest & (np.abs(v) <= still)] = PHASES.index(HEATING)
    phase[on & ~near_rest & (np.abs(v) <= still)] = PHASES.index(HOLD)
    phase[(~on & ~near_rest) | (v < -still)] = PHASES.index(COOLING)
    phase[v > still] = PHASES.index(TRANSFORMATION)
    starts = _cycle_starts(t, on, near_rest, MIN_OFF_S)
    if len(starts) < MIN_CYCLES:
        # a wire that never gets back to rest (heat building up): cycles by the drive alone
        starts = _cycle_starts(t, on, np.ones_like(near_rest), LONG_OFF_S)
    if on.any() and (not starts or starts[0] > int(np.argmax(on))):
        # the first actuation opens the first cycle whatever came before it
        starts = [int(np.argmax(on))] + starts
    merged = _merge_blips(starts, near_rest)
    return Segmentation(phase, _number(t.size, merged if len(merged) >= MIN_CYCLES else starts))


def _merge_blips(starts: list[int], near_rest: np.ndarray) -> list[int]:
    """Join a cycle that never leaves the rest band (a controller's short pulse on a wire that
    cooled a little below its zero) to the cycle after it: alone it would be a held-out
    cycle with nothing in it. Kept apart when joining leaves too few cycles to hold one out."""
    bounds = starts + [near_rest.size]
    kept: list[int] = []
    for k in range(len(starts)):
        if kept and near_rest[bounds[k - 1] : bounds[k]].all():
            continue  # the previous cycle was a blip: it runs on into this one
        kept.append(starts[k])
    return kept


def _cycle_starts(
    t: np.ndarray, on: np.ndarray, near_rest: np.ndarray, min_off_s: float
) -> list[int]:
    """Samples where the drive comes on after at least ``min_off_s`` off with the wire near rest."""
    starts, off_since = [], None
    for k in range(t.size):
        if not on[k]:
            if off_since is None and near_rest[k]:
                off_since = t[k]
            elif not near_rest[k]:
                off_since = None
        else:
            if off_since is not None and t[k] - off_since >= min_off_s:
                starts.append(k)
            off_since = None
    return starts


def _number(n: int, starts: list[int]) -> np.ndarray:
    """Cycle number per sample; what comes before the first start belongs to the first cycle."""
    cycle = np.zeros(n, dtype=np.int64)
    for i, k in enumerate(starts[1:], start=1):
        cycle[k:] = i
    return cycle


def _segment_thermal(run: TimeSeriesRun) -> Segmentation:
    """A run driven by temperature: heating / cooling from the temperature, transformation
    where the strain (or force) changes fast; a cycle starts at each temperature minimum."""
    t = run.time
    temp = _smooth(t, run.drive_values, SMOOTHING_S)
    dtemp = np.gradient(temp, t)
    m = _smooth(t, motion(run), SMOOTHING_S)
    stroke = max(np.percentile(m, 99) - np.percentile(m, 1), 1e-12)
    rate = np.abs(np.gradient(m, t)) / np.maximum(np.abs(dtemp), 1e-12)
    span = max(np.ptp(temp), 1e-12)
    # faster than a stroke spread over the whole temperature range: transforming
    fast = rate > 2.0 * stroke / span
    phase = np.full(t.size, PHASES.index(REST))
    phase[dtemp > 0] = PHASES.index(HEATING)
    phase[dtemp < 0] = PHASES.index(COOLING)
    phase[fast & (dtemp != 0)] = PHASES.index(TRANSFORMATION)
    return Segmentation(phase, _number(t.size, [0] + _valleys(temp, TURN_FRACTION * span)))


def _valleys(values: np.ndarray, turn: float) -> list[int]:
    """Indices of the minima after which ``values`` rises by at least ``turn`` again (and
    before which it fell by as much): the turning points of a path, not its noise."""
    valleys, falling = [], False
    low = high = 0
    for k in range(1, values.size):
        if falling:
            if values[k] < values[low]:
                low = k
            elif values[k] - values[low] >= turn:
                valleys.append(low)
                falling, high = False, k
        else:
            if values[k] > values[high]:
                high = k
            elif values[high] - values[k] >= turn:
                falling, low = True, k
    return valleys


def cycle_roles(n_cycles: int) -> tuple[list[int], list[int]]:
    """The cycles that select the terms, every third from the second (0-based 1, 4, 7 ...), and
    those that test them, every third from the third (2, 5 ...) when MIN_FIT_CYCLES are left to
    fit (none otherwise); neither below MIN_CYCLES."""
    if n_cycles < MIN_CYCLES:
        return [], []
    select, test = list(range(1, n_cycles, 3)), list(range(2, n_cycles, 3))
    if n_cycles - len(select) - len(test) < MIN_FIT_CYCLES:
        return select, []
    return select, test
