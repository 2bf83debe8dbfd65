"""Reference generators for the dissertation's test protocols (dissertation chapters 5 and 6).

Every generator returns ``(t, r)``: ``t = k Ts`` for k = 0 .. n-1 with n = round(duration/Ts)
(a 20 s test at 100 Hz is 2000 samples, the count behind the IAE sums of Table 5.3) and r in
SI units, metres of wire displacement or newtons of wire tension. Event times are rounded
to whole samples and constant segments are exactly constant, which the PI-PD switching and
:func:`hems_ros.control.metrics.step_segments` rely on.

Timing the dissertation leaves open, and the choice made here:

* Sine: ``base + p2p/2 (1 - cos 2 pi f t)``. The actuator only pulls, so the wave sits
  above the rest position and starts there with zero slope instead of demanding an
  instant jump to mid-stroke.
* Step pair, 70 s: up at 5 s and 35 s, each 5 s wide (5 + 5 + 25 + 5 + 30 s). The 5 s
  rest gives a baseline for the rise time, 30 s from onset to onset is the protocol, and
  25-30 s after each step lets the wire cool completely (cooling times are below 5 s).
  70 s is the duration the Table 5.3 IAE sums imply.
* Staircase, 70 s: four steps up and four down, one every 7.5 s from 5 s, so the last
  step down comes at 57.5 s and 12.5 s remain to cool to rest. The dwell is the longest
  that fits 70 s with the same 5 s baseline and a final rest of more than 10 s.
* Ramp (chapter 6): rise at 1 mm/s to 27 mm from 2 s, hold 5 s, come back down at the same
  rate, rest 10 s. Chapter 6 takes the RMSE on the rise only; the descent and the rest
  are there because the mean power covers the whole test.
* Force (chapter 6): levels are absolute wire tension between the rest tension of 2 N (the
  bias-spring pretension; lower forces cannot be reached because the wire cannot push)
  and 20 N, the largest amplitude reported.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import partial
from typing import Callable

import numpy as np

from hems_ros.control.base import DEFAULT_TS, check_positive

MM = 1e-3
CH5_STROKE = 20 * MM
CH6_STROKE = 27 * MM
CH6_RAMP_RATE = 1 * MM
CH6_FORCE_REST = 2.0
CH6_FORCE_PEAK = 20.0
SINE_DURATION = 20.0
STEP_TEST_DURATION = 70.0


def time_base(duration: float, ts: float = DEFAULT_TS) -> np.ndarray:
    """Sample times 0, Ts, ... covering ``duration`` seconds."""
    check_positive("duration", duration)
    check_positive("ts", ts)
    return np.arange(int(round(duration / ts))) * ts


def _sample(time: float, ts: float) -> int:
    return int(round(time / ts))


def sine(
    frequency: float,
    peak_to_peak: float,
    ts: float = DEFAULT_TS,
    duration: float = SINE_DURATION,
    base: float = 0.0,
) -> tuple[np.ndarray, np.ndarray]:
    """Return (t, ``base + p2p/2 (1 - cos 2 pi f t)``): from ``base`` at rest to base + p2p."""
    t = time_base(duration, ts)
    return t, base + 0.5 * peak_to_peak * (1.0 - np.cos(2.0 * np.pi * frequency * t))


def step_pair(
    height: float,
    ts: float = DEFAULT_TS,
    first: float = 5.0,
    width: float = 5.0,
    period: float = 30.0,
    duration: float = STEP_TEST_DURATION,
    base: float = 0.0,
) -> tuple[np.ndarray, np.ndarray]:
    """Two steps of ``height`` above ``base``, ``width`` s wide, onsets ``period`` s apart."""
    t = time_base(duration, ts)
    r = np.full(t.size, base)
    for onset in (first, first + period):
        r[_sample(onset, ts) : _sample(onset + width, ts)] = base + height
    return t, r


def staircase(
    step: float,
    ts: float = DEFAULT_TS,
    n_steps: int = 4,
    first: float = 5.0,
    dwell: float = 7.5,
    duration: float = STEP_TEST_DURATION,
    base: float = 0.0,
) -> tuple[np.ndarray, np.ndarray]:
    """``n_steps`` steps of ``step`` up, then down again, one every ``dwell`` s from ``first``."""
    t = time_base(duration, ts)
    r = np.full(t.size, base)
    for i in range(2 * n_steps):
        level = i + 1 if i < n_steps else 2 * n_steps - 1 - i
        r[_sample(first + i * dwell, ts) :] = base + level * step
    return t, r


def ramp(
    peak: float,
    rate: float,
    ts: float = DEFAULT_TS,
    start: float = 2.0,
    hold: float = 5.0,
    rest: float = 10.0,
    base: float = 0.0,
) -> tuple[np.ndarray, np.ndarray]:
    """Trapezoid: rise at ``rate`` from ``base`` to ``base + peak``, hold, descend, rest."""
    rise = peak / rate
    t = time_base(start + 2.0 * rise + hold + rest, ts)
    down = start + rise + hold
    profile = np.minimum(rate * (t - start), peak - rate * (t - down))
    return t, base + np.clip(profile, 0.0, peak)


@dataclass(frozen=True)
class Protocol:
    """One test of the dissertation.

    ``segment`` is where the RMSE is taken ("all" in chapter 5; "ascending" or
    "stationary" in chapter 6), see :func:`hems_ros.control.metrics.segment_mask`.
    """

    name: str
    chapter: int
    mode: str
    segment: str
    description: str
    make: Callable[[float], tuple[np.ndarray, np.ndarray]]

    def generate(self, ts: float = DEFAULT_TS) -> tuple[np.ndarray, np.ndarray]:
        """Return the protocol's (t, reference) sampled every ``ts`` seconds."""
        return self.make(ts)


