"""``hems demo``: the main end-to-end job (`make demo`).

Brings the 16-node graph up as separate processes, enables it, runs the scripted grasp on
all six fingers (position approach, force hold, release), prints the per-finger summary,
writes a PNG plot and shuts everything down. The run is recorded into a bag
(``bags/demo_<date>_<time>/`` unless ``--record DIR``) whose path and message counts are
printed at the end.
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

from hems_ros.cli import grasp
from hems_ros.cli.commands import gap_line
from hems_ros.cli.numbers import positive
from hems_ros.cli.up import (
    add_graph_arguments,
    bag_folder,
    graph_options,
    layout_text,
    stop_recorder,
)
from hems_ros.client.recording import wait_until_recording
from hems_ros.launcher import Graph


def register(subparsers) -> None:
    parser = subparsers.add_parser(
        "demo",
        help="run the end-to-end demonstration (what `make demo` runs)",
        description="Start the HEMS graph (16 nodes, one process each), enable it, run a scripted "
        "grasp on all six fingers (position approach, force hold, release), print a per-finger "
        "summary (tracking error, peak force, energy), write a PNG plot, shut down.",
    )
    add_graph_arguments(parser)
    grasp.add_grasp_arguments(parser)
    parser.set_defaults(func=run, plot=Path("results/demo_grasp.png"))
    parser.add_argument(
        "--ready-timeout",
        type=positive,
        default=60.0,
        help="seconds to wait for every node to come up (default 60)",
    )
    parser.add_argument(
        "--record",
        type=Path,
        default=True,
        metavar="DIR",
        help="bag folder the run is recorded into (default bags/demo_<date>_<time>)",
    )


def run(args: argparse.Namespace) -> int:
    try:
        options = graph_options(args)
        plan = grasp.plan_from(args)
        record = bag_folder(args.record, "demo")
    except ValueError as error:
        print(f"demo: {error}", file=sys.stderr)
        return 2
    from hems_ros.bag.recording import RecorderProcess
    from hems_ros.bag.selection import record_regex
    from hems_ros.client.graph_client import GraphClient

    graph = Graph(options)
    graph.start()
    recorder = RecorderProcess(record, regex=record_regex(options.namespace))
    print(
        f"demo: started the graph ({layout_text(options)}), recording into {record}; waiting for "
        f"every stream",
        flush=True,
    )
    try:
        with GraphClient(
            "hems_demo", sim_time=options.sim_time, namespace=options.namespace
        ) as client:
            try:
                wait_until_recording(
                    client, recorder, options.fingers, time.monotonic() + args.ready_timeout
                )
            except (TimeoutError, RuntimeError) as error:
                print(f"demo: {error}", file=sys.stderr)
                return 1
            try:
                traces, phase_starts, statuses = grasp.enabled_grasp(
                    client, plan, options.fingers, args.ready_timeout, "demo"
                )
            except grasp.EnableRefused as error:
                print(
                    f"demo: could not enable the graph: {graph.with_exits(str(error))}",
                    file=sys.stderr,
                )
                return 1
            except RuntimeError as error:
                print(f"demo: {graph.with_exits(str(error))}", file=sys.stderr)
                return 1
            print(f"demo: {gap_line(client.snapshot(fingers=(), seconds=0.2))}", flush=True)
        rows = grasp.report(traces, plan, phase_starts, args.plot)
        problem = grasp.fault_report(statuses) or grasp.tracking_report(rows, plan, options.fingers)
        if problem:
            print(f"demo: not a valid run: {problem}", file=sys.stderr)
            return 1
        crashed = graph.exited()
        if crashed:
            print(f"demo: nodes exited during the run: {crashed}", file=sys.stderr)
            return 1
        return 0
    finally:
        stop_recorder("demo", recorder)
        started = time.monotonic()
        graph.stop()
        print(f"demo: graph stopped in {time.monotonic() - started:.2f} s")
