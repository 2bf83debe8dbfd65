"""The report folder of a diagnosis: report.md, PNG figures, corrected.yaml, summary.json.

The folder is written beside its destination and moved into place at the end, so a run
that fails leaves no partial report (and an earlier report of the same name stays until
the new one is complete).
"""

from __future__ import annotations

import json
import math
import os
import shutil
from pathlib import Path

import numpy as np

from hems_ros.diagnosis import localise
from hems_ros.diagnosis.dataset import TimeSeriesData
from hems_ros.diagnosis.search import noise_limit
from hems_ros.diagnosis.workflow import Diagnosis
from hems_ros.physics.params import save_params
from hems_ros.reports import diagnosis_figures


def summary(d: Diagnosis) -> dict:
    """The machine-readable result (summary.json)."""
    g = d.gap
    s = d.search
    return {
        "verdict": d.verdict,
        "named": d.named(),
        "recalibrated": d.recalibrated(),
        "unexplained": d.unexplained,
        # group -> residual RMS over the noise floor, where the corrected model leaves more
        # than localise.LEFT_RMS
        "left_above_noise": d.left,
        "gap": {
            "metric": f"{g.metric} RMSE",
            "unit": g.unit,
            "train_before": g.train_before,
            "train_after": g.train_after,
            "heldout_before": g.heldout_before,
            "heldout_after": g.heldout_after,
            "noise_floor": g.noise if math.isfinite(g.noise) else None,
            "heldout_beyond_noise_before": g.beyond_noise(g.heldout_before),
            "heldout_beyond_noise_after": g.beyond_noise(g.heldout_after),
        },
        "ambiguous_with": [{"effect": e, "rivals": r} for e, r in s.ambiguous_with],
        "findings": s.findings,
        "near_bounds": d.near_bounds(),
        "timing": d.timing(),
        "intervals": _interval_summary(d),
        "dropped": s.dropped,
        "model": d.model_name,
        "heldout": d.data.split.description,
        "noise_floor": _noise(d),
        # sd of the log of a perfect model's cost: how far the floor's estimate may be off
        "noise_floor_spread": d.data.cost_spread,
        "ranking": [_fit_entry(f, s.start) for f in (s.steps[0].ranked if s.steps else [])],
        "load_relation": _relation_entry(s.load_relation),
        "fit": _convergence(s.final),
        "summary": d.summary_line(),
    }


def _convergence(f) -> dict:
    """How the kept start's least-squares run ended (no structure: nothing was fitted)."""
    return {
        "converged": f.converged,
        "stop": f.stop,
        "starts": f.starts,
        "evaluations": f.evaluations,
    }


def _noise(d: Diagnosis) -> dict:
    if isinstance(d.data, TimeSeriesData):
        return {
            c: {
                "value": d.data.sigma[c] * localise.display(d.data, c)[1],
                "unit": localise.display(d.data, c)[0],
            }
            for c in d.data.channels
        }
    return {}


def _fit_entry(f, start) -> dict:
    return {
        "candidate": f.structure[-1].name,
        "kind": f.structure[-1].kind,
        "parameters": [p for c in f.structure for p in f.describe(c)],
        "train_cost": f.train,
        "heldout_cost": f.heldout,
        "delta_bic": f.bic - start.bic,
        "pinned": f.pinned,
        **_convergence(f),
    }


def _relation_entry(named) -> dict | None:
    """The load relation's costs (its own noise-floor units) and the effects named on it."""
    if named is None:
        return None
    return {
        "noise_floor_n": named.sigma_n,
        "heldout_cost_before": named.start.heldout,
        "heldout_cost_after": named.final.heldout,
        "named": [_fit_entry(f, named.start) for f in named.steps],
    }


