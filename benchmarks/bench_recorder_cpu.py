"""Recorder CPU on the live graph: share of one core while recording every graph topic.

Starts the graph (index finger only, then all six fingers unless --fingers says otherwise),
the recorder node in its own process with its default topic set, and after a warm-up reads
the recorder's CPU time (utime + stime from /proc) over --seconds of recording. The graph
need not be enabled: every stream runs at its full rate from start-up (duty 0 while not
enabled). Floor: at most 20 % of one core at the full graph rate.
Run: python benchmarks/bench_recorder_cpu.py [--seconds S] [--fingers index all] [--smoke]
(--smoke: 2 s of the index finger's graph, no ceiling)
"""

from __future__ import annotations

import argparse
import os
import tempfile
import time
from pathlib import Path

import smoke

from hems_ros.bag import bag_info
from hems_ros.bag.recording import RecorderProcess
from hems_ros.graph import names
from hems_ros.launcher import Graph, GraphOptions
from hems_ros.rosenv import apply_network_defaults

CEILING = 0.20
TICKS = os.sysconf("SC_CLK_TCK")


def cpu_seconds(pid: int) -> float:
    fields = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()
    return (int(fields[11]) + int(fields[12])) / TICKS  # utime, stime


def measure(fingers: tuple[str, ...], seconds: float, warmup: float) -> dict[str, float]:
    graph = Graph(GraphOptions(fingers=fingers, composed=False, log_level="warn"))
    graph.start()
    try:
        with tempfile.TemporaryDirectory() as tmp:
            recorder = RecorderProcess(Path(tmp) / "bench")
            try:
                recorder.wait_for_topics(
                    [names.topic(f, "encoder") for f in fingers]
                    + [names.topic(f, "duty") for f in fingers],
                    timeout=90,
                )
                time.sleep(
                    warmup
                )  # imports and discovery of the last endpoints are not steady state
                before = bag_info_count(recorder)
                cpu0, wall0 = cpu_seconds(recorder.process.pid), time.monotonic()
                time.sleep(seconds)
                cpu1, wall1 = cpu_seconds(recorder.process.pid), time.monotonic()
                after = bag_info_count(recorder)
            finally:
                info = recorder.stop()
    finally:
        graph.stop()
    return {
        "share": (cpu1 - cpu0) / (wall1 - wall0),
        "rate": (after - before) / (wall1 - wall0),
        "messages": info.message_count,
        "topics": sum(1 for t in info.topics.values() if t.count),
    }


def bag_info_count(recorder: RecorderProcess) -> int:
    """Messages in the recorder's finished chunks so far (the bag is read while being written)."""
    return bag_info(recorder.output).message_count


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument(
        "--seconds", type=float, default=20.0, help="measured recording time per graph"
    )
    parser.add_argument(
        "--warmup", type=float, default=5.0, help="seconds of recording before measuring"
    )
    parser.add_argument(
        "--fingers", nargs="+", default=["index", "all"], help="graphs to measure: a finger or all"
    )
    args = smoke.parse_args(parser, seconds=2.0, warmup=1.0, fingers=["index"])
    apply_network_defaults()
    ok = True
    print(
        f"recorder CPU benchmark: {args.seconds:g} s of recording per graph, ceiling "
        f"{CEILING:.0%} of one core"
    )
    for choice in args.fingers:
        fingers = names.FINGERS if choice == "all" else (names.check_finger(choice),)
        result = measure(fingers, args.seconds, args.warmup)
        ok &= result["share"] <= CEILING
        processes = len(Graph(GraphOptions(fingers=fingers, composed=False)).commands())
        print(
            f"  {len(fingers)} finger{'s' if len(fingers) > 1 else ' '} "
            f"({processes:>2} processes): "
            f"{result['rate']:>6,.0f} msg/s on {result['topics']} topics   recorder "
            f"{result['share']:6.1%} of one core   ceiling {CEILING:.0%}   ratio "
            f"{result['share'] / CEILING:.2f}"
        )
    return 0 if ok or args.smoke else 1


if __name__ == "__main__":
    raise SystemExit(main())
