"""The Barrier that gathers concurrent fits into one model batch per round
(hems_ros.diagnosis.batching)."""

from __future__ import annotations

import random
import threading
import time

import pytest

from hems_ros.diagnosis.batching import Barrier

TIMEOUT_S = 10.0


def _run(barrier: Barrier, jobs) -> list:
    """barrier.run in a thread of its own, so a deadlock fails the test instead of hanging it."""
    box: dict = {}

    def target() -> None:
        try:
            box["out"] = barrier.run(jobs)
        except BaseException as error:  # noqa: BLE001 - inspected by the test
            box["error"] = error

    thread = threading.Thread(target=target, daemon=True)
    thread.start()
    thread.join(TIMEOUT_S)
    assert not thread.is_alive(), "Barrier.run deadlocked"
    if "error" in box:
        raise box["error"]
    return box["out"]


class Recorder:
    """An evaluate that squares numbers and logs every batch it was given."""

    def __init__(self, delay_s: float = 0.0) -> None:
        self.batches: list[list] = []
        self.delay_s = delay_s

    def __call__(self, items: list) -> list:
        self.batches.append(list(items))
        time.sleep(self.delay_s)
        return [(tag, x * x) for tag, x in items]


def _job(tag: int, calls: list[int], jitter: float = 0.0, seed: int = 0):
    """A job that asks ``calls[k]`` items in its k-th request and checks it got its own back."""

    def job(barrier: Barrier) -> list:
        rng = random.Random(seed * 100 + tag)
        got = []
        for k, n in enumerate(calls):
            time.sleep(rng.uniform(0.0, jitter))  # threads reach the barrier in any order
            items = [(tag, 10 * k + i) for i in range(n)]
            answer = barrier(items)
            assert answer == [(tag, x * x) for _, x in items]
            got.append(sum(x for _, x in answer))
        return tag, got

    return job


def test_every_round_holds_one_request_of_every_live_job() -> None:
    ev = Recorder()
    barrier = Barrier(ev)
    calls = {0: [2, 1, 3], 1: [1], 2: [3, 3], 3: []}
    out = _run(barrier, [_job(t, c, jitter=0.01) for t, c in calls.items()])
    # round 1: jobs 0, 1, 2; round 2: jobs 0 and 2 (1 is done); round 3: job 0
    assert [[tag for tag, _ in b] for b in ev.batches] == [
        [0, 0, 1, 2, 2, 2],
        [0, 2, 2, 2],
        [0, 0, 0],
    ]
    assert barrier.rounds == 3 and barrier.evaluated == 13
    assert out == [(0, [1, 100, 400 + 441 + 484]), (1, [0]), (2, [5, 100 + 121 + 144]), (3, [])]


def test_a_job_that_ends_lets_the_waiting_ones_go_on() -> None:
    def short(barrier: Barrier):
        barrier([(5, 1)])
        time.sleep(0.2)  # the others wait in round 2 before it ends
        return "done"

    ev = Recorder()
    out = _run(Barrier(ev), [_job(0, [1, 1]), short, _job(2, [2, 2])])
    assert out == [(0, [0, 100]), "done", (2, [1, 221])]
    assert [[tag for tag, _ in b] for b in ev.batches] == [[0, 5, 2, 2], [0, 2, 2]]


def test_jobs_take_turns_one_at_a_time() -> None:
    # each job's Python between requests runs alone: the next job waits for it
    running, most = [0], [0]

    def job(barrier: Barrier) -> int:
        total = 0
        for k in range(3):
            running[0] += 1
            most[0] = max(most[0], running[0])
            time.sleep(0.01)  # releases the GIL: a job running beside it would be seen here
            running[0] -= 1
            total += barrier([(0, k)])[0][1]
        return total

    ev = Recorder()
    barrier = Barrier(ev)
    assert _run(barrier, [job] * 8) == [0 + 1 + 4] * 8
    assert most[0] == 1
    assert [len(b) for b in ev.batches] == [8, 8, 8] and barrier.rounds == 3


@pytest.mark.parametrize("seed", range(4))
def test_batches_do_not_depend_on_thread_scheduling(seed: int) -> None:
    calls = {t: [1 + (t + k) % 3 for k in range(2 + t % 3)] for t in range(6)}
    ev = Recorder()
    out = _run(Barrier(ev), [_job(t, c, jitter=0.005, seed=seed) for t, c in calls.items()])
    reference = Recorder()
    expected = _run(Barrier(reference), [_job(t, c) for t, c in calls.items()])
    assert ev.batches == reference.batches and out == expected
    assert [len(b) for b in ev.batches] == [12, 12, 6, 6]  # jobs 0-5, 0-5, 1 2 4 5, 2 5


def test_an_evaluate_error_reaches_every_waiting_job() -> None:
    class Broken(Exception):
        pass

    seen: list = []

    def evaluate(items: list) -> list:
        if len(seen) == 1:
            raise Broken("model blew up")
        seen.append(items)
        return list(items)

    def job(barrier: Barrier):
        barrier([1])
        try:
            barrier([2])
        except RuntimeError as error:
            return error
        return None

    errors = _run(Barrier(evaluate), [job] * 3)
    assert len(seen) == 1 and len(seen[0]) == 3
    assert all(isinstance(e, RuntimeError) and isinstance(e.__cause__, Broken) for e in errors)
    assert str(errors[0]) == "a batch of model evaluations failed"


def test_an_evaluate_error_fails_the_run() -> None:
    def evaluate(items: list) -> list:
        raise ValueError("bad set")

    def job(barrier: Barrier):
        return barrier([0])

    with pytest.raises(RuntimeError, match="a batch of model evaluations failed") as caught:
        _run(Barrier(evaluate), [job] * 4)
    assert isinstance(caught.value.__cause__, ValueError)


def test_a_job_that_raises_does_not_hold_up_the_others() -> None:
    def bad(barrier: Barrier):
        barrier([(9, 1)])
        time.sleep(0.2)  # the others are waiting for it by now
        raise KeyError("job 1 gave up")

    ev = Recorder()
    barrier = Barrier(ev)
    finished: list = []

    def good(tag: int):
        inner = _job(tag, [1, 1, 1, 1])

        def job(b: Barrier):
            result = inner(b)
            finished.append(tag)
            return result

        return job

    with pytest.raises(KeyError, match="job 1 gave up"):
        _run(barrier, [good(0), bad, good(2)])
    assert sorted(finished) == [0, 2]
    assert [len(b) for b in ev.batches] == [3, 2, 2, 2]


def test_a_barrier_runs_again_after_a_failure() -> None:
    fail = [True]

    def evaluate(items: list) -> list:
        if fail[0]:
            fail[0] = False
            raise ValueError("once")
        return [x + 1 for x in items]

    barrier = Barrier(evaluate)
    with pytest.raises(RuntimeError):
        _run(barrier, [lambda b: b([1])])
    assert _run(barrier, [lambda b: b([1]), lambda b: b([5, 6])]) == [[2], [6, 7]]