def _relation_lines(named) -> list[str]:
    if named is None:
        return []
    lines = [
        "### The load relation",
        "",
        "The force the measured motion of the load calls for under the load's law, against the "
        "measured force, whatever the wire is made of (costs in units of the relation's noise "
        f"floor, {named.sigma_n:.3g} N): held-out cost {_num(named.start.heldout)} with the "
        "starting model's load.",
        "",
    ]
    if not named.steps:
        return lines + ["No effect of the load is named on it.", ""]
    lines += [
        "| named | fitted | held-out cost | dBIC |",
        "|---|---|---|---|",
    ]
    for f in named.steps:
        c = f.structure[-1]
        lines.append(
            f"| {c.name} | {', '.join(f.describe(c))} | {_num(f.heldout)} | "
            f"{f.bic - named.start.bic:.0f} |"
        )
    return lines + [
        "",
        "The steps below are made on top of these values, and accept no term that makes the "
        "relation worse.",
        "",
    ]


def write(d: Diagnosis, out: Path) -> Path:
    """Write the report folder ``out`` (replacing a finished earlier one)."""
    out = Path(out)
    if out.exists() and not (out / "summary.json").is_file() and any(out.iterdir()):
        raise FileExistsError(f"{out} exists and is not a diagnosis report; choose another --out")
    partial = out.with_name(f".{out.name}.partial-{os.getpid()}")
    shutil.rmtree(partial, ignore_errors=True)
    partial.mkdir(parents=True)
    try:
        figures = diagnosis_figures.draw(d, partial)
        save_params(
            d.corrected.replace(
                name=f"{d.model_name}_corrected",
                description=f"{d.model_name} corrected by hems diagnose: {d.summary_line()}",
            ),
            partial / "corrected.yaml",
        )
        (partial / "summary.json").write_text(
            json.dumps(summary(d), indent=2, default=_json) + "\n"
        )
        (partial / "report.md").write_text(markdown(d, figures))
        if out.exists():
            shutil.rmtree(out)
        partial.rename(out)
    except BaseException:
        shutil.rmtree(partial, ignore_errors=True)
        raise
    return out


def _json(value):
    if isinstance(value, (np.floating, np.integer)):
        return value.item()
    raise TypeError(f"not JSON: {value!r}")


def _num(v: float, digits: int = 3) -> str:
    return "-" if v is None or not math.isfinite(v) else f"{v:.{digits}g}"


def markdown(d: Diagnosis, figures: list[str]) -> str:
    """report.md: verdict, gap, where the disagreement sits, the candidates, the model."""
    g = d.gap
    lines = [
        f"# Diagnosis: {d.model_name} against the measurement",
        "",
        f"**{d.summary_line()}**",
        "",
        f"Data: {_data_line(d)}. {d.data.split.description}.",
        "",
    ]
    if isinstance(d.data, TimeSeriesData):
        lines += [
            "Noise floor (high-frequency part of the starting model's residual): "
            + ", ".join(f"{c} {v['value']:.3g} {v['unit']}" for c, v in _noise(d).items())
            + f". Read cycle by cycle it spreads {d.data.cost_spread:.2g} in log: with no term "
            f"accepted, a held-out cost up to {noise_limit(d.data.cost_spread):.3g} counts as "
            "the noise.",
            "",
        ]
    timing = d.timing()
    if timing is not None:
        lines += [_timing_line(timing), ""]
    final = d.search.final
    if not final.converged:
        lines += [
            f"The corrected model's fit ({', '.join(final.names)}) stopped after "
            f"{final.evaluations} evaluations without meeting its tolerances ({final.stop}): "
            "its values are where it stopped, not an optimum.",
            "",
        ]
    notes = [f"- {r.name}: {n}" for r in d.data.runs for n in r.notes]
    if notes:
        lines += ["What the loaders adjusted:", ""] + notes + [""]
    lines += [
        "## Gap",
        "",
        f"| {g.metric} RMSE, {g.unit} | before | after |",
        "|---|---|---|",
        f"| training data | {_num(g.train_before)} | {_num(g.train_after)} |",
        f"| held-out data that chose nothing (test) | {_num(g.heldout_before)} | "
        f"{_num(g.heldout_after)} |",
    ]
    if math.isfinite(g.noise):
        lines += [
            f"| test, beyond the noise floor ({_num(g.noise)} {g.unit}) | "
            f"{_num(g.beyond_noise(g.heldout_before))} | {_num(g.beyond_noise(g.heldout_after))} |"
        ]
    lines += [""]
    lines += [
        "## Where the model and the measurement disagree",
        "",
        "Residual RMS by phase (time series) or figure (tables), before / after; cost is the mean "
        "squared residual in noise-floor units (1 = the noise).",
        "",
        "| group | channel | samples | RMS before | RMS after | cost before | cost after |",
        "|---|---|---|---|---|---|---|",
    ]
    after = {(r.group, r.channel): r for r in d.phases_after}
    for r in d.phases_before:
        a = after[(r.group, r.channel)]
        lines.append(
            f"| {r.group} | {r.channel} | {r.samples} | {_num(r.rms)} {r.unit} | {_num(a.rms)} "
            f"{a.unit} | {_num(r.cost)} | {_num(a.cost)} |"
        )
    lines += ["", f"Left unexplained: {', '.join(d.unexplained) or 'nothing'}.", ""]
    lines += _candidate_lines(d)
    lines += _interval_lines(d)
    lines += [
        "## Corrected model",
        "",
        "`corrected.yaml` (loads with `--physics-config`, "
        "`ros2 run hems_ros actuation_unit --ros-args -p physics_config:=<path>`):",
        "",
    ]
    changes = _changes(d)
    lines += (
        ["| parameter | starting model | corrected |", "|---|---|---|"]
        + [f"| {k} | {a} | {b} |" for k, a, b in changes]
        if changes
        else ["No change."]
    )
    lines += ["", "## Figures", ""] + [f"![{Path(f).stem}]({f})" for f in figures] + [""]
    return "\n".join(lines)


