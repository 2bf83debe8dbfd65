"""Many concurrent fits, one simulation batch per round.

Each fit runs scipy's least squares in a thread of its own; whenever it needs the model it
hands its parameter sets to the :class:`Barrier` and waits. Once every fit still running
is waiting, the barrier runs all their sets as one batch (the physics batch vectorises
across sets and spreads them over the cores) and wakes them. Each round holds exactly one
request of every live fit, in fit order, so the batches, and therefore the results, do
not depend on how the threads were scheduled.
"""

from __future__ import annotations

import threading
from typing import Callable, Sequence, TypeVar

T = TypeVar("T")


class Barrier:
    """Gathers the requests of concurrent jobs into one call of ``evaluate`` per round."""

    def __init__(self, evaluate: Callable[[list], list]) -> None:
        self._evaluate = evaluate
        self._cv = threading.Condition()
        self._local = threading.local()
        self._live = 0
        self._pending: dict[int, list] = {}
        self._results: dict[int, list] = {}
        self._error: BaseException | None = None
        self.rounds = 0
        self.evaluated = 0

    def run(self, jobs: Sequence[Callable[["Barrier"], T]]) -> list[T]:
        """Run ``jobs`` (each called with this barrier) concurrently; their results in order."""
        outs: list = [None] * len(jobs)
        errors: list = [None] * len(jobs)
        self._live, self._error = len(jobs), None

        def work(i: int, job) -> None:
            self._local.job = i
            try:
                outs[i] = job(self)
            except BaseException as error:  # noqa: BLE001 - re-raised in the caller's thread
                errors[i] = error
            finally:
                with self._cv:
                    self._live -= 1
                    self._flush()

        threads = [
            threading.Thread(target=work, args=(i, job), daemon=True) for i, job in enumerate(jobs)
        ]
        for thread in threads:
            thread.start()
        for thread in threads:
            thread.join()
        first = next((e for e in errors if e is not None), None)
        if first is not None:
            raise first
        return outs

    def __call__(self, items: list) -> list:
        """Evaluate ``items`` in the next round (blocks until it has run)."""
        job = self._local.job
        with self._cv:
            self._pending[job] = list(items)
            self._flush()
            while job not in self._results and self._error is None:
                self._cv.wait()
            if job not in self._results:
                raise RuntimeError("a batch of model evaluations failed") from self._error
            return self._results.pop(job)

    def _flush(self) -> None:
        """Run the round once every live job waits (called with the lock held)."""
        if not self._pending or len(self._pending) < self._live:
            return
        order = sorted(self._pending)
        batch = [item for job in order for item in self._pending[job]]
        try:
            results = self._evaluate(batch)
        except BaseException as error:  # noqa: BLE001 - handed to every waiting job
            self._error = error
            self._pending.clear()
            self._cv.notify_all()
            return
        self.rounds += 1
        self.evaluated += len(batch)
        start = 0
        for job in order:
            n = len(self._pending[job])
            self._results[job] = results[start : start + n]
            start += n
        self._pending.clear()
        self._cv.notify_all()
