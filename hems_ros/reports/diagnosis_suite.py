"""``hems diagnose-suite``: run the hidden-effect suite and the dissertation's studies, and
render suite.md / suite.json / the confusion matrix and the page docs/diagnosis.md.
"""

from __future__ import annotations

import json
import math
from dataclasses import dataclass
from pathlib import Path
from typing import Callable

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from hems_ros.diagnosis import candidates as library  # noqa: E402
from hems_ros.diagnosis import (
    cluster,  # noqa: E402
    public_data,  # noqa: E402
    suite,  # noqa: E402
)
from hems_ros.diagnosis import dissertation as studies_module  # noqa: E402
from hems_ros.diagnosis import joint as joint_module  # noqa: E402
from hems_ros.diagnosis.bagload import load_bag_runs  # noqa: E402
from hems_ros.diagnosis.workflow import Diagnosis, diagnose  # noqa: E402
from hems_ros.physics.params import load_params  # noqa: E402

DPI = 80
#: Seeds per case: single effects twice, the null five times (its rate is the one measured).
SEEDS = {"single": 2, "null": 5}
QUICK = (
    ("load_damping", "pulses", "mid"),
    ("supply_sag", "staircase", "high"),
    ("as_shifted", "pulses", "low"),
    ("nothing", "pulses", "high"),
    ("encoder_ripple", "staircase", "mid"),
    ("friction_and_sag", "pulses", "low"),
)
#: What the suite must show (the floors of the workflow's acceptance).
FLOORS = {
    "single_low": 0.9,
    "single_high": 0.8,
    "null": 0.9,
    "gap_cut": 0.5,
    "recovery_low": 0.15,
    "coverage": 0.85,
}


#: The committed bag recorded from the graph with a hidden effect (bags/README.md), in a checkout.
GRAPH_BAG = Path(__file__).resolve().parents[2] / "bags" / "diagnose_index_damping"
GRAPH_MODEL = "ch6_hems_index"
PUBLIC_DATA = Path(__file__).resolve().parents[2] / "tests" / "data" / "public"


@dataclass
class SuiteResult:
    outcomes: list[suite.Outcome]
    studies: list[tuple[studies_module.Study, Diagnosis]]
    page: str
    headline: str


def grid(seed: int, quick: bool) -> list[tuple[suite.Case, str, str, int]]:
    """Every (case, profile, noise level, seed) the suite runs."""
    by_name = {c.name: c for c in suite.CASES}
    if quick:
        return [(by_name[c], p, n, seed) for c, p, n in QUICK]
    return [
        (case, prof, noise, seed + k)
        for case in suite.CASES
        for prof in suite.PROFILES
        for noise in suite.NOISE
        for k in range(SEEDS.get(case.category, 1))
    ]


def case_key(case: suite.Case, prof: str, noise: str, seed: int) -> str:
    """The name of a suite run's task and of its result file."""
    return f"{case.name}-{prof}-{noise}-seed{seed}"


def suite_tasks(rows: list[tuple[suite.Case, str, str, int]]) -> list[cluster.Task]:
    """One task per (case, profile, noise level, seed) of :func:`grid`."""
    base = load_params(suite.BASE)
    duties = {p: suite.profile(p, base) for p in suite.PROFILES}
    return [
        cluster.Task(
            case_key(case, prof, noise, s),
            suite.run_case,
            (case, prof, noise, s, base, duties[prof]),
            cost=1 + len(case.expected),
        )
        for case, prof, noise, s in rows
    ]


