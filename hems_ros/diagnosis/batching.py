"""Many fits side by side, one simulation batch per round.

Each fit runs scipy's least squares in a thread of its own; whenever it needs the model it
hands its parameter sets to the :class:`Barrier` and waits. The fits take turns, in fit
order: one runs until its next request (or its end) and wakes the next, and the last of a
round runs every request as one batch (the physics batch vectorises across sets and spreads
them over the cores), then wakes the first. Each round holds exactly one request of every
live fit, in fit order, so the batches, and therefore the results, do not depend on how the
threads were scheduled.

The threads only turn scipy's loop inside out. Their Python holds the GIL, so running them
at once would gain nothing and cost a wake-up of every fit after each batch, each of which
waits for a core on a host whose cores are all busy (a suite's worker beside another).
"""

from __future__ import annotations

import threading
from typing import Callable, Sequence, TypeVar

T = TypeVar("T")


class Barrier:
    """Gathers the requests of jobs that take turns into one call of ``evaluate`` per round."""

    def __init__(self, evaluate: Callable[[list], list]) -> None:
        self._evaluate = evaluate
        self._lock = threading.Lock()
        self._local = threading.local()
        self._turns: list[threading.Event] = []
        self._live: list[int] = []  # jobs not ended, in order
        self._pending: dict[int, list] = {}
        self._results: dict[int, list] = {}
        self._error: BaseException | None = None
        self.rounds = 0
        self.evaluated = 0

    def run(self, jobs: Sequence[Callable[["Barrier"], T]]) -> list[T]:
        """Run ``jobs`` (each called with this barrier) in turns; their results in order."""
        outs: list = [None] * len(jobs)
        errors: list = [None] * len(jobs)
        self._turns = [threading.Event() for _ in jobs]
        self._live, self._error = list(range(len(jobs))), None

        def work(i: int, job) -> None:
            self._local.job = i
            self._wait_turn(i)
            try:
                outs[i] = job(self)
            except BaseException as error:  # noqa: BLE001 - re-raised in the caller's thread
                errors[i] = error
            finally:
                with self._lock:
                    self._live.remove(i)
                    self._pass_turn(i)

        threads = [
            threading.Thread(target=work, args=(i, job), daemon=True) for i, job in enumerate(jobs)
        ]
        for thread in threads:
            thread.start()
        if jobs:
            self._turns[0].set()
        for thread in threads:
            thread.join()
        first = next((e for e in errors if e is not None), None)
        if first is not None:
            raise first
        return outs

    def __call__(self, items: list) -> list:
        """Evaluate ``items`` in the next round (blocks until it has run)."""
        job = self._local.job
        with self._lock:
            if self._error is not None:  # a failed batch ends every round of this run
                raise RuntimeError("a batch of model evaluations failed") from self._error
            self._pending[job] = list(items)
            self._pass_turn(job)
        self._wait_turn(job)
        if job not in self._results:
            raise RuntimeError("a batch of model evaluations failed") from self._error
        return self._results.pop(job)

    def _wait_turn(self, job: int) -> None:
        self._turns[job].wait()
        self._turns[job].clear()

    def _pass_turn(self, after: int) -> None:
        """Wake the next live job of this round; after the round's last, run the batch and
        wake the first (called with the lock held)."""
        if self._error is not None:  # every waiting job was woken with it
            return
        following = next((j for j in self._live if j > after), None)
        if following is not None:
            self._turns[following].set()
            return
        if not self._pending:
            return
        order = sorted(self._pending)
        batch = [item for job in order for item in self._pending[job]]
        try:
            results = self._evaluate(batch)
        except BaseException as error:  # noqa: BLE001 - handed to every waiting job
            self._error = error
            self._pending.clear()
            for job in order:
                self._turns[job].set()
            return
        self.rounds += 1
        self.evaluated += len(batch)
        start = 0
        for job in order:
            n = len(self._pending[job])
            self._results[job] = results[start : start + n]
            start += n
        self._pending.clear()
        self._turns[order[0]].set()
