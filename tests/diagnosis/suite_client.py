"""Runs the suite tasks of test_suite_on_dask on a scheduler and prints their records as one
JSON line: ``python suite_client.py SCHEDULER FOLDER``."""

from __future__ import annotations

import json
import sys
from pathlib import Path

from hems_ros.diagnosis import cluster, suite_runs

CASES = (("load_damping", "pulses", "mid"),)


def tasks() -> list[cluster.Task]:
    rows = suite_runs.grid(0, quick=True)
    return suite_runs.suite_tasks([r for r in rows if (r[0].name, *r[1:3]) in CASES])


def run(scheduler: str, folder: Path, workers: int | None = None) -> cluster.Report:
    return cluster.run_tasks(tasks(), folder, scheduler=scheduler, workers=workers)


def records(report: cluster.Report) -> list[dict]:
    return [suite_runs.record(o) for o in report.results()]


if __name__ == "__main__":
    report = run(sys.argv[1], Path(sys.argv[2]))
    where = sorted({d.where.rsplit(":", 1)[0] for d in report.done.values()})
    print(json.dumps({"records": records(report), "workers": report.workers, "where": where}))