def _data_line(d: Diagnosis) -> str:
    if isinstance(d.data, TimeSeriesData):
        return "; ".join(
            f"{r.name} ({r.n_samples} samples, {r.duration_s:.1f} s, {_inputs(r)} in)"
            for r in d.data.runs
        )
    return "; ".join(f"{r.name} ({len(r.tests)} rows)" for r in d.data.runs)


def _candidate_lines(d: Diagnosis) -> list[str]:
    s = d.search
    lines = [
        "## Candidates",
        "",
        f"Starting model: training cost {_num(s.start.train)}, held-out (selecting) cost "
        f"{_num(s.start.heldout)}. Each step fits every candidate on top of the model so far "
        f"(bounded least squares, several starts) and ranks them by BIC on the training data "
        f"(dBIC: against the starting model); the cost on the held-out selecting data decides "
        f"whether the best one generalises. The gap above is measured on the test data, which "
        f"chose nothing.",
        "",
    ]
    lines += _relation_lines(s.load_relation)
    for i, step in enumerate(s.steps, start=1):
        lines += [
            f"### Step {i}",
            "",
            "| candidate | kind | fitted | train cost | held-out cost | dBIC | |",
            "|---|---|---|---|---|---|---|",
        ]
        for f in step.ranked:
            c = f.structure[-1]
            mark = (
                "accepted"
                if f is step.chosen
                else ("as good" if f in step.rivals else ("on a bound" if f.pinned else ""))
            )
            lines.append(
                f"| {c.name} | {c.kind} | {', '.join(f.describe(c))} | {_num(f.train)} | "
                f"{_num(f.heldout)} | {f.bic - s.start.bic:.0f} | {mark} |"
            )
        lines.append("")
    if s.dropped:
        lines += [f"Dropped again once later terms were in: {', '.join(s.dropped)}.", ""]
    if s.findings:
        lines += [
            "Findings (fits that ended on a published bound at some step; such a fit is "
            "not accepted):",
            "",
        ]
        lines += [f"- {p}" for p in s.findings] + [""]
    lines += ["Bounds and where they come from:", ""]
    lines += [
        f"- **{c.name}** ({c.kind}; {c.title}; changes {', '.join(c.phases)}): "
        + ", ".join(
            f"{p.symbol} {p.display(lo):.4g}-{p.display(hi):.4g} {p.unit}".rstrip()
            for p, (lo, hi) in zip(c.parameters, c.bounds(d.start))
        )
        + f". {_bounds_source(c)}."
        for c in d.candidates
    ]
    return lines + [""]


