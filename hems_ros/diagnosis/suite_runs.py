"""The hidden-effect suite as a whole: its grid of cases, profiles, noise levels and seeds,
the cases as tasks on the Dask runner, the dissertation's studies beside them, each outcome as
a record and the figures the suite is judged by. ``hems_ros.reports.diagnosis_suite`` renders
them (docs/diagnosis-suite.md).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path
from typing import Callable

import numpy as np

from hems_ros.diagnosis import cluster, public_data, suite
from hems_ros.diagnosis import dissertation as studies_module
from hems_ros.diagnosis import joint as joint_module
from hems_ros.diagnosis.bagload import load_bag_runs
from hems_ros.diagnosis.workflow import Diagnosis, diagnose
from hems_ros.physics.params import load_params

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
class SuiteRuns:
    """What a suite run found: the cases' outcomes and, beside them, the dissertation's
    studies, the three tables fitted together, the graph's recorded run and the public data."""

    outcomes: list[suite.Outcome]
    studies: list[tuple[studies_module.Study, Diagnosis]]
    graph: Diagnosis | None
    joint: joint_module.Joint | None
    public: list


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
) -> SuiteRuns:
    """Run the suite (and the dissertation's studies).

    Each case is a task on ``scheduler`` (:mod:`hems_ros.diagnosis.cluster`) whose outcome
    lands in ``out/cases``: a run stopped half-way continues from there."""
    say = progress or (lambda message: None)
    report = cluster.run_tasks(
        suite_tasks(grid(seed, quick)),
        Path(out) / "cases",
        scheduler=scheduler,
        workers=workers,
        say=say,
        describe=_verdict_line,
    )
    runs = SuiteRuns(report.results(), [], None, None, [])
    if not dissertation:
        return runs
    for study in studies_module.STUDIES:
        say(f"study {study.key}: {study.command}")
        runs.studies.append((study, studies_module.run(study, progress=lambda m: say("  " + m))))
    say("the three tables together, each on its rig")
    runs.joint = joint_module.joint(progress=lambda m: say("  " + m))
    if GRAPH_BAG.is_dir():
        say(f"graph run: {GRAPH_BAG}")
        runs.graph = diagnose(load_bag_runs(GRAPH_BAG), [], load_params(GRAPH_MODEL))
    if PUBLIC_DATA.is_dir():
        for item in public_data.STUDIES:
            say(f"public data {item.key}: {item.command(str(PUBLIC_DATA))}")
            runs.public.append((item, public_data.run(item, PUBLIC_DATA)))
    return runs


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
