"""``hems experiment ch5|ch6|all``: the dissertation's controller tests in simulation.

Runs the lockstep experiments of :mod:`hems_ros.experiments` and writes Markdown tables
beside Tables 5.2-5.5 / 6.1-6.2 and PNG figures into a results folder; ``--docs`` also
regenerates docs/experiments.md and its figures.
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path


def register(subparsers) -> None:
    parser = subparsers.add_parser(
        "experiment",
        help="run the dissertation's chapter 5/6 controller tests in simulation (tables + plots)",
        description="Chapter 5: sine 20 mm peak-to-peak at 0.125/0.25/0.5 Hz (20 s), two 20 mm "
        "steps (70 s) and a 5 mm staircase (70 s) with PID, PI-PD and BPID (Table 5.1 "
        "gains) on the straight actuator with a 40 N mass. Chapter 6: BPID on the HEMS "
        "index unit (2 N bias pretension): 27 mm position sine/ramp/steps/staircase and "
        "4-20 N force sine 0.125/0.25 Hz, steps, staircase. Plant at 1 kHz, control at "
        "100 Hz. Writes <chapter>.md (RMSE mm or N, IAE, MACSI %/sample, APC W, rise "
        "time s, overshoot as the first peak past a new level and hold excursion as the "
        "largest over the plateau; dissertation / ours / ratio) and PNG plots.",
        formatter_class=argparse.ArgumentDefaultsHelpFormatter,
    )
    parser.add_argument("chapter", choices=("ch5", "ch6", "all"), help="which chapter's tests")
    parser.add_argument(
        "-o",
        "--output",
        type=Path,
        default=None,
        help="results folder (default results/<chapter>; with 'all', "
        "<output>/ch5 and <output>/ch6)",
    )
    parser.add_argument(
        "--docs",
        type=Path,
        default=None,
        metavar="DIR",
        help="also write DIR/experiments.md and DIR/figures/experiments_*.png "
        "(needs chapter 'all')",
    )
    parser.set_defaults(func=run)


def _folder(args, chapter: str) -> Path:
    if args.output is None:
        return Path("results") / chapter
    return args.output / chapter if args.chapter == "all" else args.output


def run(args: argparse.Namespace) -> int:
    from hems_ros.experiments import chapters
    from hems_ros.physics import load_params
    from hems_ros.reports import experiments as report
    from hems_ros.reports import findings

    if args.docs is not None and args.chapter != "all":
        print("--docs needs chapter 'all' (docs/experiments.md covers both chapters)")
        return 2
    # made before the runs, so that a folder that cannot be written fails at once, not after them
    for chapter in ("ch5", "ch6") if args.chapter == "all" else (args.chapter,):
        _folder(args, chapter).mkdir(parents=True, exist_ok=True)
    if args.docs is not None:
        (args.docs / "figures").mkdir(parents=True, exist_ok=True)
    start = time.perf_counter()
    results: dict[str, tuple] = {}
    if args.chapter in ("ch5", "all"):
        print(
            "chapter 5: 5 references x 3 controllers, 40 N mass (plant 1 kHz, control 100 Hz)",
            flush=True,
        )
        runs = chapters.run_ch5(progress=lambda m: print(m, flush=True))
        print(
            "checking the chapter 5 claims (a miss runs its evidence: sweeps, evidence sets) ...",
            flush=True,
        )
        f5 = findings.ch5_findings(runs, load_params(chapters.CH5_PARAMS))
        results["ch5"] = (runs, f5)
    if args.chapter in ("ch6", "all"):
        print("chapter 6: BPID, index unit, 4 position + 4 force references", flush=True)
        runs6 = chapters.run_ch6(progress=lambda m: print(m, flush=True))
        print("checking the chapter 6 claims (a miss runs its evidence) ...", flush=True)
        results["ch6"] = (runs6, findings.ch6_findings(runs6))
    for chapter, (chapter_runs, found) in results.items():
        folder = _folder(args, chapter)
        figs = report.write_chapter(chapter, chapter_runs, found, folder)
        print(f"wrote {folder / (chapter + '.md')} and {len(figs)} figures")
        for f in found:
            print(f"  {'ok  ' if f.reproduced else 'MISS'} {f.claim}: {f.ours}")
        if not all(f.reproduced for f in found):
            print(
                f"  why each MISS, with the runs that show it: {folder / (chapter + '.md')}, "
                "'Not reproduced, and why'"
            )
    if args.docs is not None:
        (ch5, f5), (ch6, f6) = results["ch5"], results["ch6"]
        path = report.write_docs(ch5, ch6, f5, f6, args.docs)
        print(f"wrote {path}")
    print(f"done in {time.perf_counter() - start:.1f} s")
    return 0
