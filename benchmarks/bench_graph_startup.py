"""How often a freshly started graph, enabled as soon as the supervisor accepts, leaves
ENABLED in its first seconds of heating.

`make demo` and `hems step` start the graph and a recorder, enable as soon as the supervisor
accepts, and send their first setpoints at once: the processes are then still settling
(discovery among 18 participants, first calls). This repeats that ``--starts`` times per
mode: start, record, enable when ready (asking every 0.5 s), move every finger to 20 mm,
watch ``--heat-s`` seconds, stop; and counts the starts after which the supervisor was not
ENABLED, with the first fault of each. Modes as in bench_graph.py.

Usage: .venv/bin/python benchmarks/bench_graph_startup.py [--starts 10] [--modes separate,composed]
       [--heat-s 2] [--smoke]    (one composed start)
"""

from __future__ import annotations

import argparse
import collections
import shutil
import tempfile
from pathlib import Path

import smoke
from bench_graph_joins import fault_kind  # reserves this run's ROS domain

from hems_ros.client.recorded_run import recorded_graph
from hems_ros.graph import names
from hems_ros.launcher import GraphOptions

READY_TIMEOUT_S = 90.0


def start_once(composed: bool, heat_s: float, bag: Path) -> str | None:
    """One start; the supervisor's first fault (or state) if it was not ENABLED at the end,
    None if it was. RuntimeError when the graph did not come up."""
    options = GraphOptions(composed=composed, log_level="error")
    with recorded_graph(options, bag, "hems_bench_startup", READY_TIMEOUT_S) as graph_run:
        client = graph_run.client
        ok, message = client.enable_when_ready(READY_TIMEOUT_S, retry_s=0.5)
        if not ok:
            raise RuntimeError(f"could not enable: {graph_run.graph.with_exits(message)}")
        for finger in names.FINGERS:
            client.send_setpoint(finger, "position", 0.02)
        client.spin_for(heat_s)
        status = client.snapshot(seconds=0.2).supervisor
        client.call("disable")
    if status is None:
        return "no supervisor status"
    return (
        None
        if status.state_name == "ENABLED"
        else (status.faults[0] if status.faults else status.state_name)
    )


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--starts", type=int, default=10, help="graph starts per mode (default 10)")
    parser.add_argument(
        "--modes",
        default="separate,composed",
        help="comma-separated modes to run: separate, composed (default both)",
    )
    parser.add_argument(
        "--heat-s",
        type=float,
        default=2.0,
        help="seconds of heating watched after the enable (default 2)",
    )
    args = smoke.parse_args(parser, starts=1, modes="composed")
    results: dict[str, tuple[int, collections.Counter]] = {}
    scratch = Path(tempfile.mkdtemp(prefix="hems_bench_startup_"))
    try:
        for mode in args.modes.split(","):
            faults: collections.Counter[str] = collections.Counter()
            for i in range(args.starts):
                fault = start_once(mode == "composed", args.heat_s, scratch / f"{mode}_{i}")
                shutil.rmtree(scratch / f"{mode}_{i}", ignore_errors=True)
                print(f"  {mode} start {i + 1}/{args.starts}: {fault or 'ENABLED'}", flush=True)
                if fault:
                    faults[fault_kind(fault)] += 1
            results[mode] = (args.starts, faults)
    finally:
        shutil.rmtree(scratch, ignore_errors=True)
    print("mode        starts  supervisor left ENABLED  first faults")
    for mode, (starts, faults) in results.items():
        left = sum(faults.values())
        kinds = ", ".join(f"{k} x{n}" for k, n in sorted(faults.items())) or "-"
        print(
            f"{mode:10s}  {starts:6d}  {left:4d} ({100 * left / starts:3.0f} %)            {kinds}"
        )


if __name__ == "__main__":
    main()