def run(
    out: Path,
    seed: int = 0,
    quick: bool = False,
    dissertation: bool = True,
    progress: Callable[[str], None] | None = None,
    scheduler: str = cluster.LOCAL,
    workers: int | None = None,
) -> SuiteResult:
    """Run the suite (and the dissertation's studies), write the results into ``out``.

    Each case is a task on ``scheduler`` (:mod:`hems_ros.diagnosis.cluster`) whose outcome
    lands in ``out/cases``: a run stopped half-way continues from there."""
    say = progress or (lambda message: None)
    tasks = suite_tasks(grid(seed, quick))
    report = cluster.run_tasks(
        tasks,
        Path(out) / "cases",
        scheduler=scheduler,
        workers=workers,
        say=say,
        describe=_verdict_line,
    )
    outcomes = report.results()
    studies = []
    graph = None
    joint = None
    public = []
    if dissertation:
        for study in studies_module.STUDIES:
            say(f"study {study.key}: {study.command}")
            studies.append((study, studies_module.run(study, progress=lambda m: say("  " + m))))
        say("the three tables together, each on its rig")
        joint = joint_module.joint(progress=lambda m: say("  " + m))
        if GRAPH_BAG.is_dir():
            say(f"graph run: {GRAPH_BAG}")
            graph = diagnose(load_bag_runs(GRAPH_BAG), [], load_params(GRAPH_MODEL))
        if PUBLIC_DATA.is_dir():
            for item in public_data.STUDIES:
                say(f"public data {item.key}: {item.command(str(PUBLIC_DATA))}")
                public.append((item, public_data.run(item, PUBLIC_DATA)))
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    stats = statistics(outcomes)
    _confusion_figure(outcomes, out / "confusion.png")
    (out / "suite.json").write_text(
        json.dumps(
            {
                "seed": seed,
                "quick": quick,
                "statistics": stats,
                "runs": [record(o) for o in outcomes],
            },
            indent=1,
        )
        + "\n"
    )
    page = render(
        outcomes,
        stats,
        studies,
        graph,
        seed,
        quick,
        figure="figures/diagnosis_confusion.png",
        public=public,
        joint=joint,
    )
    (out / "suite.md").write_text(
        render(outcomes, stats, studies, graph, seed, quick, "confusion.png", public, joint)
    )
    return SuiteResult(outcomes, studies, page, headline(stats, len(outcomes)))


def _verdict_line(o: suite.Outcome) -> str:
    right = "right" if o.right else "WRONG"
    return f"{o.verdict} {','.join(o.named) or '-'} ({right})"


def record(o: suite.Outcome) -> dict:
    return {
        "case": o.case.name,
        "category": o.case.category,
        "profile": o.profile,
        "noise": o.noise,
        "seed": o.seed,
        "verdict": o.verdict,
        "named": list(o.named),
        "first": o.first,
        "ranking": list(o.ranking),
        "right": o.right,
        "errors": o.errors,
        "covered": o.covered,
        "gap_before": o.gap_before,
        "gap_after": o.gap_after,
        "beyond_noise_before": o.beyond_before,
        "beyond_noise_after": o.beyond_after,
        "unexplained": list(o.unexplained),
    }


def _rate(items: list[bool]) -> float:
    return float(np.mean(items)) if items else math.nan


def statistics(outcomes: list[suite.Outcome]) -> dict:
    """The suite's figures against its floors."""
    single = [o for o in outcomes if o.case.category == "single"]
    named = [
        o for o in outcomes if o.verdict in ("named", "ambiguous", "partial") and o.case.expected
    ]
    cuts = [1.0 - o.gap_after / o.gap_before for o in named if o.gap_before > 0]
    beyond = [1.0 - o.beyond_after / o.beyond_before for o in named if o.beyond_before > 0]
    short = sorted(
        {
            f"{o.case.name} ({o.profile}, {o.noise})"
            for o in named
            if o.gap_before > 0 and o.gap_after > 0.5 * o.gap_before
        }
    )
    low_errors = [e for o in outcomes if o.noise == "low" and o.right for e in o.errors.values()]
    # calibration of the intervals: every recovered value of a right answer
    covered = [c for o in outcomes if o.right for c in o.covered.values()]
    by = {}
    for level in suite.NOISE:
        group = [o for o in single if o.noise == level]
        by[level] = {
            "ranked_first": _rate([o.ranked_first for o in group]),
            "right": _rate([o.right for o in group]),
            "runs": len(group),
        }
    cat = {}
    for category in ("structural", "pair", "parameter", "outside", "null"):
        group = [o for o in outcomes if o.case.category == category]
        cat[category] = {"right": _rate([o.right for o in group]), "runs": len(group)}
    return {
        "single": by,
        "categories": cat,
        "gap_cut_min": float(min(cuts)) if cuts else math.nan,
        "beyond_noise_cut_min": float(min(beyond)) if beyond else math.nan,
        "gap_cut_short": short,
        "recovery_error_max_low": float(max(low_errors)) if low_errors else math.nan,
        "coverage": _rate(covered),
        "coverage_values": len(covered),
    }


