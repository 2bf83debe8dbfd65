"""Tables, figures and Markdown of the chapter 5 and 6 experiments.

``write_ch5`` / ``write_ch6`` put ``<chapter>.md`` (tables: dissertation, ours, ratio) and
PNG figures (reference and measurement, error, duty against time, like the dissertation's
figures 5.x and 6.x) into a results folder; ``write_docs`` assembles docs/experiments.md
from both with the findings of :mod:`hems_ros.reports.findings`.
"""

from __future__ import annotations

import math
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

from hems_ros.control import FORCE_MODE_BPID  # noqa: E402
from hems_ros.experiments.dissertation import (  # noqa: E402
    CH5_PROTOCOLS,
    CH5_RISE_TIME_S,
    CH5_SS_ERROR_MM,
    CH5_STRATEGIES,
    CH5_TABLES,
    CH6_FORCE,
    CH6_HOLD,
    CH6_POSITION,
    CH6_SS_ERROR,
    CH6_TABLES,
    PROTOCOL_LABELS,
    STRATEGY_LABELS,
)
from hems_ros.reports.findings import Finding  # noqa: E402

DPI = 80
COLORS = {"pid": "tab:blue", "pipd": "tab:orange", "bpid": "tab:green"}


def _num(v: float, digits: int = 2) -> str:
    return "-" if v is None or (isinstance(v, float) and math.isnan(v)) else f"{v:.{digits}f}"


def _ratio(ours: float, theirs: float) -> str:
    if any(isinstance(v, float) and math.isnan(v) for v in (ours, theirs)) or not theirs:
        return "-"
    return f"{ours / theirs:.2f}"


def ch5_tables(ch5: dict) -> str:
    """Tables 5.2-5.5 side by side with ours, plus the step figures."""
    lines = []
    head = "| controller | " + " | ".join(PROTOCOL_LABELS[p] for p in CH5_PROTOCOLS) + " |"
    rule = "|---" * (len(CH5_PROTOCOLS) + 1) + "|"
    for metric, (title, unit, table, factor) in CH5_TABLES.items():
        lines += [f"**{title}** ({unit}; cells: dissertation / ours / ratio)", "", head, rule]
        for s in CH5_STRATEGIES:
            cells = []
            for p in CH5_PROTOCOLS:
                ours = ch5[p, s].metrics[metric] * factor
                cells.append(f"{table[p, s]:.2f} / {ours:.2f} / {_ratio(ours, table[p, s])}")
            lines.append(f"| {STRATEGY_LABELS[s]} | " + " | ".join(cells) + " |")
        lines.append("")
    lines += [
        "**Step figures** (dissertation / ours; rise time 10-90 %, mean over rising jumps; "
        "overshoot and steady-state error: largest over the jumps)",
        "",
        "| controller | step rise time s | step overshoot mm | step ss error mm | "
        "staircase rise time s | staircase overshoot mm | staircase ss error mm |",
        "|---|---|---|---|---|---|---|",
    ]
    for s in CH5_STRATEGIES:
        st, sc = ch5["ch5_step", s].metrics, ch5["ch5_staircase", s].metrics
        lines.append(
            f"| {STRATEGY_LABELS[s]} | {CH5_RISE_TIME_S[s]:.1f} / {st['rise_time_s']:.2f} | 0 / "
            f"{st['overshoot']:.2f} | {CH5_SS_ERROR_MM[s]:.2f} / {st['ss_error']:.3f} | - / "
            f"{sc['rise_time_s']:.2f} | - / {sc['overshoot']:.2f} | - / {sc['ss_error']:.3f} |"
        )
    return "\n".join(lines) + "\n"


def ch6_tables(ch6: dict) -> str:
    """Tables 6.1 and 6.2 side by side with ours."""
    lines = []
    for kind, names in (("position", CH6_POSITION), ("force", CH6_FORCE)):
        title, unit, table = CH6_TABLES[kind]
        lines += [
            f"**{title}** (dissertation / ours / ratio)",
            "",
            "| reference | RMSE "
            + unit
            + " | mean power W (APC) | rise time s | ss error "
            + unit
            + " | overshoot "
            + unit
            + " | hold excursion "
            + unit
            + " | model mean electrical power W |",
            "|---|---|---|---|---|---|---|---|",
        ]
        for p in names:
            m, d = ch6[p].metrics, table[p]
            ss_d = CH6_SS_ERROR.get(p, math.nan)
            lines.append(
                f"| {PROTOCOL_LABELS[p]} | {_num(d['rmse'], 3)} / {_num(m['rmse'], 3)} / "
                f"{_ratio(m['rmse'], d['rmse'])} | {_num(d['apc_w'])} / {_num(m['apc_w'])} / "
                f"{_ratio(m['apc_w'], d['apc_w'])} | {_num(d['rise_time_s'])} "
                f"/ {_num(m['rise_time_s'])} | {_num(ss_d)} / {_num(m['ss_error'], 3)} | "
                f"0 / {_num(m['overshoot'], 3)} | "
                f"{CH6_HOLD.get(kind, '-') if math.isfinite(m['excursion']) else '-'} "
                f"/ {_num(m['excursion'], 3)} | {ch6[p].power_w.mean():.1f} |"
            )
        lines.append("")
    return "\n".join(lines)


