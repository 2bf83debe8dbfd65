"""``hems soak``: run the full graph for a long time, with grasp cycles and command-line tools
joining, while recording; then report memory per process, messages lost in the bag, control
periods missed and faults (hems_ros.graph.soak judges them)."""

from __future__ import annotations

import argparse
import random
import subprocess
import sys
import time
from pathlib import Path
from typing import TYPE_CHECKING

from hems_ros.cli.numbers import non_negative_int, positive
from hems_ros.cli.up import (
    add_graph_arguments,
    bag_folder,
    graph_options,
    layout_text,
    stop_recorder,
)
from hems_ros.graph import names, soak
from hems_ros.rosenv import child_environment

if TYPE_CHECKING:
    from hems_ros.client.recorded_run import RecordedGraph

MEMORY_EVERY_S = 10.0
PROGRESS_EVERY_S = 60.0
OPEN_M, CLOSED_M = (0.005, 0.010), (0.015, 0.025)  # tendon positions of a random grasp cycle


def register(subparsers) -> None:
    parser = subparsers.add_parser(
        "soak",
        help="run the graph for N minutes with grasps and command-line joins; report its health",
        description="Start the graph, record it, enable it and drive every finger through random "
        "grasp cycles (position setpoints between 5 and 25 mm of tendon travel) while command-line "
        "tools join the domain now and then (hems status, hems setpoint, hems enable). At the "
        "end, each after the warm-up: resident memory growth per process (limit 5 %), messages "
        "lost in the bag (gaps in sequence numbers, limit 0), control periods missed (encoder "
        "samples no duty command answered, limit 0.5 %); and faults over the whole run (limit "
        "0); what the start-up and warm-up lost and missed is reported apart. "
        "Exit code 0 when every limit held, 1 otherwise.",
    )
    parser.add_argument(
        "--minutes", type=positive, default=30.0, help="soak length, minutes (default 30)"
    )
    parser.add_argument(
        "--warmup-minutes",
        type=positive,
        default=3.0,
        help="memory growth, lost messages and missed control periods are counted from the "
        "end of this, minutes (default 3)",
    )
    parser.add_argument(
        "--grasp-period-s",
        type=positive,
        default=8.0,
        help="one grasp cycle (close, then open) every this many seconds (default 8)",
    )
    parser.add_argument(
        "--join-period-s",
        type=positive,
        default=30.0,
        help="a command-line tool joins every this many seconds (default 30)",
    )
    parser.add_argument(
        "--seed", type=non_negative_int, default=1, help="random grasp targets (default 1)"
    )
    parser.add_argument(
        "--report", type=Path, default=None, help="also write the report (Markdown) to this file"
    )
    add_graph_arguments(parser)
    parser.add_argument(
        "--record",
        type=Path,
        default=None,
        metavar="DIR",
        help="bag folder (default bags/soak_<date>_<time>)",
    )
    parser.set_defaults(func=run)


def _join(i: int, rng: random.Random) -> list[str]:
    hems = [sys.executable, "-m", "hems_ros.cli.main"]
    kind = ("status", "setpoint", "enable")[i % 3]
    if kind == "setpoint":
        finger = rng.choice(names.FINGERS)
        return hems + ["setpoint", finger, f"{1e3 * rng.uniform(*CLOSED_M):.1f}", "--unit", "mm"]
    return hems + [kind]