def headline(stats: dict, n: int) -> str:
    s = stats["single"]
    c = stats["categories"]
    parts = [
        f"{n} runs",
        f"single effects ranked first: low {_pct(s['low']['ranked_first'])}, "
        f"mid {_pct(s['mid']['ranked_first'])}, high {_pct(s['high']['ranked_first'])}",
    ]
    parts += [f"{k} {_pct(v['right'])}" for k, v in c.items() if v["runs"]]
    parts.append(
        f"smallest held-out cut {_pct(stats['gap_cut_min'])} "
        f"({_pct(stats['beyond_noise_cut_min'])} beyond the noise)"
    )
    parts.append(f"95 % intervals hold the truth in {_pct(stats['coverage'])}")
    return "; ".join(parts)


def _pct(v: float) -> str:
    return "-" if not math.isfinite(v) else f"{100 * v:.0f} %"


# --------------------------------------------------------------------------- page
def render(
    outcomes,
    stats,
    studies,
    graph: Diagnosis | None,
    seed: int,
    quick: bool,
    figure: str,
    public: list | None = None,
    joint: joint_module.Joint | None = None,
) -> str:
    lines = [
        "# Finding what the model misses (generated by `hems diagnose-suite --docs "
        "docs/diagnosis.md`)",
        "",
        "`hems diagnose` replays measured runs on the physics model, the measured input driving it "
        "open loop; localises the residual by phase (heating, transformation, hold, cooling, rest) "
        "and cycle; then explains it, first by a recalibration of the printed model's parameters "
        "within published NiTi bounds, then by missing effects from the library below. Each "
        "candidate is fitted by bounded least squares from several starts on the training data, "
        "ranked by BIC and kept only when it removes a fair share of what is left there and "
        "improves the held-out data beyond the noise (`hems_ros/diagnosis/search.py`). The verdict "
        "is one of none, timing, recalibrated, named, ambiguous, partial (terms accepted, a phase "
        "left above twice the noise), unexplained. The README shows a worked "
        "example; `hems diagnose --help` the options.",
        "",
    ]
    lines += _library()
    lines += _suite_section(outcomes, stats, seed, quick, figure)
    for study, d in studies:
        lines += _study_section(study, d)
    if joint is not None:
        lines += _joint_section(joint)
    if graph is not None:
        lines += _graph_section(graph)
    for study, d in public or []:
        lines += _public_section(study, d)
    return "\n".join(lines) + "\n"


def _public_section(study: public_data.PublicStudy, d: Diagnosis) -> list[str]:
    """One published measurement of another wire: what it is, the call, the verdict with its
    intervals, what the loaders did and what the fits ran into."""
    lines = [
        f"## Public data: {study.title}",
        "",
        f"{study.question} Source: {study.source} (tests/data/public/README.md).",
        "",
        f"`{study.command('tests/data/public')}`",
        "",
        f"**{d.summary_line()}**",
        "",
    ]
    notes = sorted({n for r in d.data.runs for n in r.notes if "row by row" in n or "coldest" in n})
    if notes:
        lines += ["What the loader did: " + "; ".join(notes) + ".", ""]
    if d.search.findings:
        lines += ["Fits on a bound (findings): " + "; ".join(d.search.findings) + ".", ""]
    return lines


def _graph_section(d: Diagnosis) -> list[str]:
    truth = load_params(GRAPH_BAG / "physics.yaml")
    return [
        "## A graph run",
        "",
        f"`bags/diagnose_index_damping` was recorded from the one-finger graph (separate processes "
        f"over Fast DDS) whose actuation unit ran `{GRAPH_BAG.name}/physics.yaml`: {GRAPH_MODEL} "
        f"with the load damping at {truth.load.damping_n_s_per_m:g} N s/m instead of "
        f"{load_params(GRAPH_MODEL).load.damping_n_s_per_m:g}. The diagnosis reads the measured "
        f"topics only (duty, encoder, wire force, setpoints; never /hems/sim).",
        "",
        f"`hems diagnose bags/diagnose_index_damping --model {GRAPH_MODEL}`",
        "",
        f"**{d.summary_line()}**",
        "",
        "What the loader adjusted: "
        + ("; ".join(n for r in d.data.runs for n in r.notes) or "nothing")
        + ".",
        "",
    ]


