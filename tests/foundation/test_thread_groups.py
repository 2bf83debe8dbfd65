"""The per-thread split of bench_graph_floor.py (benchmarks/threads.py): threads grouped by
role, their CPU and context switches between two snapshots."""

from __future__ import annotations

import os
import threading

import pytest
from benchmark_modules import load

threads = load("threads")

Use = threads.ThreadUse


def test_threads_are_grouped_by_role_and_middleware_kind() -> None:
    group = threads.thread_group
    assert group(100, "100", "python3", "unit") == "main thread, unit"
    assert group(100, "101", "dds.shm.50423", "unit") == "dds shared-memory listener, own port"
    assert group(100, "102", "dds.shm.7005", "unit") == (
        "dds shared-memory listener, host-wide port"
    )
    assert group(100, "103", "dds.ev.0", "unit").startswith("dds event thread")
    assert group(100, "104", "dds.asyn.0.1", "unit") == "dds asynchronous writer"
    assert group(100, "105", "dds.tls.request", "unit") == "dds tls.request"
    assert group(100, "106", "python3", "unit") == "other threads"


def test_use_between_snapshots_is_summed_by_group_per_second() -> None:
    before = {
        (1, "1"): ("main thread, unit", Use(1.0, 100)),
        (2, "2"): ("main thread, unit", Use(2.0, 300)),
        (1, "7"): ("dds UDP listener (discovery)", Use(0.5, 10)),
        (1, "8"): ("other threads", Use(9.0, 9)),  # ended before the second snapshot
    }
    after = {
        (1, "1"): ("main thread, unit", Use(1.5, 600)),
        (2, "2"): ("main thread, unit", Use(2.5, 800)),
        (1, "7"): ("dds UDP listener (discovery)", Use(0.6, 30)),
        (2, "9"): ("other threads", Use(4.0, 40)),  # started after the first one
    }
    groups = threads.by_group(before, after, elapsed_s=10.0)
    assert set(groups) == {"main thread, unit", "dds UDP listener (discovery)"}
    assert groups["main thread, unit"] == pytest.approx((0.1, 100.0))
    assert groups["dds UDP listener (discovery)"] == pytest.approx((0.01, 2.0))


def test_windows_average_by_group_a_missing_group_counting_zero() -> None:
    mean = threads.mean_by_group(
        [
            {"main thread, unit": (0.2, 600.0), "dds event thread": (0.01, 20.0)},
            {"main thread, unit": (0.4, 620.0)},
        ]
    )
    assert mean["main thread, unit"] == pytest.approx((0.3, 610.0))
    assert mean["dds event thread"] == pytest.approx((0.005, 10.0))


def test_the_table_gives_cpu_per_wake_up_and_a_dash_without_any() -> None:
    rows = threads.table(
        {
            "skeleton": {"main thread, unit": (0.15, 600.0)},
            "graph": {"main thread, unit": (0.26, 650.0), "dds asynchronous writer": (0.0, 0.0)},
        }
    )
    assert rows[0].startswith("| threads | skeleton: cores")
    assert rows[2] == "| main thread, unit | 0.150, 600, 250 | 0.260, 650, 400 |"
    assert rows[3] == "| dds asynchronous writer | 0.000, 0, - | 0.000, 0, - |"


def test_a_snapshot_reads_this_process_threads() -> None:
    stop = threading.Event()
    worker = threading.Thread(target=stop.wait, name="worker")
    worker.start()
    try:
        taken = threads.snapshot({os.getpid(): "test"})
    finally:
        stop.set()
        worker.join()
    groups = [group for (pid, _), (group, _) in taken.items() if pid == os.getpid()]
    assert groups.count("main thread, test") == 1
    assert "other threads" in groups
    main = taken[(os.getpid(), str(os.getpid()))][1]
    assert main.cpu_s > 0.0 and main.switches >= 1
