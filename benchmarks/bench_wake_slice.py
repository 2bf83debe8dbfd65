"""How long a woken thread waits behind a busy loop on its core, with the kernel's default
slice and with the short slice the composed graph asks for (hems_ros/ros/short_slice.py).

A pure-Python busy loop and a sleeper share one core (both pinned to the first CPU). The
sleeper sleeps ``--period-ms``, then works 0.5 ms, ``--wakes`` times; its wake-up delay is
the time past the sleep's end at which it runs again. The two slices alternate, one
sleeper process each, each a fresh process so that nothing is inherited between them.
Prints p50, p99 and max of the delay per slice, and the ratio of the p99s. On a kernel
without per-thread slices (before Linux 6.12) both rows read alike.

Usage: .venv/bin/python benchmarks/bench_wake_slice.py [--wakes 1000] [--repeat 2] [--smoke]
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
import time

import smoke
from host import host_line

from hems_ros.ros.short_slice import SLICE_S, current_slice_s, request_short_slice
from hems_ros.rosenv import die_with_parent

WORK_S = 0.5e-3


def sleeper(wakes: int, period_s: float, short: bool) -> dict:
    """Run in the child: the delays of ``wakes`` wake-ups, in ms, and the slice it ran with."""
    os.sched_setaffinity(0, {min(os.sched_getaffinity(0))})
    if short:
        request_short_slice()
    delays = []
    for _ in range(wakes):
        start = time.perf_counter()
        time.sleep(period_s)
        woke = time.perf_counter()
        delays.append((woke - start - period_s) * 1e3)
        while time.perf_counter() - woke < WORK_S:
            pass
    return {"delays_ms": delays, "slice_s": current_slice_s()}


def measure(wakes: int, period_s: float, short: bool) -> dict:
    done = subprocess.run(
        [sys.executable, __file__, "--child", json.dumps([wakes, period_s, short])],
        capture_output=True,
        text=True,
        check=True,
    )
    return json.loads(done.stdout)


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--wakes", type=int, default=1000, help="wake-ups per sleeper")
    parser.add_argument("--period-ms", type=float, default=5.0, help="each sleep, ms")
    parser.add_argument("--repeat", type=int, default=2, help="sleepers per slice, alternating")
    parser.add_argument("--child", help=argparse.SUPPRESS)
    if "--child" in sys.argv:
        wakes, period_s, short = json.loads(parser.parse_args().child)
        print(json.dumps(sleeper(wakes, period_s, short)))
        return 0
    args = smoke.parse_args(parser, wakes=50, repeat=1)
    print(host_line())
    cpu = min(os.sched_getaffinity(0))
    loop = subprocess.Popen(
        ["taskset", "-c", str(cpu), sys.executable, "-c", "while True: pass"],
        preexec_fn=die_with_parent,
    )
    delays: dict[bool, list[float]] = {False: [], True: []}
    slices: dict[bool, float | None] = {}
    try:
        time.sleep(0.5)
        for _ in range(args.repeat):
            for short in (False, True):
                result = measure(args.wakes, args.period_ms * 1e-3, short)
                delays[short] += result["delays_ms"]
                slices[short] = result["slice_s"]
    finally:
        loop.kill()
        loop.wait()
    print(f"busy loop and sleeper on CPU {cpu}: {args.wakes} wake-ups x {args.repeat} per slice")
    print("| slice | p50 ms | p99 ms | max ms |")
    print("|---|---|---|---|")
    p99 = {}
    for short, values in delays.items():
        values.sort()
        p99[short] = values[int(0.99 * (len(values) - 1))]
        kept = slices[short]
        name = "unknown" if kept is None else f"{kept * 1e3:.2f} ms"
        asked = f" (asked {SLICE_S * 1e3:.2f} ms)" if short else " (the kernel's default)"
        print(
            f"| {name}{asked} | {statistics.median(values):.3f} | {p99[short]:.3f} "
            f"| {values[-1]:.3f} |"
        )
    print(f"p99 default over short: {p99[False] / max(p99[True], 1e-6):.1f}x")
    return 0


if __name__ == "__main__":
    sys.exit(main())
