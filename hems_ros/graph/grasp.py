"""The scripted grasp and its summary (plain Python, no ROS).

Phases per finger (tendon side): approach in position mode to ``approach_m``, hold
``force_n`` in force mode, release to position 0. The summary of a recorded run gives per
finger: position tracking error over the end of the approach, force tracking error over the
end of the hold, peak tendon force, and the electrical energy spent.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np


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
        return [("approach", "position", self.approach_m, self.approach_s),
                ("hold", "force", self.force_n, self.hold_s),
                ("release", "position", 0.0, self.release_s)]


@dataclass
class FingerTrace:
    """Time series of one finger (s, tendon m, tendon N, %, W) gathered during the run."""

    t: list[float]
    position_m: list[float]
    force_n: list[float]
    power_t: list[float]
    power_w: list[float]
    duty_t: list[float]
    duty_percent: list[float]

    @classmethod
    def empty(cls) -> "FingerTrace":
        return cls([], [], [], [], [], [], [])


@dataclass(frozen=True)
class FingerSummary:
    finger: str
    position_rmse_mm: float
    force_rmse_n: float
    peak_force_n: float
    energy_j: float


def _window_rmse(t: np.ndarray, y: np.ndarray, target: float, start: float, end: float) -> float:
    mask = (t >= start) & (t < end)
    return float(np.sqrt(np.mean((y[mask] - target) ** 2))) if mask.any() else float("nan")


def summarize(finger: str, trace: FingerTrace, plan: GraspPlan, t_start: float) -> FingerSummary:
    t = np.asarray(trace.t) - t_start
    x = np.asarray(trace.position_m)
    f = np.asarray(trace.force_n)
    approach_end = plan.approach_s
    hold_end = approach_end + plan.hold_s
    pos = _window_rmse(t, x, plan.approach_m, approach_end - plan.settle_window_s, approach_end)
    force = _window_rmse(t, f, plan.force_n, hold_end - plan.settle_window_s, hold_end)
    tp = np.asarray(trace.power_t)
    energy = float(np.trapezoid(trace.power_w, tp)) if len(tp) > 1 else 0.0
    peak = float(np.nanmax(f)) if len(f) else float("nan")
    return FingerSummary(finger, 1e3 * pos, force, peak, energy)


def format_summary(rows: list[FingerSummary], plan: GraspPlan) -> str:
    lines = [f"grasp: approach {1e3 * plan.approach_m:g} mm, hold {plan.force_n:g} N, release "
             f"(tracking errors are RMS over the last {plan.settle_window_s:g} s of each phase)",
             f"{'finger':<16} {'pos err mm':>10} {'force err N':>11} {'peak N':>7} {'energy J':>9}"]
    for r in rows:
        lines.append(f"{r.finger:<16} {r.position_rmse_mm:>10.3f} {r.force_rmse_n:>11.3f} {r.peak_force_n:>7.2f} "
                     f"{r.energy_j:>9.1f}")
    return "\n".join(lines)


def plot(traces: dict[str, FingerTrace], plan: GraspPlan, t_start: float, path) -> None:
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
