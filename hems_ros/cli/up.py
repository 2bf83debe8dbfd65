"""``hems up``: start the HEMS graph and keep it running until Ctrl-C or SIGTERM."""

from __future__ import annotations

import argparse
import signal
import subprocess
import sys
import time
from datetime import datetime
from pathlib import Path

from hems_ros.cli.numbers import add_namespace_argument, positive, positive_or_max
from hems_ros.graph import names
from hems_ros.launcher import Graph, GraphOptions, default_params_file, node_specs
from hems_ros.processes import exit_description, stop_process
from hems_ros.rosenv import child_environment, die_with_parent


def rate_text(rate: float) -> str:
    return "max" if rate == 0 else f"{rate:g}"


def add_graph_arguments(parser: argparse.ArgumentParser) -> None:
    layout = parser.add_mutually_exclusive_group()
    layout.add_argument(
        "--separate",
        dest="composed",
        action="store_false",
        help="run each node in a process of its own, as `ros2 run` starts them (0.6-0.9 "
        "cores and 1.1 GB on a two-core host, against 0.2-0.4 cores and 100 MB composed)",
    )
    layout.add_argument(
        "--composed",
        dest="composed",
        action="store_true",
        help="run all nodes in one process, one thread, one wait set (the default)",
    )
    parser.add_argument(
        "--sim-time",
        action="store_true",
        help="run every node on simulated time from a /clock publisher",
    )
    parser.add_argument(
        "--rate",
        type=positive_or_max,
        default=1.0,
        help="with --sim-time: the most simulated seconds per wall second (default 1), or max "
        "(as fast as the graph answers); the clock waits for every node each step, so a "
        "run's figures do not depend on the rate",
    )
    parser.add_argument(
        "--params-file",
        type=Path,
        default=default_params_file(),
        help="ROS params file for every node (default config/hems.yaml)",
    )
    parser.add_argument(
        "--extra-params",
        type=Path,
        action="append",
        metavar="FILE",
        help="ROS params file applied over --params-file (repeatable; later files win), e.g. "
        "the gains `hems tune --write-params FILE` writes",
    )
    parser.add_argument(
        "--fingers",
        default="all",
        help="comma-separated fingers to bring up (default all six: "
        + ",".join(names.FINGERS)
        + ")",
    )
    parser.add_argument(
        "--log-level",
        default="info",
        choices=("debug", "info", "warn", "error"),
        help="ROS log level of the nodes",
    )
    add_namespace_argument(parser)
    parser.add_argument(
        "--no-parameter-services",
        dest="parameter_services",
        action="store_false",
        help="start the separate processes without their ROS parameter services (ros2 param "
        "then does not reach them): a process joining the domain (hems setpoint, ros2 topic "
        "pub) then holds the graph up less often; the composed process keeps them",
    )


def default_bag(prefix: str) -> Path:
    return Path("bags") / datetime.now().strftime(f"{prefix}_%Y%m%d_%H%M%S")


def bag_folder(record, prefix: str) -> Path:
    """The folder ``--record`` asks for; ValueError if it is already used (checked before the
    graph starts)."""
    folder = default_bag(prefix) if record is True else Path(record)
    if folder.exists() and (not folder.is_dir() or any(folder.iterdir())):
        raise ValueError(f"--record {folder}: exists and is not an empty folder")
    try:
        folder.parent.mkdir(parents=True, exist_ok=True)
    except OSError as error:
        raise ValueError(
            f"--record {folder}: cannot make {error.filename}: {error.strerror}"
        ) from None
    return folder


def stop_recorder(prefix: str, recorder) -> bool:
    """Stop ``recorder`` and print its bag; False (and why) if the recording failed."""
    try:
        print_bag(prefix, recorder.stop())
    except RuntimeError as error:
        print(f"{prefix}: recording failed: {error}", file=sys.stderr, flush=True)
        return False
    return True


def print_bag(prefix: str, info) -> None:
    """The bag's path and its per-topic message counts (hems_ros.bag.bag_info)."""
    print(
        f"{prefix}: bag {info.path}: {info.message_count} messages, "
        f"{(info.end_ns - info.start_ns) * 1e-9:.1f} s",
        flush=True,
    )
    for topic, entry in sorted(info.topics.items()):
        print(f"  {topic:<40} {entry.count:>7}  {entry.type}")


