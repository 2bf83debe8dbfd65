"""Fast DDS's receive and event threads of a node process under SCHED_BATCH (Linux).

When a node sends a message, the receiving process's listener thread wakes and, under the
default policy, usually preempts the sender on its core, which then finishes its period's
work after the listener with cold caches: a scheduler trace of the separate-process graph
counted about 1,600 such preemptions a second (docs/design.md). A SCHED_BATCH thread
does not preempt on wake-up: it runs once the sender sleeps (the trace's senders ran on for
about 0.2-0.7 ms on average) or at once on an idle core. The nodes' main threads keep the default
policy, so a node woken for its data still preempts whatever runs. Five alternating 20 s runs of the
separate graph: 1.15-1.25 against 1.22-1.32 cores, each run lower. Node processes started
by :func:`hems_ros.ros.runner.run_node` do this; the composed process does not (its nodes
share one participant and reach each other without a listener thread).
"""

from __future__ import annotations

import os

THREAD_PREFIXES = ("dds.shm.", "dds.udp.", "dds.ev.")  # Fast DDS names its threads so


def defer_middleware_threads() -> None:
    """Put this process's Fast DDS listener and event threads under SCHED_BATCH. Call it once
    the nodes exist (their participant starts the threads)."""
    if not hasattr(os, "SCHED_BATCH") or not os.path.isdir("/proc/self/task"):
        return
    for tid in os.listdir("/proc/self/task"):
        try:
            with open(f"/proc/self/task/{tid}/comm") as comm:
                if comm.read().startswith(THREAD_PREFIXES):
                    os.sched_setscheduler(int(tid), os.SCHED_BATCH, os.sched_param(0))
        except OSError:
            continue  # the thread ended meanwhile
