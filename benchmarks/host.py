"""How quick the host is right now, printed beside every graph benchmark's figures.

The development VM's speed swings by half within minutes; a figure means little without the
host's phase it was measured in, and runs are comparable only at similar readings.
"""

from __future__ import annotations

import os
import time


def host_speed_s(additions: int = 3_000_000) -> float:
    """Seconds a fixed pure-Python loop (``additions`` additions, three million by default)
    takes now. The speed of a shared host swings by half within minutes; runs are comparable
    only at similar values."""
    start, total = time.perf_counter(), 0
    for i in range(additions):
        total += i
    return time.perf_counter() - start


def wake_round_trip_us(rounds: int = 5000) -> float:
    """Mean microseconds for two processes to wake each other once over a pipe: a second
    reading of the host beside the Python loop, which kept its speed in a phase where the same
    graph took 1.02-1.29 cores instead of 0.76-0.86."""
    to_child, from_parent = os.pipe()
    from_child, to_parent = os.pipe()
    pid = os.fork()
    if pid == 0:
        for _ in range(rounds):
            os.read(to_child, 1)
            os.write(to_parent, b"x")
        os._exit(0)
    start = time.perf_counter()
    for _ in range(rounds):
        os.write(from_parent, b"x")
        os.read(from_child, 1)
    elapsed = time.perf_counter() - start
    os.waitpid(pid, 0)
    for fd in (to_child, from_parent, from_child, to_parent):
        os.close(fd)
    return elapsed / rounds * 1e6


def twin_slowdown(pairs: int = 5, additions: int = 15_000_000) -> float:
    """How much longer :func:`host_speed_s`'s loop takes beside a copy of itself on the other
    core than alone (median of ``pairs``; 1.0: the cores do not slow each other). On this VM
    such pairs read 1.02-1.07 in one phase and 0.98-1.37 in another: two vCPUs may share a
    physical core's resources, which no division of work between two processes can undo
    (docs/design.md, "Suites and archives on Dask")."""
    ratios = []
    for _ in range(pairs):
        alone = _loops_in_children(1, additions)
        ratios.append(_loops_in_children(2, additions) / alone)
    return sorted(ratios)[len(ratios) // 2]


def _loops_in_children(count: int, additions: int) -> float:
    """Mean seconds of :func:`host_speed_s` in ``count`` forked processes started together."""
    pipes, pids = [], []
    for _ in range(count):
        read, write = os.pipe()
        pid = os.fork()
        if pid == 0:
            os.write(write, repr(host_speed_s(additions)).encode())
            os._exit(0)
        os.close(write)
        pipes.append(read)
        pids.append(pid)
    times = []
    for read, pid in zip(pipes, pids):
        times.append(float(os.read(read, 64)))
        os.close(read)
        os.waitpid(pid, 0)
    return sum(times) / len(times)


def cpu_jiffies() -> tuple[int, int]:
    """(steal, total) clock ticks of all CPUs since boot (/proc/stat; (0, 0) where it is missing).

    Steal is the time a virtual CPU was ready to run while the hypervisor ran something else:
    on a shared host it is the part of a slow phase that no code of ours can change."""
    try:
        with open("/proc/stat") as stat:
            fields = [int(x) for x in stat.readline().split()[1:]]
    except (OSError, ValueError):
        return 0, 0
    # user nice system idle iowait irq softirq steal (guest time is counted in user already)
    return (fields[7] if len(fields) > 7 else 0), sum(fields[:8])


def steal_pct(before: tuple[int, int], after: tuple[int, int]) -> float:
    """Per cent of all CPUs' time between two :func:`cpu_jiffies` readings that was stolen."""
    total = after[1] - before[1]
    return 100.0 * (after[0] - before[0]) / total if total > 0 else 0.0


def host_line() -> str:
    return (
        f"host speed {host_speed_s():.2f} s (a 3-million-addition Python loop; lower is quicker), "
        f"wake-up round trip {wake_round_trip_us():.1f} us (two processes over a pipe)"
    )
