"""The figures of a diagnosis report: measured against modelled outputs, the residual by
phase (or by figure for tables of tests) and the candidates' ranking."""

from __future__ import annotations

import math
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from hems_ros.diagnosis import localise  # noqa: E402
from hems_ros.diagnosis.candidates import PHASES  # noqa: E402
from hems_ros.diagnosis.dataset import TimeSeriesData  # noqa: E402
from hems_ros.diagnosis.features import FeatureData  # noqa: E402
from hems_ros.diagnosis.workflow import Diagnosis  # noqa: E402

DPI = 80
PHASE_COLORS = {
    "heating": "#f4cccc",
    "transformation": "#fce5cd",
    "hold": "#fff2cc",
    "cooling": "#cfe2f3",
    "rest": "#ffffff",
}


def draw(d: Diagnosis, folder: Path) -> list[str]:
    """Draw the report's figures into ``folder``; their file names."""
    names = []
    if isinstance(d.data, TimeSeriesData):
        names += _overlays(d, d.data, folder)
    else:
        names.append(_figure_bars(d, d.data, folder))
    names.append(_phase_bars(d, folder))
    s = d.search
    if s.steps:
        names.append(
            _ranking(s.steps[0].ranked, s.steps[0].chosen, s.start.heldout, d.model_name, folder)
        )
    elif s.load_relation is not None and s.load_relation.ranked:
        named = s.load_relation
        chosen = named.steps[0] if named.steps else None
        names.append(
            _ranking(
                named.ranked, chosen, named.start.heldout, d.model_name, folder, "load relation"
            )
        )
    return names


def _overlays(d: Diagnosis, data: TimeSeriesData, folder: Path) -> list[str]:
    start, corrected = d.predictions["start"], d.predictions["corrected"]
    names = []
    for i, run in enumerate(data.runs[:6]):
        channels = [c for c in data.channels if c in run.outputs]
        fig, axes = plt.subplots(
            len(channels) + 1, 1, figsize=(10, 2.2 * (len(channels) + 1)), sharex=True
        )
        seg, test = data.segments[i], data.split.heldout[i] | data.split.test[i]
        for ax, name in zip(axes, channels):
            unit, scale = localise.display(data, name)
            _shade(ax, run.time, seg.phase, test)
            ax.plot(run.time, run.outputs[name] * scale, color="k", lw=1.0, label="measured")
            ax.plot(
                run.time,
                start.outputs[i][name] * scale,
                color="tab:red",
                lw=0.9,
                label=f"{d.model_name}",
            )
            ax.plot(
                run.time,
                corrected.outputs[i][name] * scale,
                color="tab:green",
                lw=0.9,
                ls="--",
                label="corrected",
            )
            ax.set_ylabel(f"{name}, {unit}")
        axes[0].legend(loc="upper right", fontsize=8)
        axes[0].set_title(f"{run.name}: measured and replayed (shaded: held out; colours: phases)")
        axes[-1].plot(run.time, run.drive_values, color="tab:orange", lw=0.8)
        axes[-1].set_ylabel(run.drive)
        axes[-1].set_xlabel("time, s")
        name = f"overlay_{i + 1}.png"
        fig.tight_layout()
        fig.savefig(folder / name, dpi=DPI)
        plt.close(fig)
        names.append(name)
    return names


def _shade(ax, t, phase, heldout) -> None:
    """Phase colours as background spans, held-out samples hatched grey."""
    edges = np.flatnonzero(np.diff(phase)) + 1
    bounds = np.concatenate([[0], edges, [t.size - 1]])
    for a, b in zip(bounds[:-1], bounds[1:]):
        ax.axvspan(t[a], t[b], color=PHASE_COLORS[PHASES[phase[a]]], lw=0)
    held = np.flatnonzero(np.diff(heldout.astype(int)))
    marks = np.concatenate(
        [[0] if heldout[0] else [], held + 1, [t.size - 1] if heldout[-1] else []]
    ).astype(int)
    for a, b in zip(marks[::2], marks[1::2]):
        ax.axvspan(t[a], t[b], facecolor="none", edgecolor="0.6", hatch="//", lw=0)


def _figure_bars(d: Diagnosis, data: FeatureData, folder: Path) -> str:
    channels = data.channels
    fig, axes = plt.subplots(1, len(channels), figsize=(4 * len(channels), 3.5), squeeze=False)
    for ax, name in zip(axes[0], channels):
        unit, scale = localise.display(data, name)
        rows = [
            (
                t.name,
                (
                    t.figures[name],
                    d.predictions["start"].outputs[j].get(name, math.nan),
                    d.predictions["corrected"].outputs[j].get(name, math.nan),
                ),
            )
            for j, (_, t) in enumerate(data.tests)
            if name in t.figures
        ]
        x = np.arange(len(rows))
        for k, (label, color) in enumerate(
            (("measured", "k"), (d.model_name, "tab:red"), ("corrected", "tab:green"))
        ):
            ax.bar(
                x + (k - 1) * 0.27,
                [values[k] * scale for _, values in rows],
                0.27,
                color=color,
                label=label,
            )
        ax.set_xticks(x, [row for row, _ in rows], rotation=45, ha="right", fontsize=7)
        ax.set_ylabel(f"{name}, {unit}")
    axes[0][0].legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(folder / "figures_before_after.png", dpi=DPI)
    plt.close(fig)
    return "figures_before_after.png"


def _phase_bars(d: Diagnosis, folder: Path) -> str:
    before = [r for r in d.phases_before]
    after = {(r.group, r.channel): r for r in d.phases_after}
    labels = [f"{r.group}\n{r.channel}" for r in before]
    x = np.arange(len(before))
    fig, ax = plt.subplots(figsize=(max(6, 0.7 * len(before) + 2), 3.5))
    ax.bar(x - 0.2, [max(r.cost, 1e-3) for r in before], 0.4, color="tab:red", label=d.model_name)
    ax.bar(
        x + 0.2,
        [max(after[(r.group, r.channel)].cost, 1e-3) for r in before],
        0.4,
        color="tab:green",
        label="corrected",
    )
    ax.axhline(1.0, color="k", lw=0.8, ls=":", label="noise floor")
    ax.set_yscale("log")
    ax.set_xticks(x, labels, fontsize=7)
    ax.set_ylabel("mean squared residual / noise floor")
    ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(folder / "residual_by_phase.png", dpi=DPI)
    plt.close(fig)
    return "residual_by_phase.png"


def _ranking(
    ranked, chosen, start_cost: float, model_name: str, folder: Path, on: str = "step 1"
) -> str:
    fig, ax = plt.subplots(figsize=(7, 0.35 * len(ranked) + 1.2))
    y = np.arange(len(ranked))[::-1]
    colors = [
        "tab:green"
        if f is chosen
        else (
            "tab:gray"
            if f.pinned
            else ("tab:blue" if f.structure[-1].kind == "effect" else "tab:purple")
        )
        for f in ranked
    ]
    ax.barh(y, [max(f.heldout, 1e-3) for f in ranked], color=colors)
    ax.axvline(start_cost, color="tab:red", lw=1, label=model_name)
    ax.axvline(1.0, color="k", lw=0.8, ls=":", label="noise floor")
    ax.set_yticks(y, [f.structure[-1].name for f in ranked], fontsize=8)
    ax.set_xscale("log")
    ax.set_xlabel(
        f"held-out cost ({on}, best BIC on top; green: accepted, purple: recalibration, "
        "grey: on a bound)"
    )
    ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(folder / "candidate_ranking.png", dpi=DPI)
    plt.close(fig)
    return "candidate_ranking.png"
