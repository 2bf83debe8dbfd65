"""The scripted grasp and its summary (plain Python, no ROS).

Phases per finger (tendon side): approach in position mode to ``approach_m``, hold
``force_n`` in force mode, release to position 0. The summary of a recorded run gives per
finger: position tracking error over the approach and over its end, force tracking error
over the hold and over its end, peak tendon force, and the electrical energy spent.

Each phase is measured from the sample whose control step first used its setpoint, found in
the controller status (:class:`PhaseTracker`). Windows counted from the time the setpoint was
sent caught the transient up to one control period early or late, which moved a whole-phase
error by a few per cent from run to run.
"""

from __future__ import annotations

from collections.abc import Iterable
from dataclasses import dataclass
from os import PathLike

import numpy as np
from numpy.typing import ArrayLike

from hems_ros.control import metrics


@dataclass(frozen=True)
class GraspPlan:
    force_n: float = 10.0
    approach_m: float = 0.02
    approach_s: float = 5.0
    hold_s: float = 6.0
    release_s: float = 4.0
    settle_window_s: float = 1.0

    def phases(self) -> list[tuple[str, str, float, float]]:
        """(name, mode, value, duration s) in order."""
        return [
            ("approach", "position", self.approach_m, self.approach_s),
            ("hold", "force", self.force_n, self.hold_s),
            ("release", "position", 0.0, self.release_s),
        ]


@dataclass
class FingerTrace:
    """Time series of one finger (s, tendon m, tendon N, J, %) gathered during the run."""

    t: list[float]
    position_m: list[float]
    force_n: list[float]
    energy_t: list[float]  # stamps of the unit's state messages, s
    energy_j: list[float]  # the unit's Joule heat since it started, at those messages
    duty_t: list[float]
    duty_percent: list[float]

    @classmethod
    def empty(cls) -> "FingerTrace":
        return cls([], [], [], [], [], [], [])


@dataclass(frozen=True)
class FingerSummary:
    finger: str
    position_rmse_mm: float  # over the last settle window of the approach
    force_rmse_n: float  # over the last settle window of the hold
    peak_force_n: float
    energy_j: float
    approach_rmse_mm: float  # over the whole approach, rise included
    hold_rmse_n: float  # over the whole hold, force build-up included


def change_over(t: ArrayLike, y: ArrayLike, start: float, end: float) -> float:
    """y(end) - y(start), each interpolated between the two samples that bracket it; NaN when the
    samples do not reach over both instants (a reader that matched late, a run cut short)."""
    t, y = np.asarray(t, dtype=float), np.asarray(y, dtype=float)
    if t.size == 0 or t[0] > start or t[-1] < end:
        return float("nan")
    return float(np.interp(end, t, y) - np.interp(start, t, y))


def _window_rmse(t: np.ndarray, y: np.ndarray, target: float, start: float, end: float) -> float:
    # half a microsecond of slack: stamps pass through float seconds on both sides
    mask = (t >= start - 5e-7) & (t < end - 5e-7)
    return metrics.rms(y[mask] - target)


class PhaseTracker:
    """Phase starts of one finger from its controller status stream, message by message."""

    def __init__(self) -> None:
        self.starts: list[float] = []
        self._phase: tuple[str, float] | None = None

    def feed(
        self, mode: str, setpoint: float, active: bool, encoder_stamp_s: float, force_stamp_s: float
    ) -> None:
        """One status: a new (mode, setpoint) while active starts a phase at the stamp of the
        reading that step used; steps before the first non-zero setpoint are not the grasp."""
        phase = (mode, float(setpoint))
        if not active or phase == self._phase or (self._phase is None and phase[1] <= 0.0):
            return
        self._phase = phase
        self.starts.append(encoder_stamp_s if mode == "position" else force_stamp_s)


def phase_windows(plan: GraspPlan, phase_starts: list[float]) -> list[tuple[float, float]]:
    """(start, end) of each phase: to the next phase's start (the last lasts its
    planned duration)."""
    durations = [p[3] for p in plan.phases()]
    ends = phase_starts[1:] + [phase_starts[-1] + durations[len(phase_starts) - 1]]
    return list(zip(phase_starts, ends))


