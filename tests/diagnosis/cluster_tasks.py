"""Small tasks for the cluster runner's tests, and a run of them to kill from outside:
``python cluster_tasks.py FOLDER N`` runs N tasks serially into FOLDER."""

from __future__ import annotations

import os
import signal
import sys
import time
from pathlib import Path

from hems_ros.diagnosis import cluster


def square(x: int, die_once: str = "", seconds: float = 0.0) -> int:
    """x * x; the first call for ``x == 3`` with a marker path kills its own process."""
    if die_once and x == 3 and not os.path.exists(die_once):
        Path(die_once).touch()
        os.kill(os.getpid(), signal.SIGKILL)
    time.sleep(seconds)
    return x * x


def parent_command(_: int) -> str:
    """The command line of the process that started this one."""
    with open(f"/proc/{os.getppid()}/cmdline") as cmdline:
        return cmdline.read().replace("\0", " ")


def worker_settings(_: int) -> dict:
    """The Dask settings the worker that runs this task sees, of those the runner quiets."""
    import dask

    return {key: dask.config.get(key) for key in cluster.QUIET}


def fails(x: int) -> int:
    raise ValueError(f"no square for {x}")


def squares(n: int, die_once: str = "", seconds: float = 0.0) -> list[cluster.Task]:
    return [cluster.Task(f"square{i}", square, (i, die_once, seconds)) for i in range(n)]


if __name__ == "__main__":
    folder, n = Path(sys.argv[1]), int(sys.argv[2])
    cluster.run_tasks(squares(n, seconds=0.3), folder, scheduler=cluster.SERIAL, say=print)
