"""Figures of merit of chapters 5 and 6 (dissertation chapters 5 and 6).

Arrays are 1-D numpy arrays sampled at the control period; r and y share a unit (SI unless
scaled by the caller) and u is the duty in %. Errors are r - y.

* RMSE = sqrt(mean((r - y)^2)), optionally over a segment mask.
* IAE twice: :func:`iae_integral` is the time integral of |e| (trapezoid rule, unit of e
  times s); :func:`iae_sum` is the dissertation's sum of |e| over samples. Table 5.3 is
  that sum with e in mm at Ts = 10 ms, i.e. ``iae_sum(r, y, scale=1e3)`` on SI data.
* MACSI = mean |u(i+1) - u(i)|, APC = sqrt(mean(u^2)) / 100 * I^2 R with I = 4 A,
  R = 4.2 ohm.
* Step figures on the segments between reference jumps (:func:`step_segments`): rise time
  10-90 % (the dissertation does not state its definition; 10-90 % is the usual one and
  both fractions are parameters), overshoot (the first peak past the new level, in the
  unit of y), hold excursion (the largest excursion past the level anywhere in the segment,
  which also counts a later ripple about the level: chapter 6 reports that oscillation
  apart from "no overshoot"), steady-state error |mean(r - y)| over the last ``window``
  seconds of the segment (a bias, separate from the oscillation).
* Chapter 6 takes RMSE on ascending parts (sine, ramp) or stationary parts (steps):
  :func:`ascending_mask`, :func:`stationary_mask`, :func:`segment_mask`.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np
from numpy.typing import ArrayLike, NDArray

APC_CURRENT = 4.0
APC_RESISTANCE = 4.2


def _arrays(*arrays: ArrayLike) -> list[NDArray[np.float64]]:
    out = [np.asarray(a, dtype=float) for a in arrays]
    n = out[0].shape
    for a in out:
        if a.ndim != 1 or a.shape != n:
            raise ValueError("signals must be 1-D arrays of equal length")
    return out


def rms(e: ArrayLike) -> float:
    """Root mean square of the residuals ``e`` (nan if there are none)."""
    e = np.asarray(e, dtype=float).ravel()
    return float(np.sqrt(np.mean(e * e))) if e.size else math.nan


def rmse(r: ArrayLike, y: ArrayLike, mask: ArrayLike | None = None) -> float:
    """Root mean square of r - y, over ``mask`` if given (nan if the mask is empty)."""
    r, y = _arrays(r, y)
    e = r - y
    if mask is not None:
        e = e[np.asarray(mask, dtype=bool)]
    return rms(e)


def iae_integral(t: ArrayLike, r: ArrayLike, y: ArrayLike) -> float:
    """Time integral of |r - y| by the trapezoid rule."""
    t, r, y = _arrays(t, r, y)
    a = np.abs(r - y)
    return float(np.sum(0.5 * (a[1:] + a[:-1]) * np.diff(t)))


def iae_sum(r: ArrayLike, y: ArrayLike, scale: float = 1.0) -> float:
    """Sum over samples of |r - y| * scale (the dissertation's IAE; scale 1e3 for mm)."""
    r, y = _arrays(r, y)
    return float(np.sum(np.abs(r - y)) * scale)


def macsi(u: ArrayLike) -> float:
    """Mean absolute control signal increment, in % duty per sample."""
    (u,) = _arrays(u)
    return float(np.mean(np.abs(np.diff(u))))


def apc(u: ArrayLike, current: float = APC_CURRENT, resistance: float = APC_RESISTANCE) -> float:
    """Average power consumption in W: sqrt(mean(u^2)) / 100 * I^2 R."""
    (u,) = _arrays(u)
    return float(np.sqrt(np.mean(u * u)) / 100.0 * current**2 * resistance)


class StepSegment(NamedTuple):
    """Samples [start, stop) after a reference jump from ``before`` to ``after``."""

    start: int
    stop: int
    before: float
    after: float


def step_segments(r: ArrayLike) -> list[StepSegment]:
    """Segments from each jump of a piecewise-constant reference to the next change.

    A jump is a change r(k) != r(k-1) with the reference constant on both sides, so the
    samples of a ramp or sine, including its first and last, do not count as steps.
    """
    (r,) = _arrays(r)
    changes = np.flatnonzero(r[1:] != r[:-1]) + 1
    segments = []
    for i, k in enumerate(changes):
        stop = int(changes[i + 1]) if i + 1 < len(changes) else r.size
        constant_before = i == 0 or changes[i - 1] < k - 1
        if constant_before and stop - k >= 2:
            segments.append(StepSegment(int(k), stop, float(r[k - 1]), float(r[k])))
    return segments


def rise_time(
    t: ArrayLike, y: ArrayLike, seg: StepSegment, lo: float = 0.1, hi: float = 0.9
) -> float:
    """Time from ``lo`` to ``hi`` of the jump within ``seg`` (fractions); nan if not reached."""
    t, y = _arrays(t, y)
    sign = 1.0 if seg.after >= seg.before else -1.0
    span = seg.after - seg.before
    progress = sign * (y[seg.start : seg.stop] - seg.before)
    reached_lo = np.flatnonzero(progress >= sign * lo * span)
    reached_hi = np.flatnonzero(progress >= sign * hi * span)
    if reached_lo.size == 0 or reached_hi.size == 0:
        return math.nan
    return float(t[seg.start + reached_hi[0]] - t[seg.start + reached_lo[0]])


def _past_level(y: ArrayLike, seg: StepSegment) -> NDArray[np.float64]:
    """How far y is past the new level of ``seg`` in the direction of the jump (+ = beyond)."""
    (y,) = _arrays(y)
    sign = 1.0 if seg.after >= seg.before else -1.0
    return sign * (y[seg.start : seg.stop] - seg.after)


def overshoot(y: ArrayLike, seg: StepSegment) -> float:
    """Return the first peak of y past the new level (>= 0).

    The peak is the largest excursion from the first sample at or beyond the level to the
    next sample back short of it (or the segment's end).

    A response that stays beyond the level (an SMA wire held there by its hysteresis) counts
    in full; a later ripple about the level once it came back does not (:func:`hold_excursion`).
    """
    past = _past_level(y, seg)
    reached = np.flatnonzero(past >= 0)
    if reached.size == 0:
        return 0.0
    first = int(reached[0])
    back = np.flatnonzero(past[first:] < 0)
    end = past.size if back.size == 0 else first + int(back[0])
    return float(past[first:end].max())


def hold_excursion(y: ArrayLike, seg: StepSegment) -> float:
    """Largest excursion of y past the new level anywhere in ``seg`` (>= 0)."""
    return float(max(0.0, np.max(_past_level(y, seg))))


def steady_state_error(
    t: ArrayLike, r: ArrayLike, y: ArrayLike, seg: StepSegment, window: float = 1.0
) -> float:
    """|mean(r - y)| over the last ``window`` seconds of ``seg``."""
    t, r, y = _arrays(t, r, y)
    k = np.arange(seg.start, seg.stop)
    k = k[t[k] >= t[seg.stop - 1] - window]
    return float(abs(np.mean(r[k] - y[k])))


def ascending_mask(r: ArrayLike) -> NDArray[np.bool_]:
    """Mark where the reference rises, r(k) > r(k-1); the first sample is False."""
    (r,) = _arrays(r)
    mask = np.zeros(r.size, dtype=bool)
    mask[1:] = r[1:] > r[:-1]
    return mask


def stationary_mask(
    t: ArrayLike, r: ArrayLike, settle: float = 1.0, min_level: float | None = None
) -> NDArray[np.bool_]:
    """Mark where the reference has been constant for at least ``settle`` seconds.

    The start of the record counts as a change, so the first ``settle`` seconds are
    excluded. ``min_level`` keeps only samples with r > min_level, e.g. the raised
    plateaus of a step test without the rest level the wire cools back to.
    Chapter 6 reports step RMSE of 0.07 mm, so its "stationary parts" exclude the rise
    (0.84 s); the default settle of 1 s does that.
    """
    t, r = _arrays(t, r)
    changed = np.ones(r.size, dtype=bool)
    changed[1:] = r[1:] != r[:-1]
    last_change = np.maximum.accumulate(np.where(changed, np.arange(r.size), 0))
    mask = t - t[last_change] >= settle
    if min_level is not None:
        mask &= r > min_level
    return mask


def segment_mask(
    kind: str, t: ArrayLike, r: ArrayLike, settle: float = 1.0, min_level: float | None = None
) -> NDArray[np.bool_]:
    """Mask for ``kind`` "all", "ascending" or "stationary" (see the protocols' ``segment``)."""
    if kind == "all":
        (r,) = _arrays(r)
        return np.ones(r.size, dtype=bool)
    if kind == "ascending":
        return ascending_mask(r)
    if kind == "stationary":
        return stationary_mask(t, r, settle=settle, min_level=min_level)
    raise ValueError(f"segment kind must be 'all', 'ascending' or 'stationary', got {kind!r}")