def _library() -> list[str]:
    base = load_params(suite.BASE)
    lines = [
        "## The candidates",
        "",
        "| candidate | kind | what | parameters (bounds) | phases it changes |",
        "|---|---|---|---|---|",
    ]
    for c in library.ALL:
        bounds = ", ".join(
            f"{p.symbol} {p.display(lo):.4g}-{p.display(hi):.4g} {p.unit}".rstrip()
            for p, (lo, hi) in zip(c.parameters, c.bounds(base))
        )
        lines.append(f"| {c.name} | {c.kind} | {c.title} | {bounds} | {', '.join(c.phases)} |")
    lines += ["", "Where the bounds come from:", ""]
    lines += [f"- **{c.name}**: {c.source}." for c in library.ALL]
    return lines + [""]


def _suite_section(outcomes, stats, seed, quick, figure) -> list[str]:
    s, c = stats["single"], stats["categories"]
    noise = ", ".join(f"{k} {v[0] * 1e3:g} mm / {v[1]:g} N" for k, v in suite.NOISE.items())
    lines = [
        "## Hidden-effect suite",
        "",
        f"Starting model `{suite.BASE}` (Table 4.1, bare wire, 12 N bias spring, 20 V PWM stage). "
        f"For each case the truth is that model with something changed; it is driven by a duty "
        f"profile (`pulses`: eight pulses of 1.0-2.2 s at 60-100 % duty, one every 8 s; "
        f"`staircase`: the duty a BPID recorded on the starting model holding 5, 10, 15 mm for 3 s "
        f"each, three times), sampled at 100 Hz and read by sensors with Gaussian noise ({noise} "
        f"standard deviation) quantised to 1 um and 0.01 N. Each case is recorded twice: the "
        f"workflow fits on the profile and holds out a second recording of the same kind at other "
        f"lengths, duties and levels (pulses of 1.1-2.2 s at 65-100 %; a staircase of "
        f"8, 14, 4 mm), as a lab keeps a validation run; a warm start, which acts in the first "
        f"cycle only, is tested that way too. The workflow sees the measured duty, position and "
        f"wire force only. Seed {seed}" + (" (reduced subset)." if quick else "."),
        "",
        "| what the suite must show | floor | measured |",
        "|---|---|---|",
        f"| single effect ranked first, low noise | {_pct(FLOORS['single_low'])} | "
        f"{_pct(s['low']['ranked_first'])} of {s['low']['runs']} |",
        f"| single effect ranked first, mid noise | - | {_pct(s['mid']['ranked_first'])} of "
        f"{s['mid']['runs']} |",
        f"| single effect ranked first, high noise | {_pct(FLOORS['single_high'])} | "
        f"{_pct(s['high']['ranked_first'])} of {s['high']['runs']} |",
        f"| structural mismatch: right effect named | - | {_pct(c['structural']['right'])} of "
        f"{c['structural']['runs']} |",
        f"| two at once: both named | - | {_pct(c['pair']['right'])} of {c['pair']['runs']} |",
        f"| parameter only: recalibrated | - | {_pct(c['parameter']['right'])} of "
        f"{c['parameter']['runs']} |",
        f"| outside the library: unexplained or partial | - | {_pct(c['outside']['right'])} of "
        f"{c['outside']['runs']} |",
        f"| null: no missing effect | {_pct(FLOORS['null'])} | {_pct(c['null']['right'])} of "
        f"{c['null']['runs']} |",
        f"| whenever named: held-out RMSE beyond the noise floor cut | {_pct(FLOORS['gap_cut'])} | "
        f"at least {_pct(stats['beyond_noise_cut_min'])} |",
        # the floor is the cut beyond the noise: with the noise in, an effect that leaves the
        # test cycles little above it cannot be cut by half
        f"| whenever named: held-out RMSE cut (noise included) | - | at "
        f"least {_pct(stats['gap_cut_min'])} |",
        f"| recovered parameters, low noise: largest error | {_pct(FLOORS['recovery_low'])} | "
        f"{_pct(stats['recovery_error_max_low'])} |",
        f"| recovered parameters: 95 % interval holds the true value | "
        f"{_pct(FLOORS['coverage'])} | {_pct(stats['coverage'])} of "
        f"{stats['coverage_values']} values |",
        "",
    ]
    if stats["gap_cut_short"]:
        lines += [
            "The held-out RMSE counts the sensor noise too; it falls by less than half where the "
            "hidden effect leaves the held-out recording little above the noise: "
            + ", ".join(stats["gap_cut_short"])
            + ". Beyond the noise floor (sqrt(RMSE^2 - noise^2), the noise floor estimated from "
            "the data) the named effects remove at least the share in the row above.",
            "",
        ]
    lines += ["Cases:", ""] + [
        f"- `{case.name}` ({case.category}): {case.description}" for case in suite.CASES
    ]
    lines += [
        "",
        f"![confusion matrix]({figure})",
        "",
        "Every run (gap: held-out RMSE of the output the starting model misses most, before "
        "-> after; error: largest relative error of the recovered values):",
        "",
        "| case | profile | noise | seed | verdict | named | first in ranking | gap | error | "
        "unexplained |",
        "|---|---|---|---|---|---|---|---|---|---|",
    ]
    for o in outcomes:
        err = max(o.errors.values()) if o.errors else math.nan
        lines.append(
            f"| {o.case.name} | {o.profile} | {o.noise} | {o.seed} | "
            f"{o.verdict}{'' if o.right else ' (wrong)'} | {', '.join(o.named) or '-'} | "
            f"{o.ranking[0] if o.ranking else '-'} | {o.gap_before:.3g} -> {o.gap_after:.3g} | "
            f"{_pct(err)} | {', '.join(o.unexplained) or '-'} |"
        )
    return lines + [""]


