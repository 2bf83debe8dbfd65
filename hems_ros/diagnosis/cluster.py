"""Many independent tasks (the suite's cases, an archive's runs) on a Dask cluster.

The one module of the project that imports Dask; the tasks themselves are plain functions
of the diagnosis core. Each task has a key that names it in the output folder: its result
is written there as soon as it is done (``<folder>/<key>.pkl``), so a run that was killed
starts again where it stopped, and a task whose worker died is submitted again and reported.

Schedulers: ``serial`` runs the tasks in this process, one after the other, each with every
core for its own parallel simulation batches; ``local`` (the default) starts a
``LocalCluster`` of worker processes on this machine, one per core unless told otherwise;
``tcp://HOST:PORT`` uses a running cluster (``dask scheduler``, ``dask worker``). On a
cluster each task runs its batches on ``threads_per_task`` cores (default 1): the workers
are the parallelism, and a worker holding every core would slow its neighbours. Results do
not depend on where or on how many threads a task ran (the simulation batch runs each
parameter set independently), so every scheduler gives the same results.
"""

from __future__ import annotations

import os
import pickle
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Callable, Sequence

import cloudpickle

from hems_ros.physics import jit

SERIAL = "serial"
LOCAL = "local"
SUFFIX = ".pkl"
CONNECT_S = 30.0
SPAWN_ENVIRON = "distributed.nanny.pre-spawn-environ"
MULTIPROCESSING_METHOD = "distributed.worker.multiprocessing-method"
WORKER_WAIT_S = 120.0
# Dask's housekeeping, which took 12 % of a core in an idle local cluster of two workers and
# 1.4 % with these (docs/design.md, "Suites and archives on Dask"): with a worker on each
# core it has no free core to run on and preempts the tasks. The workers' statistical
# profiler (for the dashboard) walks the running task's stack every 10 ms; every server's
# event loop measured its own delay every 20 ms; each nanny read its worker's memory every
# 0.1 s and each server its CPU and memory every 0.5 s; the scheduler looked for work to
# steal every second, though no worker ever holds more tasks than it runs (see _on_cluster).
QUIET = {
    "distributed.worker.profile.enabled": False,
    "distributed.admin.tick.interval": "1s",
    "distributed.worker.memory.monitor-interval": "1s",
    "distributed.admin.system-monitor.interval": "5s",
    "distributed.scheduler.work-stealing": False,
}


class TaskFailed(RuntimeError):
    """A task was lost with its worker on every attempt."""


@dataclass(frozen=True)
class Task:
    """``function(*args)``, a module-level function so that workers import it by name."""

    key: str  # unique among the tasks of a run; a file name
    function: Callable[..., Any]
    args: tuple = ()
    # a guess of the task's relative run time: the longest start first, so that the last
    # task to finish is a short one (the order changes no result)
    cost: float = 1.0


@dataclass(frozen=True)
class Done:
    """A task's result, how long it took and where it ran."""

    result: Any
    seconds: float
    where: str  # "here" or the worker's address


@dataclass
class Report:
    done: dict[str, Done]  # by task key, in the tasks' order
    resumed: int  # results found in the folder, not run again
    retried: list[str]  # one line per failed attempt that was run again
    workers: int
    seconds: float  # wall time of this call

    def results(self) -> list[Any]:
        return [d.result for d in self.done.values()]


def scheduler_error(scheduler: str) -> str | None:
    """What is wrong with a scheduler's name, or None."""
    if scheduler in (SERIAL, LOCAL) or (
        scheduler.startswith("tcp://") and ":" in scheduler.removeprefix("tcp://")
    ):
        return None
    return f"scheduler {scheduler!r}: serial, local or tcp://HOST:PORT"