class _Soak:
    def __init__(self, args: argparse.Namespace, graph_run: RecordedGraph, fingers) -> None:
        self.args, self.fingers = args, fingers
        self.graph, self.recorder, self.client = (
            graph_run.graph,
            graph_run.recorder,
            graph_run.client,
        )
        self.rng = random.Random(args.seed)
        self.memory = soak.MemoryLog()
        self.faults: list[str] = []
        self.grasps = self.joins = self.recovered = 0
        self.started_ns = 0  # when run() began, wall clock ns (the graph's stamps)

    def on_status(self, message) -> None:
        if message.state_name in ("FAULT", "ESTOP"):
            text = "; ".join(message.faults) or message.state_name
            if not self.faults or self.faults[-1] != text:
                self.faults.append(text)

    def sample_memory(self, t: float) -> None:
        for name, process in self.graph.processes.items():
            self.memory.add(name, t, soak.rss_bytes(process.pid))
        self.memory.add("recorder", t, soak.rss_bytes(self.recorder.process.pid))

    def run(self) -> None:
        end_s = 60.0 * self.args.minutes
        start = time.monotonic()
        self.started_ns = time.time_ns()
        next_grasp = next_join = next_memory = 0.0
        next_progress = PROGRESS_EVERY_S
        closing, joiner = True, None
        while (t := time.monotonic() - start) < end_s:
            if t >= next_memory:
                self.sample_memory(t)
                next_memory += MEMORY_EVERY_S
            if t >= next_grasp:
                span = CLOSED_M if closing else OPEN_M
                for finger in self.fingers:
                    self.client.send_setpoint(
                        finger, "position", self.rng.uniform(*span), confirm_s=2.0
                    )
                self.grasps += not closing
                closing = not closing
                next_grasp += self.args.grasp_period_s / 2
            if joiner is None and t >= next_join:
                joiner = subprocess.Popen(
                    _join(self.joins, self.rng),
                    env=child_environment(),
                    stdout=subprocess.DEVNULL,
                    stderr=subprocess.DEVNULL,
                )
                self.joins += 1
                next_join += self.args.join_period_s
            if joiner is not None and joiner.poll() is not None:
                joiner = None
            if len(self.faults) > self.recovered:
                # counted; the soak goes on from a reset graph, as an operator would go on
                self.recovered = len(self.faults)
                self.client.enable_when_ready(60.0, reset=True, retry_s=1.0)
            if t >= next_progress:
                self.progress(t)
                next_progress += PROGRESS_EVERY_S
            self.client.spin_for(0.05)
        if joiner is not None:
            joiner.wait(timeout=60)

    def progress(self, t: float) -> None:
        name, growth = max(
            (
                (n, g)
                for n, (_, _, g) in self.memory.growth(60.0 * self.args.warmup_minutes).items()
            ),
            key=lambda item: item[1],
            default=("-", 0.0),
        )
        memory = f", worst memory growth {100 * growth:+.1f} % ({name})" if name != "-" else ""
        print(
            f"soak: {t / 60:.1f}/{self.args.minutes:g} min: {self.grasps} grasps, {self.joins} "
            f"joins, {len(self.faults)} faults{memory}",
            flush=True,
        )


def run(args: argparse.Namespace) -> int:
    try:
        options = graph_options(args)
        folder = bag_folder(True if args.record is None else args.record, "soak")
    except ValueError as error:
        print(f"hems soak: {error}", file=sys.stderr)
        return 2
    from hems_msgs.msg import SupervisorStatus

    from hems_ros.bag.reader import load_bag
    from hems_ros.client.recorded_run import recorded_graph
    from hems_ros.ros import qos

    print(
        f"hems soak: {layout_text(options)}, recording into {folder}, {args.minutes:g} min",
        flush=True,
    )
    with recorded_graph(options, folder, "hems_soak", 120.0) as graph_run:
        client = graph_run.client
        ok, message = client.enable_when_ready(120.0, reset=True, retry_s=1.0)
        if not ok:
            print(
                f"hems soak: could not enable the graph: {graph_run.graph.with_exits(message)}",
                file=sys.stderr,
            )
            return 1
        run_ = _Soak(args, graph_run, options.fingers)
        client.node.create_subscription(
            SupervisorStatus,
            names.supervisor_status_topic(options.namespace),
            run_.on_status,
            qos.STATUS,
        )
        run_.run()
        for finger in options.fingers:
            client.send_setpoint(finger, "position", 0.0, confirm_s=2.0)
        client.call("disable")
        client.spin_for(0.5)
        recorded = stop_recorder("hems soak", graph_run.recorder)
    if not recorded:
        return 1
    bag = load_bag(folder)
    # the start-up (sixteen processes loading on two cores, streams being matched) misses
    # periods and loses samples the steady graph does not: judged, like memory, after the
    # warm-up, and reported apart
    warmed_ns = run_.started_ns + round(60e9 * args.warmup_minutes)
    early = [soak.missed_periods(bag, f, until_ns=warmed_ns) for f in options.fingers]
    result = soak.SoakResult(
        minutes=args.minutes,
        grasps=run_.grasps,
        joins=run_.joins,
        faults=run_.faults,
        memory=run_.memory.growth(60.0 * args.warmup_minutes),
        losses=soak.bag_losses(bag, since_ns=warmed_ns),
        missed={finger: soak.missed_periods(bag, finger, warmed_ns) for finger in options.fingers},
        bag=str(folder),
        missed_in_warmup=(sum(m for m, _ in early), sum(n for _, n in early)),
        lost_in_warmup=sum(soak.bag_losses(bag, until_ns=warmed_ns).values()),
    )
    text = result.markdown()
    print(text)
    if args.report is not None:
        args.report.write_text(text)
    failures = result.failures()
    for failure in failures:
        print(f"hems soak: {failure}", file=sys.stderr)
    return 1 if failures else 0
