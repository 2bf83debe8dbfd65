"""``hems diagnose --each``: a lab's archive of runs, every run diagnosed on its own and all of
them together (one fit of the wire's parameters, each run on its own rig), as tasks on a Dask
cluster or serially (:mod:`hems_ros.diagnosis.cluster`)."""

from __future__ import annotations

import argparse
import functools
import sys
from pathlib import Path
from typing import TYPE_CHECKING, Callable

if TYPE_CHECKING:
    from hems_ros.diagnosis.runs import Run
    from hems_ros.diagnosis.workflow import Diagnosis
    from hems_ros.physics.params import UnitParams

SHARED = "all"


def task_keys(names: list[str]) -> list[str]:
    """The runs' names as folder names, numbered where two runs share one."""
    taken = {SHARED}
    keys = []
    for name in names:
        key, k = name, 2
        while key in taken:
            key, k = f"{name}-{k}", k + 1
        taken.add(key)
        keys.append(key)
    return keys


def diagnose_each(
    groups: list[tuple[str, list[Run]]],
    heldout: list[Run],
    model: UnitParams,
    options: dict,
    out: Path,
    args: argparse.Namespace,
    say: Callable[[str], None],
) -> int:
    """Each group of runs (a RUN's fingers or tests) alone, then all of them with ``heldout``;
    a report folder for each and a table of the verdicts."""
    # here, not at the top: every `hems` verb imports this module while it looks for verbs,
    # and these take seconds of CPU (scipy, numba, matplotlib) that a `hems setpoint` joining
    # a running graph would take from it
    from hems_ros.diagnosis import cluster
    from hems_ros.diagnosis.inputs import ARCHIVE_TABLE
    from hems_ros.diagnosis.workflow import diagnose
    from hems_ros.reports import diagnosis as report

    run = functools.partial(diagnose, **options)
    keys = task_keys([name for name, _ in groups])
    everything = [r for _, group in groups for r in group]
    tasks = [
        cluster.Task(key, run, (group, [], model), cost=len(group))
        for key, (_, group) in zip(keys, groups)
    ]
    tasks.append(cluster.Task(SHARED, run, (everything, heldout, model), cost=len(everything)))
    try:
        done = cluster.run_tasks(
            tasks,
            out / ".tasks",
            scheduler=args.scheduler,
            workers=args.workers,
            say=say,
            describe=lambda d: d.verdict,
        ).done
    except cluster.TaskFailed as error:
        print(f"hems diagnose: {error}", file=sys.stderr)
        return 1
    for key, d in done.items():
        report.write(d.result, out / key)
    (out / ARCHIVE_TABLE).write_text(_table({key: d.result for key, d in done.items()}))
    say(f"reports: {out}")
    for key, d in done.items():
        print(f"{key}: {d.result.summary_line()}")
    return 0


def _table(diagnoses: dict[str, Diagnosis]) -> str:
    lines = [
        "# Diagnosis of an archive",
        "",
        f"Each run on its own, then all of them together ({SHARED}); every report in the "
        "folder of its name.",
        "",
        "| run | verdict |",
        "|---|---|",
    ]
    lines += [f"| [{key}]({key}/report.md) | {d.summary_line()} |" for key, d in diagnoses.items()]
    return "\n".join(lines) + "\n"