def run_tasks(
    tasks: Sequence[Task],
    folder: Path,
    scheduler: str = LOCAL,
    workers: int | None = None,
    threads_per_task: int = 1,
    retries: int = 2,
    say: Callable[[str], None] = lambda message: None,
    describe: Callable[[Any], str] = lambda result: "",
) -> Report:
    """Run every task whose result is not yet in ``folder``; every task's :class:`Done`.

    ``retries``: how often a task lost with its worker is submitted again."""
    keys = [t.key for t in tasks]
    if len(set(keys)) != len(keys):
        raise ValueError("task keys must be unique")
    if (error := scheduler_error(scheduler)) is not None:
        raise ValueError(error)
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    start = time.perf_counter()
    done = {key: d for key in keys if (d := _load(folder, key)) is not None}
    if done:
        say(f"resuming: {len(done)} of {len(tasks)} tasks already done in {folder}")
    todo = sorted((t for t in tasks if t.key not in done), key=lambda t: -t.cost)
    progress = _Progress(len(tasks), len(done), say, describe)

    def finished(task: Task, result: Done) -> None:
        _save(folder, task.key, result)
        done[task.key] = result
        progress(task.key, result)

    retried: list[str] = []
    if scheduler == SERIAL:
        for task in todo:
            finished(task, _call(task.function, task.args, None))
        n_workers = 1
    elif not todo:  # everything was done: no cluster to start
        n_workers = 0
    else:
        n_workers = _on_cluster(
            todo, scheduler, workers, threads_per_task, retries, finished, retried, say
        )
    ordered = {key: done[key] for key in keys}
    return Report(ordered, len(tasks) - len(todo), retried, n_workers, time.perf_counter() - start)


def _call(function: Callable[..., Any], args: tuple, threads: int | None) -> Done:
    if threads is not None:
        jit.limit_threads(threads)
    start = time.perf_counter()
    result = function(*args)
    return Done(result, time.perf_counter() - start, _where())


def _where() -> str:
    try:
        from distributed import get_worker

        return get_worker().address
    except (ImportError, ValueError):
        return "here"


def _on_cluster(
    todo: list[Task],
    scheduler: str,
    workers: int | None,
    threads_per_task: int,
    retries: int,
    finished: Callable[[Task, Done], None],
    retried: list[str],
    say: Callable[[str], None],
) -> int:
    import dask
    from distributed import Client, LocalCluster, as_completed

    if scheduler == LOCAL:  # else a tcp:// address (run_tasks checked)
        # a worker that dies with a task fails that task at once, so that it is reported
        # and submitted again here, instead of being retried unseen by the scheduler; and the
        # workers start without the MALLOC_TRIM_THRESHOLD_ the nanny sets by default, which
        # also fixes glibc's mmap threshold at 128 KiB: every larger array was then mapped and
        # unmapped anew, and the suite's tasks ran 40 % slower than in a plain process; and
        # with Dask's housekeeping slowed down (QUIET)
        with dask.config.set(
            {
                **QUIET,
                "distributed.scheduler.allowed-failures": 0,
                f"{SPAWN_ENVIRON}.MALLOC_TRIM_THRESHOLD_": None,
                MULTIPROCESSING_METHOD: "forkserver",
            }
        ):
            _preload_fork_server({t.function.__module__ for t in todo})
            cluster = LocalCluster(
                n_workers=workers or os.cpu_count() or 1,
                threads_per_worker=1,
                processes=True,
                host="127.0.0.1",
                dashboard_address="127.0.0.1:0",  # its status page: loopback, any free port
            )
        client = Client(cluster)
    else:
        cluster, client = None, Client(scheduler, timeout=CONNECT_S)
        if not client.scheduler_info()["workers"]:
            say(f"waiting up to {WORKER_WAIT_S:.0f} s for a worker to join {scheduler}")
            client.wait_for_workers(1, timeout=WORKER_WAIT_S)
    try:
        n_workers = len(client.scheduler_info()["workers"])
        assert client.scheduler is not None  # a client that connected has its scheduler
        say(f"{n_workers} workers at {client.scheduler.address}")
        attempts = dict.fromkeys((t.key for t in todo), 0)

        def submit(task: Task):
            attempts[task.key] += 1
            return client.submit(
                _call,
                task.function,
                task.args,
                threads_per_task,
                key=f"{task.key}-{attempts[task.key]}",
                pure=False,
            )

        # no more tasks in flight than the cluster has threads: each next task goes to the
        # first worker that is free, longest first, whatever the scheduler guesses of their
        # durations (it would queue tasks behind a long one on a busy worker)
        waiting = list(reversed(todo))
        running: dict = {}
        flow = as_completed()

        def top_up() -> None:
            free = max(1, _threads(client)) - len(running)
            for _ in range(min(free, len(waiting))):
                task = waiting.pop()
                future = submit(task)
                running[future] = task
                flow.add(future)

        top_up()
        for future in flow:
            task = running.pop(future)
            if future.status == "finished":
                finished(task, future.result())
            else:
                error = _error(future)
                if not _lost(error):  # the task's own error: its inputs would raise it again
                    raise error
                line = f"{task.key}: attempt {attempts[task.key]} failed ({_why(error)})"
                if attempts[task.key] > retries:
                    raise TaskFailed(line) from error
                retried.append(line)
                say(line + "; submitted again")
                waiting.append(task)
            top_up()
        return n_workers
    finally:
        client.close()
        if cluster is not None:
            cluster.close()


