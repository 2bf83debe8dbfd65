"""A process-wide limit on the batch's threads reaches threads started after it was set (numba
counts threads per calling thread, and a new thread starts with all of them)."""

from __future__ import annotations

import threading

import numba

from hems_ros.physics import jit


def _threads_in_a_new_thread(apply: bool) -> int:
    seen = []

    def run() -> None:
        if apply:
            jit.apply_thread_limit()
        seen.append(numba.get_num_threads())

    thread = threading.Thread(target=run)
    thread.start()
    thread.join()
    return seen[0]


def test_a_thread_limit_reaches_a_thread_started_after_it():
    numba.set_num_threads(1)  # in this thread only
    jit.limit_threads(1)
    try:
        assert _threads_in_a_new_thread(apply=False) == numba.config.NUMBA_NUM_THREADS
        assert _threads_in_a_new_thread(apply=True) == 1
    finally:
        jit.limit_threads(None)
        numba.set_num_threads(numba.config.NUMBA_NUM_THREADS)
    assert _threads_in_a_new_thread(apply=True) == numba.config.NUMBA_NUM_THREADS