def _sentence(text: str) -> str:
    return text[0].upper() + text[1:] + "."


def _role(select: bool, test: bool) -> str:
    """A held-out row's role; a row that is both (too few rows to test apart) selects."""
    return " (held out, selects)" if select else " (held out, tests)" if test else ""


def _rows(d: Diagnosis) -> list[str]:
    """Every row of the tables: measured / starting model / corrected, per figure."""
    data = d.data
    lines = []
    channels = data.channels
    lines += [
        "| row | "
        + " | ".join(f"{c} measured / {d.model_name} / corrected" for c in channels)
        + " |",
        "|---" * (len(channels) + 1) + "|",
    ]
    start, corrected = d.predictions["start"], d.predictions["corrected"]
    select, tested = data.split.heldout[0], data.split.test[0]
    for j, (_, test) in enumerate(data.tests):
        cells = []
        for name in channels:
            scale = _scale(name)
            if name in test.figures:
                cells.append(
                    f"{test.figures[name] * scale:.3g} "
                    f"/ {start.outputs[j].get(name, math.nan) * scale:.3g} "
                    f"/ {corrected.outputs[j].get(name, math.nan) * scale:.3g}"
                )
            else:
                cells.append("-")
        lines.append(f"| {test.name}{_role(select[j], tested[j])} | " + " | ".join(cells) + " |")
    return lines


def _study_section(study: studies_module.Study, d: Diagnosis) -> list[str]:
    lines = [
        f"## {study.title}",
        "",
        study.question,
        "",
        f"`{study.command}`",
        "",
        f"**{d.summary_line()}**",
        "",
        _sentence(d.data.split.description),
        "",
    ]
    lines += _rows(d)
    lines.append("")
    if d.search.findings:
        lines += [
            "Fits that ended on a published bound at some step (findings; such a fit is "
            "not accepted):",
            "",
        ]
        lines += [f"- {f}" for f in d.search.findings] + [""]
    steps = d.search.steps
    if steps:
        ranked = ", ".join(
            f"{f.structure[-1].name} ({', '.join(f.describe(f.structure[-1]))})"
            for f in steps[0].ranked[:4]
        )
        lines += [f"First step, best four by BIC: {ranked}.", ""]
    if study.sheath_check:
        lines += _sheath_lines(studies_module.sheath_check(d))
    return lines