def findings_md(findings: list[Finding]) -> str:
    lines = ["| claim | reproduced | ours |", "|---|---|---|"]
    lines += [f"| {f.claim} | {'yes' if f.reproduced else '**no**'} | {f.ours} |" for f in findings]
    missed = [f for f in findings if not f.reproduced]
    if missed:
        lines += ["", "Not reproduced, and why:", ""]
        lines += [f"- **{f.claim}.** {f.evidence}" for f in missed]
    chosen = [f for f in findings if f.reproduced and f.evidence]
    if chosen:
        lines += ["", "Reproduced, and what it rests on:", ""]
        lines += [f"- **{f.claim}.** {f.evidence}" for f in chosen]
    return "\n".join(lines) + "\n"


def _axes(title: str, unit: str):
    fig, ax = plt.subplots(3, 1, figsize=(7, 6), sharex=True, height_ratios=(3, 2, 2))
    ax[0].set_title(title, fontsize=10)
    ax[0].set_ylabel(unit)
    ax[1].set_ylabel(f"error {unit}")
    ax[2].set_ylabel("duty %")
    ax[2].set_xlabel("time s")
    for a in ax:
        a.grid(alpha=0.3)
    return fig, ax


def _save(fig, path: Path) -> Path:
    fig.tight_layout()
    fig.savefig(path, dpi=DPI)
    plt.close(fig)
    return path


def plot_ch5(ch5: dict, folder: Path) -> list[Path]:
    """One figure per reference: the three controllers' position, error and duty."""
    paths = []
    for p in CH5_PROTOCOLS:
        fig, ax = _axes(f"Chapter 5, {PROTOCOL_LABELS[p]}: 40 N mass, Table 5.1 gains", "mm")
        ref = ch5[p, "bpid"]
        ax[0].plot(ref.time, ref.reference * 1e3, "k--", lw=1, label="reference")
        for s in CH5_STRATEGIES:
            run = ch5[p, s]
            kw = dict(color=COLORS[s], lw=0.9, label=STRATEGY_LABELS[s])
            ax[0].plot(run.time, run.measurement * 1e3, **kw)
            ax[1].plot(run.time, (run.reference - run.measurement) * 1e3, **kw)
            ax[2].plot(run.time, run.duty, alpha=0.6, **kw)
        ax[0].legend(fontsize=8, loc="upper right")
        paths.append(_save(fig, folder / f"{p}.png"))
    return paths


def plot_ch6(ch6: dict, folder: Path) -> list[Path]:
    """One figure per reference: BPID measurement, error and duty."""
    paths = []
    for p, run in ch6.items():
        unit, k = ("mm", 1e3) if run.mode == "position" else ("N", 1.0)
        fig, ax = _axes(f"Chapter 6, index finger, BPID {run.mode}: {PROTOCOL_LABELS[p]}", unit)
        ax[0].plot(run.time, run.reference * k, "k--", lw=1, label="reference")
        ax[0].plot(
            run.time,
            run.measurement * k,
            color=COLORS["bpid"],
            lw=0.9,
            label="encoder" if run.mode == "position" else "force sensor",
        )
        ax[1].plot(run.time, (run.reference - run.measurement) * k, color=COLORS["bpid"], lw=0.9)
        ax[2].plot(run.time, run.duty, color=COLORS["bpid"], lw=0.6)
        ax[0].legend(fontsize=8, loc="upper right")
        paths.append(_save(fig, folder / f"{p}.png"))
    return paths