def _protocols() -> dict[str, Protocol]:
    force_span = CH6_FORCE_PEAK - CH6_FORCE_REST
    rows = [
        *(
            Protocol(
                f"ch5_sine_{f}",
                5,
                "position",
                "all",
                f"sine 20 mm p-p at {f} Hz, 20 s",
                partial(sine, f, CH5_STROKE),
            )
            for f in (0.125, 0.25, 0.5)
        ),
        Protocol(
            "ch5_step",
            5,
            "position",
            "all",
            "two 20 mm steps 5 s wide, 30 s apart",
            lambda ts: step_pair(CH5_STROKE, ts),
        ),
        Protocol(
            "ch5_staircase",
            5,
            "position",
            "all",
            "0 -> 20 mm in 5 mm steps and back",
            lambda ts: staircase(CH5_STROKE / 4, ts),
        ),
        Protocol(
            "ch6_position_sine_0.125",
            6,
            "position",
            "ascending",
            "sine 27 mm p-p at 0.125 Hz",
            lambda ts: sine(0.125, CH6_STROKE, ts),
        ),
        Protocol(
            "ch6_position_ramp",
            6,
            "position",
            "ascending",
            "ramp to 27 mm at 1 mm/s and back",
            lambda ts: ramp(CH6_STROKE, CH6_RAMP_RATE, ts),
        ),
        Protocol(
            "ch6_position_step",
            6,
            "position",
            "stationary",
            "two 27 mm steps 5 s long, 30 s apart",
            lambda ts: step_pair(CH6_STROKE, ts),
        ),
        Protocol(
            "ch6_position_staircase",
            6,
            "position",
            "stationary",
            "4 x 6.75 mm up and down",
            lambda ts: staircase(CH6_STROKE / 4, ts),
        ),
        *(
            Protocol(
                f"ch6_force_sine_{f}",
                6,
                "force",
                "ascending",
                f"sine 2-20 N at {f} Hz",
                partial(sine, f, force_span, base=CH6_FORCE_REST),
            )
            for f in (0.125, 0.25)
        ),
        Protocol(
            "ch6_force_step",
            6,
            "force",
            "stationary",
            "two 2 -> 20 N steps 5 s long, 30 s apart",
            lambda ts: step_pair(force_span, ts, base=CH6_FORCE_REST),
        ),
        Protocol(
            "ch6_force_staircase",
            6,
            "force",
            "stationary",
            "2 -> 20 N in 4 steps and back",
            lambda ts: staircase(force_span / 4, ts, base=CH6_FORCE_REST),
        ),
    ]
    return {p.name: p for p in rows}


PROTOCOLS = _protocols()
"""All protocols by name: ch5_* (position, 40 N mass) and ch6_position_*, ch6_force_*."""