def _joint_section(j: joint_module.Joint) -> list[str]:
    """The three tables diagnosed together, what each alone makes of the terms, and whether the
    joint in-bounds model could replace the calibrated sets."""
    d = j.diagnosis
    rigs = ", ".join(f"config/measurements/{s.rig}" for s in studies_module.STUDIES)
    lines = [
        "## The three tables together: one wire for chapters 3, 5 and 6",
        "",
        "The tables above, each on its own rig (" + rigs + ": the loads, the pulley, capstan "
        f"and glove friction), diagnosed together from the {joint_module.JOINT_MODEL} wire "
        "(C_M = C_A = 6.89 MPa/degC, inside NiTi's band) with every candidate within its "
        "published bounds. Each figure weighs by its assumed uncertainty, so the figures a model "
        "misses by the most uncertainties lead the fit.",
        "",
        f"`{joint_module.joint_command()}`",
        "",
        f"**{d.summary_line()}**",
        "",
        _sentence(d.data.split.description),
        "",
    ]
    lines += _rows(d) + [""]
    if d.search.findings:
        lines += ["Fits on a bound (findings): " + "; ".join(d.search.findings) + ".", ""]
    lines += [
        "Each table alone, fitting one term at a time on top of the joint model (95 % "
        "intervals; *on a bound*: the fit ended on a published bound):",
        "",
        "| term | parameter | " + " | ".join(s.key for s in studies_module.STUDIES) + " |",
        "|---|---|" + "---|" * len(studies_module.STUDIES),
    ]
    by = {(p.study.key, p.candidate): p for p in j.pulls}
    for name in dict.fromkeys(p.candidate for p in j.pulls):
        for par in library.BY_NAME[name].parameters:
            cells = []
            for study in studies_module.STUDIES:
                pull = by[(study.key, name)]
                value, low, high = pull.values[par.key]
                on_bound = any(f": {par.symbol} at its" in pin for pin in pull.pinned)
                mark = " *on a bound*" if on_bound else ""
                cells.append(
                    f"{value / par.scale:.4g} [{low / par.scale:.4g}, {high / par.scale:.4g}]{mark}"
                )
            lines.append(f"| {name} | {par.symbol}, {par.unit} | " + " | ".join(cells) + " |")
    apart = joint_module.apart(j.pulls)
    lines += [""]
    if apart:
        lines += [
            "Pulled apart (95 % intervals that do not overlap): "
            + "; ".join(
                f"{_symbol(key)}: {a.study.key} against {b.study.key}" for key, a, b in apart
            )
            + ".",
            "",
        ]
    else:
        lines += ["No two tables pull a term apart: their intervals overlap.", ""]
    slopes = "; ".join(
        _slopes(study.calibrated, j.slopes[study.key]) for study in studies_module.STUDIES
    )
    lines += [
        "Could an in-bounds slope replace the calibrated sets' C_M = C_A = 33.5 MPa/degC? Each "
        "figure's RMS miss over its rows, in units of its assumed uncertainty, for the "
        "calibrated set of the table's rig, the same set with only its stress slopes refitted "
        f"to the table within 5-15 MPa/degC ({slopes} MPa/degC), and the joint model:",
        "",
        "| table | figure | calibrated set | slopes in bounds | joint in-bounds model |",
        "|---|---|---|---|---|",
    ]
    lines += [
        f"| {m.study.key} | {m.figure} | {m.calibrated:.3g} | {m.slopes_in_bounds:.3g} | "
        f"{m.joint:.3g} |"
        for m in j.misses
    ]
    lines.append("")
    need = j.need_the_slope
    if need:
        lines += [
            "The calibrated sets stay: these figures need the out-of-bounds slope (the set "
            "with its slopes in bounds misses them by more): "
            + "; ".join(
                f"{m.study.key} {m.figure} ({m.slopes_in_bounds:.3g} against {m.calibrated:.3g} "
                f"uncertainties, +{m.slopes_in_bounds - m.calibrated:.2g})"
                for m in need
            )
            + ".",
            "",
        ]
    else:
        lines += [
            "No figure needs the out-of-bounds slope: each set with its slopes in bounds meets "
            "every figure of its table at least as well.",
            "",
        ]
    worse = j.worse
    lines += [
        (
            "The joint in-bounds model meets fewer figures than the calibrated sets: "
            + "; ".join(
                f"{m.study.key} {m.figure} ({m.joint:.3g} against {m.calibrated:.3g})"
                for m in worse
            )
            + "."
        )
        if worse
        else "The joint in-bounds model meets every figure at least as well as the calibrated "
        "sets.",
        "",
    ]
    return lines + _sheath_lines(j.sheath)


