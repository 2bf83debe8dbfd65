"""``hems up``: start the HEMS graph and keep it running until Ctrl-C or SIGTERM."""

from __future__ import annotations

import argparse
import signal
import sys
import time
from pathlib import Path

from hems_ros.graph import names
from hems_ros.launcher import Graph, GraphOptions, default_params_file


def add_graph_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("--composed", action="store_true",
                        help="run all nodes in one process (multi-threaded executor) instead of one process each")
    parser.add_argument("--sim-time", action="store_true",
                        help="run every node on simulated time from a /clock publisher")
    parser.add_argument("--rate", type=float, default=1.0,
                        help="with --sim-time: simulated seconds per wall second (default 1)")
    parser.add_argument("--params-file", type=Path, default=default_params_file(),
                        help="ROS params file for every node (default config/hems.yaml)")
    parser.add_argument("--fingers", default="all",
                        help="comma-separated fingers to bring up (default all six: " + ",".join(names.FINGERS) + ")")
    parser.add_argument("--log-level", default="info", choices=("debug", "info", "warn", "error"),
                        help="ROS log level of the nodes")


def graph_options(args: argparse.Namespace) -> GraphOptions:
    fingers = names.FINGERS if args.fingers == "all" else tuple(
        names.check_finger(f.strip()) for f in args.fingers.split(","))
    if not args.rate > 0:
        raise ValueError(f"--rate {args.rate}: must be > 0")
    if not args.params_file.is_file():
        raise ValueError(f"--params-file {args.params_file}: no such file")
    return GraphOptions(params_file=args.params_file, composed=args.composed, sim_time=args.sim_time,
                        rate=args.rate, fingers=fingers, log_level=args.log_level)


def register(subparsers) -> None:
    parser = subparsers.add_parser(
        "up", help="start the 16 nodes of the graph (Ctrl-C stops them all)",
        description="Start six actuation units, three shoulder modules, six finger controllers and the "
                    "supervisor, each in its own process (or composed in one). Ctrl-C or SIGTERM stops every "
                    "node within 3 s. Then: hems enable; hems setpoint index 20 --unit mm; hems status.")
    add_graph_arguments(parser)
    parser.add_argument("--duration", type=float, default=None, help="stop by itself after this many seconds")
    parser.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    try:
        options = graph_options(args)
    except ValueError as error:
        print(f"hems up: {error}", file=sys.stderr)
        return 2
    stop = {"requested": False}

    def request_stop(signum, frame) -> None:
        stop["requested"] = True

    signal.signal(signal.SIGINT, request_stop)
    signal.signal(signal.SIGTERM, request_stop)
    graph = Graph(options)
    graph.start()
    print(f"hems up: {len(graph.processes)} processes "
          f"({'composed' if options.composed else 'one per node'}"
          f"{f', sim time x{options.rate:g}' if options.sim_time else ''}); Ctrl-C to stop", flush=True)
    started = time.monotonic()
    reported: set[str] = set()
    try:
        while not stop["requested"]:
            if args.duration is not None and time.monotonic() - started >= args.duration:
                break
            for name, code in graph.exited().items():
                if name not in reported:
                    reported.add(name)
                    print(f"hems up: {name} exited with code {code}", file=sys.stderr, flush=True)
            if len(reported) == len(graph.processes):
                break
            time.sleep(0.05)
    finally:
        t0 = time.monotonic()
        codes = graph.stop()
        print(f"hems up: stopped {len(codes)} processes in {time.monotonic() - t0:.2f} s"
              + (f" (killed after the grace period: {', '.join(graph.killed)})" if graph.killed else ""), flush=True)
    return 0
