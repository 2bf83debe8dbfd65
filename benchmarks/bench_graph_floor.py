"""What the separate layout's messaging costs before any node works, beside the real graph.

The skeleton is sixteen processes built as the graph's nodes are (a LeanNode in
``run_node``, spun by lean_spin, middleware threads deferred, the project's Fast DDS profile)
that send the graph's messages (its types, QoS, rates and phases on the clock's grid, each
a pre-encoded default message) and do nothing else:

- a unit ticks on its pair's grid, takes its duty commands and the supervisor's statuses
  there, sends an encoder reading and a wire tension, and its state every fifth tick;
- a shoulder module wakes on its units' tensions and sends a force reading for each;
- a controller wakes on its encoder readings, takes the force readings and statuses there,
  sends a duty command, and its status every second step;
- the supervisor takes the controllers' statuses and units' states every 20 ms, 1.2 ms after
  the thumb pair's tick, and sends its status.

The skeleton and the real separate graph (six fingers enabled, holding 10 mm) run one after
the other in alternating windows (``--rounds`` pairs), so each pair sees the same host; each
pair's ratio says how much of the graph's CPU the messaging and wake-ups alone take. The
skeleton's CPU is the floor under any node code in this layout on this host, in this phase.
A last table splits both by thread (benchmarks/threads.py): the nodes' main threads, which
run Python at each wake-up, against Fast DDS's, whose shared-memory listeners wake once per
message received.

Usage: .venv/bin/python benchmarks/bench_graph_floor.py [--seconds 20] [--rounds 2] [--busy]
       [--smoke]
"""

from __future__ import annotations

import argparse
import statistics
import subprocess
import sys
import time
from pathlib import Path

import busy as busy_option
import smoke
import yaml
from bench_graph import FLOORS, cores, cpu_by_process, hold, node_kind  # reserves the domain
from host import host_line
from threads import by_group, mean_by_group, snapshot, table

from hems_ros.client.graph_client import GraphClient
from hems_ros.graph import names
from hems_ros.launcher import Graph, GraphOptions, default_params_file
from hems_ros.rosenv import child_environment

SKELETON_NODE = Path(__file__).with_name("skeleton_node.py")
SETTLE_S = 5.0
ROLES = ("unit", "module", "controller", "supervisor")  # skeleton_node.BUILDERS


def skeleton_processes() -> list[tuple[str, str]]:
    return (
        [("unit", f) for f in names.FINGERS]
        + [("module", m) for m in names.MODULES]
        + [("controller", f) for f in names.FINGERS]
        + [("supervisor", "supervisor")]
    )


def graph_rates() -> list[str]:
    """The skeleton's rates as the graph runs them (config/hems.yaml's shared section), for
    skeleton_node's command line."""
    shared = yaml.safe_load(default_params_file().read_text())["/**"]["ros__parameters"]
    tick_s = shared["tick_period_s"]
    return [
        str(tick_s),
        str(shared["check_period_s"]),
        str(round(shared["state_period_s"] / tick_s)),
        str(shared["status_every"]),
    ]


Window = tuple[dict[str, list[float]], dict[str, tuple[float, float]]]


def skeleton_window(seconds: float) -> Window:
    """Start the skeleton, let it settle, measure: cores of each process by role, and the
    threads' use by group (threads.by_group)."""
    environment, rates = child_environment(), graph_rates()
    processes = [
        (
            role,
            subprocess.Popen(
                [sys.executable, str(SKELETON_NODE), role, name, *rates],
                env=environment,
                stdout=subprocess.PIPE,
                text=True,
            ),
        )
        for role, name in skeleton_processes()
    ]
    try:
        for role, process in processes:
            assert process.stdout is not None
            if process.stdout.readline().strip() != "ready":
                sys.exit(f"bench_graph_floor: a skeleton {role} ended at start-up")
        time.sleep(SETTLE_S)
        pids = [process.pid for _, process in processes]
        roles = {process.pid: role for role, process in processes}
        before, threads, t0 = cpu_by_process(pids), snapshot(roles), time.monotonic()
        time.sleep(seconds)
        used = cores(before, cpu_by_process(pids), time.monotonic() - t0)
        groups = by_group(threads, snapshot(roles), time.monotonic() - t0)
        ended = [role for role, process in processes if process.poll() is not None]
        if ended:
            sys.exit(f"bench_graph_floor: skeleton processes ended while measured: {ended}")
    finally:
        for _, process in processes:
            process.terminate()
        for _, process in processes:
            process.wait(timeout=30)
    by_role: dict[str, list[float]] = {}
    for role, process in processes:
        by_role.setdefault(role, []).append(used.get(process.pid, 0.0))
    return by_role, groups


