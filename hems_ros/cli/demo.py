"""``hems demo``: the main end-to-end job (`make demo`).

Brings the 16-node graph up (composed in one process; a process per node with
``--separate``), enables it, runs the scripted grasp on
all six fingers (position approach, force hold, release), prints the per-finger summary,
writes a PNG plot and shuts everything down. The run is recorded into a bag
(``bags/demo_<date>_<time>/`` unless ``--record DIR``) whose path and message counts are
printed at the end; ``--summary FILE`` also writes the verdict and the supervisor's
stream-gap figures as JSON for scripts.
"""

from __future__ import annotations

import argparse
import json
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
from hems_ros.graph.supervisor_logic import gap_report


def register(subparsers) -> None:
    parser = subparsers.add_parser(
        "demo",
        help="run the end-to-end demonstration (what `make demo` runs)",
        description="Start the HEMS graph (16 nodes, composed in one process unless --separate), "
        "enable it, run a scripted "
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
    parser.add_argument(
        "--summary",
        type=Path,
        metavar="FILE",
        help="also write the run's verdict as JSON to FILE: valid (as the exit code), problem "
        "(why not, else null), stream_gaps (the supervisor's gap figures in ms, as `hems status "
        "--json` gives them; null if the grasp never ran)",
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
    summary: dict = {"valid": False, "problem": None, "stream_gaps": None}
    try:
        with recorded_graph(options, record, "hems_demo", args.ready_timeout) as graph_run:
            summary["problem"], summary["stream_gaps"] = _grasp(
                graph_run, plan, options.fingers, args
            )
            if not stop_recorder("demo", graph_run.recorder):
                summary["problem"] = summary["problem"] or "the recording failed"
            summary["valid"] = summary["problem"] is None
    except (TimeoutError, RuntimeError) as error:
        print(f"demo: {error}", file=sys.stderr)
        summary.update(valid=False, problem=str(error))
    finally:
        if graph_run is not None:
            print(f"demo: graph stopped in {graph_run.stop_s:.2f} s")
        if args.summary is not None:
            args.summary.write_text(json.dumps(summary, indent=2) + "\n")
    return 0 if summary["valid"] else 1


def _grasp(graph_run, plan, fingers, args: argparse.Namespace) -> tuple[str | None, dict | None]:
    """The enabled grasp on the running graph: (None if it was a valid run, else why not; the
    supervisor's stream-gap figures, None if the grasp did not run or none came)."""
    graph, client = graph_run.graph, graph_run.client
    try:
        traces, phase_starts, statuses = grasp.enabled_grasp(
            client, plan, fingers, args.ready_timeout, "demo"
        )
    except grasp.EnableRefused as error:
        problem = f"could not enable the graph: {graph.with_exits(str(error))}"
        print(f"demo: {problem}", file=sys.stderr)
        return problem, None
    except RuntimeError as error:
        problem = graph.with_exits(str(error))
        print(f"demo: {problem}", file=sys.stderr)
        return problem, None
    snap = client.snapshot(fingers=(), seconds=0.2)
    gaps = gap_report(snap.diagnostics) if snap.diagnostics else None
    print(f"demo: {gap_line(snap)}", flush=True)
    rows = grasp.report(traces, plan, phase_starts, args.plot)
    verdict = grasp.fault_report(statuses) or grasp.tracking_report(rows, plan, fingers)
    if verdict:
        print(f"demo: not a valid run: {verdict}", file=sys.stderr)
        return verdict, gaps
    crashed = graph.exited()
    if crashed:
        problem = f"nodes exited during the run: {crashed}"
        print(f"demo: {problem}", file=sys.stderr)
        return problem, gaps
    return None, gaps
