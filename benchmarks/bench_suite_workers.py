"""The hidden-effect suites on one Dask worker and on two, side by side in one run.

Requirement: on this two-core host two workers run a quick subset of the suite at least 1.7
times as fast as one (each worker's simulation batches on one core; hems_ros/diagnosis/
cluster.py). The subset: by default 8 truths taken at even steps through the blind suite's
evaluation grid (docs/diagnosis.md, which states the same measure on 16 of them as it is made);
with --suite self, the six quick cases of the suite whose truths the model's own code makes
(docs/diagnosis-suite.md). Also measured: the same subset serially in this process, where each
case's batches use both cores, which is what a single worker per core competes with.

Each layout starts from an empty output folder and is timed from the call to the last result,
cluster start-up included; an untimed first cluster starts the server the workers fork from,
as the imports are untimed: a process pays for both once. The sum of the task times says how
much of the wall time the tasks themselves took. Before and after the runs, a pure-Python
loop is timed alone and beside a copy of itself on the other core: how much the host's two
cores slow each other at the moment, which caps what two workers can gain. Prints measured
numbers and ratios; the exit code does not depend on the timings.

Run: .venv/bin/python benchmarks/bench_suite_workers.py [--suite blind|self] [--repeat N] [--smoke]
"""

from __future__ import annotations

import argparse
import statistics
import sys

import smoke
from host import cpu_jiffies, host_line, steal_pct, twin_slowdown

from hems_ros.diagnosis import blind, cluster, speedup, suite_runs

GOAL = 1.7
SMOKE_CASES = ("nothing",)
BLIND_TASKS = 8  # about 100 s on one worker here


def _tasks(args: argparse.Namespace) -> tuple[list[cluster.Task], str]:
    """The tasks to time and what they are."""
    if args.suite == "blind" and not args.smoke:
        count = args.cases or BLIND_TASKS
        tasks = speedup.spread(blind.tasks(blind.grid(half="evaluation")), count)
        return tasks, f"blind suite: {count} truths spread over its grid"
    # a smoke run times the self-made suite's quickest case, in seconds
    rows = suite_runs.grid(0, quick=args.cases is None)[: args.cases]
    if args.smoke:
        rows = [r for r in rows if r[0].name in SMOKE_CASES]
    subset = "the quick subset" if args.cases is None else "the full suite's first"
    what = f"self-made suite: {subset}{', smoke' if args.smoke else ''}"
    return suite_runs.suite_tasks(rows), what


def _time(
    tasks: list[cluster.Task], scheduler: str, workers: int | None
) -> tuple[float, float, float]:
    """(wall s from the call to the last result, sum of the task times s, steal %)."""
    jiffies = cpu_jiffies()
    timing = speedup.timed(tasks, scheduler, workers)
    return timing.wall_s, timing.task_s, steal_pct(jiffies, cpu_jiffies())


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--repeat", type=int, default=2, help="timed runs per layout (median)")
    parser.add_argument(
        "--suite",
        choices=("blind", "self"),
        default="blind",
        help="blind: truths spread over the blind suite's grid (default); self: the quick "
        "subset of the suite made with the model's own code",
    )
    parser.add_argument(
        "--cases",
        type=int,
        default=None,
        help=f"blind: N truths instead of {BLIND_TASKS}; self: the first N cases of the full "
        "suite instead of the quick subset",
    )
    args = smoke.parse_args(parser, repeat=1)
    tasks, what = _tasks(args)
    print(host_line())
    # a smoke run reads one short pair
    probe = (1, 3_000_000) if args.smoke else (5, 15_000_000)
    twin_before = twin_slowdown(*probe)
    print(f"{len(tasks)} tasks ({what})")
    # untimed, as a process pays them once: numba's cache and the first imports, and the
    # server that local workers fork from (hems_ros/diagnosis/cluster.py)
    _time(tasks[:1], cluster.SERIAL, None)
    _time(tasks[:1], cluster.LOCAL, 1)
    layouts = {
        "serial": (cluster.SERIAL, None),
        "1 worker": ("local", 1),
        "2 workers": ("local", 2),
    }
    walls: dict[str, list[float]] = {}
    work: dict[str, list[float]] = {}
    stolen: dict[str, list[float]] = {}
    for _ in range(args.repeat):
        for name, (scheduler, workers) in layouts.items():
            wall, busy, steal = _time(tasks, scheduler, workers)
            walls.setdefault(name, []).append(wall)
            work.setdefault(name, []).append(busy)
            stolen.setdefault(name, []).append(steal)
    print(
        "| layout | wall s (median) | task time s (sum) | speed-up over 1 worker "
        "| CPU time the hypervisor held back (steal) |"
    )
    print("|---|---|---|---|---|")
    one = statistics.median(walls["1 worker"])
    for name in layouts:
        wall = statistics.median(walls[name])
        print(
            f"| {name} | {wall:.1f} | {statistics.median(work[name]):.1f} | {one / wall:.2f}x "
            f"| {', '.join(f'{s:.1f} %' for s in stolen[name])} |"
        )
    ratio = one / statistics.median(walls["2 workers"])
    # each repeat's own pair, run minutes apart at most: the host's speed drifts between repeats
    pairs = ", ".join(f"{a / b:.2f}x" for a, b in zip(walls["1 worker"], walls["2 workers"]))
    print(f"2 workers over 1: {ratio:.2f}x (goal >= {GOAL}x); repeat by repeat {pairs}")
    beside = statistics.median(work["2 workers"]) / statistics.median(work["1 worker"])
    print(
        f"beside each other the tasks took {beside:.2f}x their time on one worker; a Python "
        f"loop took {twin_before:.2f}x (before the runs) and {twin_slowdown(*probe):.2f}x (after) "
        f"its time alone beside a copy of itself (median of {probe[0]} pairs; 1.00: the host's "
        "two cores do not slow each other)"
    )
    print(host_line())
    return 0


if __name__ == "__main__":
    sys.exit(main())
