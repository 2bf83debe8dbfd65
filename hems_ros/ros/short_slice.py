"""Ask Linux's scheduler for a short time slice for this process's threads (EEVDF, 6.12+).

Under the fair scheduler a thread woken for its data (a timer, a message) waits until the
thread running on its core has used up its slice; with another program busy on a core, that
is about 1.4 ms per wake-up on this two-core host. Since Linux 6.12 any thread may ask for
a shorter slice (``sched_runtime`` of ``sched_setattr`` under SCHED_OTHER, no privilege
needed): its deadlines come sooner, so it preempts a long-running thread when it wakes. It
gets no more CPU than before; the fair share is unchanged, only the order within it. A busy
loop sharing the core delayed a 5 ms sleeper's wake-up by 3.4 ms at the 99th percentile
with the default slice and by 0.13 ms with 0.1 ms (benchmarks/bench_wake_slice.py).

The composed graph's process asks (hems_ros/nodes/composed.py). The separate processes do
not: there every node would preempt every other on each message, and the separate graph
took 0.98-1.24 cores against 0.82-1.00 and its latency grew (docs/design.md).

Threads and child processes inherit the slice, so a process asks once, before its
middleware starts threads. Older kernels accept the request and ignore it; elsewhere
(another OS or architecture) nothing is asked.
"""

from __future__ import annotations

import ctypes
import os
import platform
import struct
import threading

#: The kernel's shortest slice, so that a wake-up waits the least.
SLICE_S = 100e-6
# struct sched_attr, first version with utilisation clamps (56 bytes):
# size, policy, flags, nice, priority, runtime, deadline, period, util_min, util_max
_ATTR = "IIQiIQQQII"
_SETATTR = {"x86_64": 314, "aarch64": 274}
_GETATTR = {"x86_64": 315, "aarch64": 275}


def _syscall(numbers: dict[str, int]) -> tuple[ctypes.CDLL, int] | None:
    number = numbers.get(platform.machine())
    if number is None or not hasattr(os, "sched_getscheduler"):
        return None
    return ctypes.CDLL(None, use_errno=True), number


def request_short_slice(seconds: float = SLICE_S) -> bool:
    """Ask for a ``seconds`` slice for every thread of this process under SCHED_OTHER, and so
    for the threads and processes they start afterwards; whether the kernel accepted it for
    the calling thread (not whether it honours it: see :func:`current_slice_s`)."""
    call = _syscall(_SETATTR)
    if call is None or os.sched_getscheduler(0) != os.SCHED_OTHER:
        return False
    libc, number = call
    nice = os.getpriority(os.PRIO_PROCESS, 0)
    fields = (os.SCHED_OTHER, 0, nice, 0, round(seconds * 1e9), 0, 0, 0, 0)
    attr = ctypes.create_string_buffer(struct.pack(_ATTR, struct.calcsize(_ATTR), *fields))
    # threads that imports started (numpy's pool) do not inherit a later request
    for tid in _threads():
        try:
            if tid != threading.get_native_id() and os.sched_getscheduler(tid) == os.SCHED_OTHER:
                libc.syscall(number, tid, attr, 0)
        except OSError:
            continue  # the thread ended meanwhile
    return libc.syscall(number, 0, attr, 0) == 0


def _threads() -> list[int]:
    try:
        return [int(tid) for tid in os.listdir("/proc/self/task")]
    except OSError:
        return []


def current_slice_s(tid: int = 0) -> float | None:
    """The slice the kernel keeps for a thread (0: the calling one), None where it cannot
    say: 0 on kernels without per-thread slices."""
    call = _syscall(_GETATTR)
    if call is None:
        return None
    libc, number = call
    size = struct.calcsize(_ATTR)
    buffer = ctypes.create_string_buffer(size)
    if libc.syscall(number, tid, buffer, size, 0) != 0:
        return None
    return struct.unpack(_ATTR, buffer.raw)[5] * 1e-9