SETUP_CH5 = (
    "Straight sheathed actuator with a 40 N hanging mass (`config/physics/ch5_straight_40n.yaml`), "
    "plant 1 kHz, controllers at 100 Hz (zero-order hold), encoder feedback (1 um counts), "
    "Table 5.1 gains with the error in micrometres, derivative filter N = 20 rad/s. One run "
    "per reference from a cold wire (the dissertation averaged three repetitions). "
    "`config/physics/ch5_straight_40n_table32.yaml` (same rig on the earlier one-node sheath "
    "calibration, heating band refitted to Table 3.2's displacement per pulse energy) serves "
    "only as an evidence run in the findings: it reproduces the 1.0 s row and a slower rise, "
    "but loses the 2.2-2.8 s rows (22.5-26.2 mm against 24.5-27.5 mm; calibration objective "
    "0.51 against 0.16), so the validated set stays the plant."
)
SETUP_CH6 = (
    "HEMS index unit (`config/physics/ch6_hems_index.yaml`: x2 pulley, glove as a bias spring "
    "pretensioned 2 N on the tendon, capstan and glove friction), BPID with Table 5.1 gains on "
    f"the encoder (position) and `FORCE_MODE_BPID` (Kp {FORCE_MODE_BPID.kp:g}, Ki "
    f"{FORCE_MODE_BPID.ki:g}, Kd {FORCE_MODE_BPID.kd:g}, Kb {FORCE_MODE_BPID.kb:g}, error in "
    f"10 mN; why: hems_ros/control/gains.py and the force overshoot finding) on the force sensor "
    "(0.03 N rms noise). Position RMSE on ascending parts (sine, ramp) or on plateaus once the "
    "rise is over (steps); force references run from the wire's rest tension (4 N: 2 N behind "
    "the x2 pulley) to 20 N. Overshoot is the first peak past each new level; hold excursion "
    "the largest distance past it anywhere on the plateau (the ripple while holding)."
)


def _figure_list(paths: list[Path], rel: str) -> str:
    return "\n".join(f"![{p.stem}]({rel}{p.name})" for p in paths) + "\n"


def write_chapter(chapter: str, runs: dict, findings: list[Finding], folder: Path) -> list[Path]:
    """``<folder>/<chapter>.md`` and its PNGs; returns the figure paths."""
    folder.mkdir(parents=True, exist_ok=True)
    if chapter == "ch5":
        tables, setup, figs = ch5_tables(runs), SETUP_CH5, plot_ch5(runs, folder)
    else:
        tables, setup, figs = ch6_tables(runs), SETUP_CH6, plot_ch6(runs, folder)
    text = (
        f"# Chapter {chapter[2:]} in simulation (generated by `hems experiment {chapter}`)\n\n"
        f"{setup}\n\n{tables}\n## Findings\n\n{findings_md(findings)}\n## Figures\n\n"
        + _figure_list(figs, "")
    )
    (folder / f"{chapter}.md").write_text(text)
    return figs


def docs_page(
    ch5: dict, ch6: dict, f5: list[Finding], f6: list[Finding], figures: list[Path]
) -> str:
    """The text of docs/experiments.md, listing ``figures`` (in docs/figures)."""
    return (
        "# Controller experiments (generated by `hems experiment all --docs docs`)\n\n"
        "The dissertation's closed-loop tests (dissertation chapters 5 and 6) run in the "
        "in-process lockstep of `hems_ros/experiments/lockstep.py`: physics kernel at 1 kHz, "
        "controller at 100 Hz with the duty held between samples, the controller reading the "
        "simulated encoder or force sensor. Cells read dissertation / ours / ratio. Regenerate "
        "with `hems experiment all --docs docs`; `hems experiment ch5|ch6` writes the same tables "
        "into `results/<chapter>/`.\n\n"
        f"## Chapter 5: PID, PI-PD and BPID\n\n{SETUP_CH5}\n\n{ch5_tables(ch5)}\n"
        f"### Findings\n\n{findings_md(f5)}\n"
        f"## Chapter 6: BPID on the HEMS index finger\n\n{SETUP_CH6}\n\n{ch6_tables(ch6)}\n"
        f"### Findings\n\n{findings_md(f6)}\n"
        "## Figures\n\n" + _figure_list(figures, "figures/")
    )


def write_docs(ch5: dict, ch6: dict, f5: list[Finding], f6: list[Finding], docs: Path) -> Path:
    """docs/experiments.md with figures in docs/figures/experiments_*.png."""
    figdir = docs / "figures"
    figdir.mkdir(parents=True, exist_ok=True)
    figs5 = [p.rename(figdir / f"experiments_{p.name}") for p in plot_ch5(ch5, figdir)]
    figs6 = [p.rename(figdir / f"experiments_{p.name}") for p in plot_ch6(ch6, figdir)]
    path = docs / "experiments.md"
    path.write_text(docs_page(ch5, ch6, f5, f6, figs5 + figs6))
    return path