def _timing_line(timing: dict) -> str:
    lower, upper = (1e3 * v for v in timing["range_s"])
    head = f"Input timing, searched within {lower:+.3g} to {upper:+.3g} ms (+: the wire gets "
    head += "the input after its record): "
    if timing["accepted_s"] is not None:
        return head + f"{1e3 * timing['accepted_s']:+.3g} ms, taken into the corrected model."
    if timing["estimate_s"] is None:
        return head + "not estimated (nothing beyond the noise to explain)."
    return head + (
        f"{1e3 * timing['estimate_s']:+.3g} ms on the starting model, not taken (it explains "
        "less than the terms that were)."
    )


def _bounds_source(c) -> str:
    given = [p.symbol for p in c.parameters if p.key in c.bound_overrides]
    return f"{', '.join(given)} from --bounds; the library's: {c.source}" if given else c.source


def _changes(d: Diagnosis) -> list[tuple[str, str, str]]:
    a, b = d.start.to_dict(), d.corrected.to_dict()
    out = []
    for group, values in b.items():
        if isinstance(values, dict):
            for k, v in values.items():
                if a[group][k] != v:
                    out.append((f"{group}.{k}", _fmt(a[group][k]), _fmt(v)))
        elif group not in ("name", "description") and a[group] != values:
            out.append((group, _fmt(a[group]), _fmt(values)))
    return out


def _fmt(v) -> str:
    return f"{v:.5g}" if isinstance(v, float) else str(v)


def _inputs(run) -> str:
    if run.kind == "prescribed_strain":
        return f"{run.drive} and the frame's strain"
    if run.stress_values is not None:
        return f"{run.drive} and the frame's stress"
    return run.drive


def _interval_summary(d: Diagnosis) -> dict | None:
    iv = d.intervals
    if iv is None:
        return None
    return {
        "level": 0.95,
        "samples": iv.n_samples,
        "effective_samples": iv.n_effective if math.isfinite(iv.n_effective) else None,
        "unidentifiable": [{"keys": [a, b], "correlation": r} for a, b, r in iv.unidentifiable()],
    }


def _interval_lines(d: Diagnosis) -> list[str]:
    """The corrected values with their 95 % intervals and the pairs the data cannot tell apart."""
    iv = d.intervals
    if iv is None:
        return []
    entries = {**d.recalibrated()}
    for n in d.named():
        entries |= n["parameters"]
    timing = d.timing()
    lines = [
        "## Corrected values and their 95 % intervals",
        "",
        f"From the training residual's Jacobian, with {iv.n_effective:.0f} effective independent "
        f"samples of {iv.n_samples} (the residual's autocorrelation counted). They hold for "
        "the noise of the data; where the model's form is not the wire's, a value can be off by "
        "more.",
        "",
        "| parameter | value | 95 % interval |",
        "|---|---|---|",
    ]
    for key, p in entries.items():
        lines.append(
            f"| {p['symbol']} ({key}) | {p['value']:.4g} {p['unit']} | "
            f"{p['lower']:.4g} to {p['upper']:.4g} |"
        )
    if timing is not None and timing["interval_s"] is not None:
        low, high = timing["interval_s"]
        lines.append(
            f"| input delay (drive.input_delay_s) | {timing['accepted_s'] * 1e3:.3g} ms | "
            f"{low * 1e3:.3g} to {high * 1e3:.3g} |"
        )
    pairs = iv.unidentifiable()
    lines += [""] + (
        [
            "Not separately identifiable (correlation beyond 0.95): "
            + "; ".join(f"{a} and {b} (r = {r:+.3f})" for a, b, r in pairs)
            + ".",
            "",
        ]
        if pairs
        else []
    )
    return lines