GRAPH_KINDS = {  # the graph's executables under the skeleton's role names
    "actuation_unit": "unit",
    "shoulder_module": "module",
    "finger_controller": "controller",
    "supervisor": "supervisor",
}


def graph_window(seconds: float) -> Window:
    """The real separate graph, enabled and holding 10 mm: cores of each process by role,
    and the threads' use by group."""
    graph = Graph(GraphOptions(composed=False, log_level="error"))
    graph.start()
    try:
        with GraphClient("hems_bench_floor") as client:
            ok, message = hold(client, graph)
            if not ok:
                sys.exit(f"bench_graph_floor: {message}")
            client.spin_for(SETTLE_S)
            pids = graph.pids
            kinds = {pid: GRAPH_KINDS.get(node_kind(pid), "other") for pid in pids}
            before, threads, t0 = cpu_by_process(pids), snapshot(kinds), time.monotonic()
            client.spin_for(seconds)
            used = cores(before, cpu_by_process(pids), time.monotonic() - t0)
            groups = by_group(threads, snapshot(kinds), time.monotonic() - t0)
            state = client.snapshot(seconds=0.5).supervisor
            if state is None or state.state_name != "ENABLED":
                sys.exit(f"bench_graph_floor: the graph left ENABLED: {state}")
    finally:
        graph.stop()
    by_role: dict[str, list[float]] = {}
    for pid, cpu in used.items():
        by_role.setdefault(kinds[pid], []).append(cpu)
    return by_role, groups


def total(by_role: dict[str, list[float]]) -> float:
    return sum(sum(values) for values in by_role.values())


def per_process(by_role: dict[str, list[float]]) -> str:
    return ", ".join(
        f"{role} {statistics.mean(by_role[role]):.3f}" for role in ROLES if role in by_role
    )


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument(
        "--seconds", type=float, default=20.0, help="measured time per window, s (default 20)"
    )
    parser.add_argument(
        "--rounds", type=int, default=2, help="skeleton and graph window pairs (default 2)"
    )
    busy_option.add_option(parser)
    args = smoke.parse_args(parser, seconds=2.0, rounds=1)
    busy = busy_option.start(args)
    try:
        measure(args)
    finally:
        if busy is not None:
            busy.kill()


def measure(args: argparse.Namespace) -> None:
    floor = FLOORS["separate"][0]
    print(
        f"separate layout's messaging floor: {args.rounds} x (skeleton, graph) windows of "
        f"{args.seconds:g} s{', a busy loop on one core' if args.busy else ''}; {host_line()}",
        flush=True,
    )
    print(
        "| round | skeleton cores | graph cores | skeleton / graph | skeleton / floor | "
        "cores per process, skeleton | graph |"
    )
    print("|---|---|---|---|---|---|---|")
    ratios = []
    thread_use: dict[str, list[dict[str, tuple[float, float]]]] = {"skeleton": [], "graph": []}
    for round_ in range(1, args.rounds + 1):
        (skeleton, skeleton_threads), (graph, graph_threads) = (
            skeleton_window(args.seconds),
            graph_window(args.seconds),
        )
        thread_use["skeleton"].append(skeleton_threads)
        thread_use["graph"].append(graph_threads)
        ratios.append(total(skeleton) / total(graph))
        print(
            f"| {round_} | {total(skeleton):.3f} | {total(graph):.3f} | {ratios[-1]:.2f} | "
            f"{total(skeleton) / floor:.2f} | {per_process(skeleton)} | {per_process(graph)} |",
            flush=True,
        )
    print("\nper thread, the rounds' mean (a context switch is about one wake-up):")
    print("\n".join(table({k: mean_by_group(v) for k, v in thread_use.items()})))
    print(
        f"the skeleton takes {min(ratios):.2f}-{max(ratios):.2f} of the graph's CPU; "
        f"separate CPU floor {floor} cores; after the runs: {host_line()}"
    )


if __name__ == "__main__":
    main()