def _slopes(name: str, fitted) -> str:
    """A calibrated set's stress slopes refitted in bounds, those on the band's edge said."""
    parts = []
    for par in library.BY_NAME["stress_slopes"].parameters:
        value = fitted.params.get(par.key)
        edge = min(abs(value - par.lower), abs(value - par.upper)) <= 1e-3 * par.upper
        parts.append(f"{par.symbol} = {value / par.scale:.3g}{' (on the edge)' if edge else ''}")
    return f"{name} " + ", ".join(parts)


def _symbol(key: str) -> str:
    return next(p.symbol for c in library.ALL for p in c.parameters if p.key == key)


def _sheath_lines(check: studies_module.SheathCheck) -> list[str]:
    """Whether the corrected wire and sheath could replace the calibrated set: the chapter 3
    sheath facts of both (validation.sheath_facts), cold starts."""
    c, k = check.corrected, check.calibrated
    lo_d, hi_d = studies_module.DISPLACEMENT_RATIO
    lo_c, hi_c = studies_module.COOLING_RATIO
    rows = [
        (
            "106.8 J, cold sheath: sheathed / bare displacement",
            f"{lo_d}-{hi_d}",
            c.displacement_ratio,
            k.displacement_ratio,
        ),
        (
            "cooling after 20 mm: sheathed / bare",
            f"{lo_c}-{hi_c}",
            c.cooling_ratio,
            k.cooling_ratio,
        ),
        (
            "1.6 s every 30 s: sheath temperature at the 6th start, degC",
            "builds up slowly",
            c.cycle_sheath_start_c[-1],
            k.cycle_sheath_start_c[-1],
        ),
        (
            "same: cooling time of the 6th cycle, s",
            "lengthens slowly",
            c.cycle_cooling_s[-1],
            k.cycle_cooling_s[-1],
        ),
    ]
    lines = [
        "Could the corrected wire and sheath (cold start) replace the calibrated set the graph "
        "runs? The chapter 3 sheath facts of both:",
        "",
        "| fact | accepted | corrected | calibrated set |",
        "|---|---|---|---|",
    ]
    lines += [
        f"| {name} | {accepted} | {_figure(a)} | {_figure(b)} |" for name, accepted, a, b in rows
    ]
    lines += [
        "",
        "The corrected set meets both accepted ranges: it is the better-founded set."
        if check.within
        else "The corrected set misses the accepted ranges of the sheath facts the calibration was "
        "fitted to, so the calibrated set stays; what the table supports within physical bounds is "
        "the named effects above, not stress slopes beyond NiTi's.",
        "",
    ]
    return lines


def _figure(value: float) -> str:
    """A figure, or what it means when there is none (a wire that never moved past the
    cooled mark)."""
    return f"{value:.3g}" if math.isfinite(value) else "never moved past 4.5 mm"


def _scale(name: str) -> float:
    from hems_ros.diagnosis.runs import FIGURE_UNITS

    return FIGURE_UNITS[name][2]


def _confusion_figure(outcomes: list[suite.Outcome], path: Path) -> None:
    """Rows: the hidden single effect; columns: what the forward selection took first."""
    single = [o for o in outcomes if o.case.category == "single"]
    truths = [c.name for c in suite.SINGLE]
    columns = [c.name for c in library.ALL] + ["(nothing)"]
    matrix = np.zeros((len(truths), len(columns)))
    for o in single:
        matrix[truths.index(o.case.name), columns.index(o.first or "(nothing)")] += 1
    keep = matrix.sum(axis=0) > 0
    keep[[columns.index(t) for t in truths]] = True
    matrix, columns = matrix[:, keep], [c for c, k in zip(columns, keep) if k]
    fig, ax = plt.subplots(figsize=(0.5 * len(columns) + 3, 0.45 * len(truths) + 2))
    ax.imshow(matrix, cmap="Greens")
    for (i, j), v in np.ndenumerate(matrix):
        if v:
            ax.text(j, i, f"{v:.0f}", ha="center", va="center", fontsize=8)
    ax.set_xticks(range(len(columns)), columns, rotation=60, ha="right", fontsize=8)
    ax.set_yticks(range(len(truths)), truths, fontsize=8)
    ax.set_xlabel("first accepted candidate")
    ax.set_ylabel("hidden effect")
    ax.set_title("hidden-effect suite, single effects (all noise levels and profiles)", fontsize=9)
    fig.tight_layout()
    fig.savefig(path, dpi=DPI)
    plt.close(fig)
