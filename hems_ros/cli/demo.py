"""``hems demo``: the main end-to-end job (`make demo`).

Brings the 16-node graph up (composed in one process; a process per node with
``--separate``), enables it, runs the scripted grasp on
all six fingers (position approach, force hold, release), prints the per-finger summary,
writes a PNG plot and shuts everything down. The run is recorded into a bag
(``bags/demo_<date>_<time>/`` unless ``--record DIR``) whose path and message counts are
printed at the end.
"""

from __future__ import annotations

import argparse
import sys
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
    from hems_ros.client.recorded_run import recorded_graph

    print(
        f"demo: starting the graph ({layout_text(options)}), recording into {record}; waiting "
        f"for every stream",
        flush=True,
    )
    graph_run = None
    try:
        with recorded_graph(options, record, "hems_demo", args.ready_timeout) as graph_run:
            code = _grasp(graph_run, plan, options.fingers, args)
            recorded = stop_recorder("demo", graph_run.recorder)
    except (TimeoutError, RuntimeError) as error:
        print(f"demo: {error}", file=sys.stderr)
        return 1
    finally:
        if graph_run is not None:
            print(f"demo: graph stopped in {graph_run.stop_s:.2f} s")
    return code if recorded else 1


def _grasp(graph_run, plan, fingers, args: argparse.Namespace) -> int:
    """The enabled grasp on the running graph: 0 if it was a valid run."""
    graph, client = graph_run.graph, graph_run.client
    try:
        traces, phase_starts, statuses = grasp.enabled_grasp(
            client, plan, fingers, args.ready_timeout, "demo"
        )
    except grasp.EnableRefused as error:
        print(f"demo: could not enable the graph: {graph.with_exits(str(error))}", file=sys.stderr)
        return 1
    except RuntimeError as error:
        print(f"demo: {graph.with_exits(str(error))}", file=sys.stderr)
        return 1
    print(f"demo: {gap_line(client.snapshot(fingers=(), seconds=0.2))}", flush=True)
    rows = grasp.report(traces, plan, phase_starts, args.plot)
    problem = grasp.fault_report(statuses) or grasp.tracking_report(rows, plan, fingers)
    if problem:
        print(f"demo: not a valid run: {problem}", file=sys.stderr)
        return 1
    crashed = graph.exited()
    if crashed:
        print(f"demo: nodes exited during the run: {crashed}", file=sys.stderr)
        return 1
    return 0