def _preload_fork_server(modules: set[str]) -> None:
    """Local workers fork from one server process that has imported Dask and the tasks'
    modules once, instead of each starting Python and importing them anew (start and close
    times: docs/design.md, "Suites and archives on Dask"). The server keeps the environment
    it started with, so the nanny's variables for new workers (pre-spawn-environ) come too
    late for glibc's malloc, which reads them at start-up; the one the nanny sets by default
    is left out above anyway. Call it under the configuration that selects the server: Dask
    sets its own module list at its first use, which this one replaces. Once the server
    runs, a further list changes nothing; a module that fails to import there is imported
    by its task instead."""
    from distributed.utils import get_mp_context

    get_mp_context().set_forkserver_preload(["distributed", "numpy", *sorted(modules)])


def _threads(client) -> int:
    return sum(w["nthreads"] for w in client.scheduler_info()["workers"].values())


def _error(future) -> BaseException:
    try:
        return future.exception()
    except BaseException as error:  # noqa: BLE001 - a cancelled future raises its reason
        return error


def _lost(error: BaseException) -> bool:
    """The task was lost with its worker (or the connection to it), not failed by itself."""
    return type(error).__name__ in ("KilledWorker", "CancelledError", "FutureCancelledError")


def _why(error: BaseException) -> str:
    if type(error).__name__ == "KilledWorker":
        return "its worker died"
    return f"{type(error).__name__}: {error}"


class _Progress:
    def __init__(self, total: int, already: int, say, describe) -> None:
        self._total, self._count, self._say, self._describe = total, already, say, describe

    def __call__(self, key: str, d: Done) -> None:
        self._count += 1
        what = self._describe(d.result)
        where = "" if d.where == "here" else f" on {d.where}"
        self._say(
            f"[{self._count}/{self._total}] {key}{': ' + what if what else ''} "
            f"({d.seconds:.1f} s{where})"
        )


def _path(folder: Path, key: str) -> Path:
    return folder / f"{key}{SUFFIX}"


def _load(folder: Path, key: str) -> Done | None:
    path = _path(folder, key)
    if not path.is_file():
        return None
    try:
        with path.open("rb") as f:
            done = pickle.load(f)
    except Exception:  # noqa: BLE001 - a file cut short or from other code: run it again
        return None
    return done if isinstance(done, Done) else None


def _save(folder: Path, key: str, done: Done) -> None:
    # written beside and renamed, so that a run killed while writing leaves no half file
    path = _path(folder, key)
    part = path.with_suffix(".part")
    with part.open("wb") as f:
        cloudpickle.dump(done, f)  # results may hold lambdas (a diagnosis's candidates)
    os.replace(part, path)