def summarize(
    finger: str, trace: FingerTrace, plan: GraspPlan, phase_starts: list[float]
) -> FingerSummary:
    """``phase_starts``: stamps (s) of the samples that began the approach, hold and release
    (:class:`PhaseTracker`)."""
    t = np.asarray(trace.t)
    x = np.asarray(trace.position_m)
    f = np.asarray(trace.force_n)
    windows = phase_windows(plan, phase_starts)
    (a0, a1), (h0, h1) = windows[:2]
    settle = plan.settle_window_s
    pos = _window_rmse(t, x, plan.approach_m, a1 - settle, a1)
    force = _window_rmse(t, f, plan.force_n, h1 - settle, h1)
    # from the unit's own accumulator over the whole grasp: integrating sampled power aliases
    # the 100 Hz duty changes
    energy = change_over(trace.energy_t, trace.energy_j, a0, windows[-1][1])
    peak = float(np.nanmax(f)) if len(f) else float("nan")
    return FingerSummary(
        finger,
        1e3 * pos,
        force,
        peak,
        energy,
        1e3 * _window_rmse(t, x, plan.approach_m, a0, a1),
        _window_rmse(t, f, plan.force_n, h0, h1),
    )


FOLLOW_FRACTION = 0.1
"""A finger whose error over the last settle window of the approach or the hold exceeds this
fraction of the setpoint did not follow it (normal demo runs: about 0.3 % and 0.2 %)."""


def tracking_report(
    rows: list[FingerSummary], plan: GraspPlan, fingers: Iterable[str]
) -> str | None:
    """Which of ``fingers`` did not follow their setpoints (a run with one is not valid), or None.

    The supervisor does not see this: a unit that never heats (no ENABLED status reached it,
    say) faults nothing, and its finger just stays where it was.
    """
    summarized = {r.finger for r in rows}
    bad = [
        f"{f} has no summary (its controller did not run every phase)"
        for f in fingers
        if f not in summarized
    ]
    for r in rows:
        if (
            not r.position_rmse_mm <= FOLLOW_FRACTION * 1e3 * plan.approach_m
        ):  # NaN counts as not followed
            bad.append(f"{r.finger} approach error {r.position_rmse_mm:.2f} mm")
        elif not r.force_rmse_n <= FOLLOW_FRACTION * plan.force_n:
            bad.append(f"{r.finger} hold error {r.force_rmse_n:.2f} N")
    return f"fingers did not follow their setpoints: {'; '.join(bad)}" if bad else None


def format_summary(rows: list[FingerSummary], plan: GraspPlan) -> str:
    lines = [
        f"grasp: approach {1e3 * plan.approach_m:g} mm, hold {plan.force_n:g} N, release "
        f"(tracking errors are RMS over the whole phase and over its last "
        f"{plan.settle_window_s:g} s)",
        f"{'finger':<16} {'approach mm':>11} {'pos err mm':>10} {'hold N':>7} {'force err N':>11} "
        f"{'peak N':>7} {'energy J':>9}",
    ]
    for r in rows:
        lines.append(
            f"{r.finger:<16} {r.approach_rmse_mm:>11.3f} {r.position_rmse_mm:>10.3f} "
            f"{r.hold_rmse_n:>7.3f} {r.force_rmse_n:>11.3f} {r.peak_force_n:>7.2f} "
            f"{r.energy_j:>9.1f}"
        )
    return "\n".join(lines)


def plot(
    traces: dict[str, FingerTrace], plan: GraspPlan, t_start: float, path: str | PathLike[str]
) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(3, 1, figsize=(9, 8), sharex=True)
    for finger, trace in traces.items():
        t = np.asarray(trace.t) - t_start
        axes[0].plot(t, 1e3 * np.asarray(trace.position_m), label=finger)
        axes[1].plot(t, trace.force_n, label=finger)
        axes[2].plot(np.asarray(trace.duty_t) - t_start, trace.duty_percent, label=finger)
    edges = np.cumsum([0.0] + [p[3] for p in plan.phases()])
    for ax in axes:
        for edge in edges[1:-1]:
            ax.axvline(edge, color="0.6", lw=0.8, ls="--")
        ax.grid(alpha=0.3)
    axes[0].axhline(1e3 * plan.approach_m, color="k", lw=0.8, ls=":")
    axes[1].axhline(plan.force_n, color="k", lw=0.8, ls=":")
    axes[0].set_ylabel("tendon position, mm")
    axes[1].set_ylabel("tendon force, N")
    axes[2].set_ylabel("duty, %")
    axes[2].set_xlabel("time since grasp start, s")
    axes[0].legend(ncol=3, fontsize=8)
    axes[0].set_title("HEMS scripted grasp: approach, force hold, release")
    fig.tight_layout()
    fig.savefig(path, dpi=90)
    plt.close(fig)
