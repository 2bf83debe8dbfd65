"""Speed of the full `hems experiment ch5` (under 20 s; real-time factor printed).

Times the 15 lockstep runs (3 controllers x (three 20 s sines + two 70 s step tests) = 600 s,
10 simulated minutes) in process, and the whole command (runs, findings, tables, PNGs) as a user
runs it (its interpreter start included).

Run: python benchmarks/bench_experiments.py [--smoke]    (--smoke: the same runs, no floor)
"""

from __future__ import annotations

import argparse
import subprocess
import sys
import tempfile
import time

import smoke

from hems_ros.experiments import chapters
from hems_ros.rosenv import child_environment

FLOOR_S = 20.0


def main() -> int:
    args = smoke.parse_args(argparse.ArgumentParser(description=__doc__.splitlines()[0]))
    chapters.run_ch5()  # compile the numba hold loop outside the timing
    start = time.perf_counter()
    runs = chapters.run_ch5()
    sim_wall = time.perf_counter() - start
    simulated = sum(run.time.size * 0.01 for run in runs.values())
    with tempfile.TemporaryDirectory() as tmp:
        start = time.perf_counter()
        subprocess.run(
            [sys.executable, "-m", "hems_ros.cli.main", "experiment", "ch5", "--output", tmp],
            check=True,
            capture_output=True,
            env=child_environment(),
        )
        total = time.perf_counter() - start
    print()
    print(f"simulated time, 15 runs        : {simulated:.0f} s ({simulated / 60:.1f} min)")
    print(
        f"lockstep runs only             : {sim_wall:.2f} s wall, real-time factor "
        f"{simulated / sim_wall:.0f}x"
    )
    print(
        f"full `hems experiment ch5`     : {total:.2f} s wall, real-time factor "
        f"{simulated / total:.0f}x (floor {FLOOR_S:.0f} s: "
        f"{'met' if total < FLOOR_S else 'MISSED'})"
    )
    return 0 if args.smoke or total < FLOOR_S else 1


if __name__ == "__main__":
    sys.exit(main())