def graph_options(args: argparse.Namespace) -> GraphOptions:
    fingers = names.parse_fingers(args.fingers)
    extra = tuple(args.extra_params or ())
    for option, path in [("--params-file", args.params_file)] + [
        ("--extra-params", p) for p in extra
    ]:
        if not path.is_file():
            raise ValueError(f"{option} {path}: no such file")
    return GraphOptions(
        params_file=args.params_file,
        extra_params_files=extra,
        composed=args.composed,
        sim_time=args.sim_time,
        rate=args.rate,
        fingers=fingers,
        log_level=args.log_level,
        parameter_services=args.parameter_services,
        namespace=args.namespace,
    )


def register(subparsers) -> None:
    parser = subparsers.add_parser(
        "up",
        help="start the 16 nodes of the graph (Ctrl-C stops them all)",
        description="Start six actuation units, three shoulder modules, six finger controllers and "
        "the supervisor, composed in one process (or each in its own with --separate); one line "
        "says when every stream is present. Ctrl-C or SIGTERM stops every node within 3 s. "
        "Then: hems enable; hems setpoint index 20 --unit mm; hems status.",
    )
    add_graph_arguments(parser)
    parser.add_argument(
        "--duration", type=positive, default=None, help="stop by itself after this many seconds"
    )
    parser.add_argument(
        "--record",
        nargs="?",
        type=Path,
        const=True,
        default=None,
        metavar="DIR",
        help="record every /hems topic, /diagnostics and /clock into the bag folder DIR "
        "(default bags/hems_<date>_<time>)",
    )
    parser.set_defaults(func=run)


def layout_text(options: GraphOptions) -> str:
    """How the graph's nodes run, in a few words."""
    nodes = len(node_specs(options))
    return f"{nodes} nodes in one process" if options.composed else f"{nodes} node processes"


def readiness_watcher(options: GraphOptions, started: float) -> subprocess.Popen:
    """`hems wait` in a process of its own: it prints one line when every stream is present
    (or what is missing after a minute) and leaves the domain; this process stays free of
    rclpy, whose signal handling would take Ctrl-C from the graph's shutdown."""
    return subprocess.Popen(
        [sys.executable, "-m", "hems_ros.cli.main", "wait", "--prefix", "hems up", "--for-up"]
        + ["--since", repr(started), "--namespace", options.namespace],
        env=child_environment(),
        preexec_fn=die_with_parent,
        process_group=0,
    )


def run(args: argparse.Namespace) -> int:
    try:
        options = graph_options(args)
        record = None if args.record is None else bag_folder(args.record, "hems")
    except ValueError as error:
        print(f"hems up: {error}", file=sys.stderr)
        return 2
    stop = {"requested": False}

    def request_stop(signum, frame) -> None:
        stop["requested"] = True

    signal.signal(signal.SIGINT, request_stop)
    signal.signal(signal.SIGTERM, request_stop)
    started = time.monotonic()
    graph = Graph(options)
    graph.start()
    if graph.orphans_removed:
        print(
            f"hems up: removed {graph.orphans_removed} Fast DDS files that killed processes "
            "had left in /dev/shm",
            flush=True,
        )
    watcher = readiness_watcher(options, started)
    recorder = None
    if record is not None:
        from hems_ros.bag.recording import RecorderProcess
        from hems_ros.bag.selection import record_regex

        recorder = RecorderProcess(record, regex=record_regex(options.namespace))
        print(f"hems up: recording into {recorder.output}", flush=True)
    print(
        f"hems up: {layout_text(options)}"
        f"{f', sim time x{rate_text(options.rate)}' if options.sim_time else ''}; Ctrl-C to stop",
        flush=True,
    )
    reported: set[str] = set()
    recorded = True
    try:
        while not stop["requested"]:
            if args.duration is not None and time.monotonic() - started >= args.duration:
                break
            for name, code in graph.exited().items():
                if name not in reported:
                    reported.add(name)
                    print(
                        f"hems up: {name} exited {exit_description(code)}",
                        file=sys.stderr,
                        flush=True,
                    )
            if len(reported) == len(graph.processes):
                break
            time.sleep(0.05)
    finally:
        if watcher.poll() is None:
            watcher.terminate()
        if recorder is not None:  # first, so that the bag ends with the graph still running
            recorded = stop_recorder("hems up", recorder)
        t0 = time.monotonic()
        codes = graph.stop()
        print(
            f"hems up: stopped {len(codes)} process{'es' if len(codes) != 1 else ''} "
            f"in {time.monotonic() - t0:.2f} s"
            + (
                f" (killed after the grace period: {', '.join(graph.killed)})"
                if graph.killed
                else ""
            ),
            flush=True,
        )
        # a watcher wedged in its own teardown (ros/teardown.py) would hold this terminal's
        # output open after the launcher has gone
        stop_process(watcher, grace_s=1.0)
    return 0 if recorded else 1
