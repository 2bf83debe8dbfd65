"""How much faster two local Dask workers run a set of tasks than one, on this machine.

Each layout starts from an empty output folder and is timed from the call to the last
result, the cluster's start and close included. A process's first local cluster also waits
for the fork server's imports (``cluster``), which a process pays once: that start is made
untimed first.
"""

from __future__ import annotations

import tempfile
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Callable, Sequence

from hems_ros.diagnosis import cluster

# enough tasks that two workers split them evenly, few enough to take minutes, not an hour
SPREAD = 16


@dataclass(frozen=True)
class Timing:
    wall_s: float  # from the call to the last result
    task_s: float  # the tasks' own times, summed


def timed(
    tasks: Sequence[cluster.Task],
    scheduler: str,
    workers: int | None,
    say: Callable[[str], None] = lambda message: None,
) -> Timing:
    """Run ``tasks`` afresh (nothing resumed) and time them."""
    with tempfile.TemporaryDirectory(prefix="hems-speedup-") as folder:
        start = time.perf_counter()
        report = cluster.run_tasks(
            tasks, Path(folder), scheduler=scheduler, workers=workers, say=say
        )
        wall = time.perf_counter() - start
    return Timing(wall, sum(d.seconds for d in report.done.values()))


@dataclass(frozen=True)
class Speedup:
    tasks: int
    one: Timing  # one local worker
    two: Timing  # two local workers

    @property
    def ratio(self) -> float:
        return self.one.wall_s / self.two.wall_s

    @property
    def beside(self) -> float:
        """The tasks' own time on two workers over theirs on one: above 1, the two cores
        slowed each other."""
        return self.two.task_s / self.one.task_s


def spread(tasks: Sequence[cluster.Task], count: int = SPREAD) -> list[cluster.Task]:
    """``count`` tasks taken at even steps through ``tasks`` (a grid's cases differ in cost
    from end to end)."""
    step = max(1, len(tasks) // count)
    return list(tasks[::step][:count])


def two_over_one(
    tasks: Sequence[cluster.Task], say: Callable[[str], None] = lambda message: None
) -> Speedup:
    timed(tasks[:1], cluster.LOCAL, 1)
    say(f"speed-up: {len(tasks)} tasks on one local worker, then on two")
    one = timed(tasks, cluster.LOCAL, 1, say)
    two = timed(tasks, cluster.LOCAL, 2, say)
    result = Speedup(len(tasks), one, two)
    say(f"speed-up: one worker {one.wall_s:.1f} s, two {two.wall_s:.1f} s: {result.ratio:.2f}x")
    return result
