"""Command-line tools joining a running, enabled graph: they must never fault it.

Every command-line tool (`hems setpoint`, `hems status`, `ros2 topic pub`...) is a new DDS
participant, and every participant of the graph takes part in its discovery; on a two-core
host that burst holds the graph's streams up by tens of milliseconds. This runs the enabled
graph with all six fingers holding a tendon position, then ``--joins`` times starts one
command-line process, in turn: `hems setpoint <finger> <mm>` (the finger and value change
each time), `hems status`, `hems enable` (already enabled), `hems reset` (nothing to reset)
and a plain rclpy process that creates a publisher and sends one FingerSetpoint as soon as
the controller has matched it, as `ros2 topic pub --once` does. It counts the joins after
which the supervisor left ENABLED, and checks that every setpoint was reached (the finger's
controller status shows the tendon within 0.5 mm of it, or past it, before the next join).
Also printed: the CPU time each kind of tool took in its own process (median), which on a
host with one free core comes out of the graph's share. Layouts: separate (`hems up
--separate`, 16 processes, as `ros2 run` of each node gives) and composed (one process, the
default of `hems up`).

Usage: .venv/bin/python benchmarks/bench_graph_joins.py [--joins 20] [--layouts separate,composed]
       [--busy] [--markdown FILE]    (the result table, as docs/reliability.md shows it)
       [--smoke]    (one join of each kind, composed)
"""

from __future__ import annotations

import argparse
import collections
import json
import math
import os
import statistics
import subprocess
import sys
import time
from pathlib import Path

import busy as busy_option
import smoke
from host import host_line

from hems_ros.rosenv import (
    apply_network_defaults,
    child_environment,
    use_private_domain,
)

apply_network_defaults()
DOMAIN_LOCK = use_private_domain()  # no test run or other benchmark shares it

from diagnostic_msgs.msg import DiagnosticArray  # noqa: E402
from hems_msgs.msg import ControllerStatus, SupervisorStatus  # noqa: E402

from hems_ros.client.graph_client import GraphClient  # noqa: E402
from hems_ros.graph import names  # noqa: E402
from hems_ros.graph.supervisor_logic import QUIET_KEY, parse_gaps  # noqa: E402
from hems_ros.launcher import Graph, GraphOptions  # noqa: E402
from hems_ros.ros import qos  # noqa: E402

SETTLE_S = 1.5  # after each command, before judging it
HOLD_M = 0.010
REACHED_M = 0.5e-3  # a setpoint counts as reached within this of the tendon position
SETTLE_HOLD_S = 60.0  # at most this long for every finger to settle at HOLD_M before the joins
KINDS = ("setpoint", "status", "enable", "reset", "topic pub")
# what `ros2 topic pub --once` does, as a short script (ros2cli is not installed here)
TOPIC_PUB = """
import sys, time, rclpy
from hems_msgs.msg import FingerSetpoint
from hems_ros.ros import qos
rclpy.init()
node = rclpy.create_node("topic_pub_once")
pub = node.create_publisher(FingerSetpoint, sys.argv[1], qos.COMMAND)
deadline = time.monotonic() + 10.0
while pub.get_subscription_count() < 1 and time.monotonic() < deadline:
    time.sleep(0.02)
pub.publish(FingerSetpoint(mode="position", value=float(sys.argv[2])))
time.sleep(0.1)
rclpy.shutdown()
"""


def fault_kind(fault: str) -> str:
    """'index: wire_force lost (600 ms ...)' -> 'wire_force lost'."""
    return fault.split(": ", 1)[-1].split(" (")[0].split(" for ")[0]


def reached(statuses: list, value: float, start_m: float) -> bool:
    """The finger, at ``start_m`` before the join, came within REACHED_M of ``value`` or went
    past it (an SMA finger that overshoots comes back only as its wire cools, which can outlast
    SETTLE_S)."""
    first = start_m - value
    return any(
        abs(m.measurement - value) <= REACHED_M or (m.measurement - value) * first < 0
        for m in statuses
    )


def command(kind: str, i: int) -> tuple[list[str], tuple[str, float] | None]:
    """(argv, (finger, tendon position m) if the join sets one) of join ``i``."""
    finger = names.FINGERS[i % len(names.FINGERS)]
    value_m = HOLD_M + 1e-3 * ((i // len(KINDS)) % 2)
    hems = [sys.executable, "-m", "hems_ros.cli.main"]
    if kind == "setpoint":
        return hems + ["setpoint", finger, f"{value_m * 1e3:g}", "--unit", "mm"], (finger, value_m)
    if kind == "topic pub":
        return (
            [sys.executable, "-c", TOPIC_PUB, names.topic(finger, "setpoint"), repr(value_m)],
            (finger, value_m),
        )
    return hems + [kind], None


def run(composed: bool, joins: int) -> dict:  # noqa: C901 -- one join of each kind in turn
    graph = Graph(GraphOptions(composed=composed, log_level="error"))
    graph.start()
    faults: list[tuple[float, str]] = []
    shown: dict[str, collections.deque] = {f: collections.deque(maxlen=400) for f in names.FINGERS}

    def on_status(message: SupervisorStatus) -> None:
        if message.state_name != "ENABLED" and (
            not faults or faults[-1][1] != "; ".join(message.faults)
        ):
            faults.append((time.monotonic(), "; ".join(message.faults) or message.state_name))

    # the supervisor's stream gaps while ENABLED, (finger, stream): (count, longest s)
    gaps: dict[tuple[str, str], tuple[int, float]] = {}
    supervisor = names.diagnostic_name(names.NAMESPACE, "supervisor")

    quiets = ["-"]  # the supervisor's latest count of its own quiets, "count, longest N ms"

    def on_diagnostics(message: DiagnosticArray) -> None:
        for status in message.status:
            if status.name == supervisor:
                gaps.update(parse_gaps((kv.key, kv.value) for kv in status.values))
                quiets[0] = next(
                    (kv.value for kv in status.values if kv.key == QUIET_KEY), quiets[0]
                )

    try:
        with GraphClient("hems_bench_joins") as client:
            client.node.create_subscription(
                SupervisorStatus, names.SUPERVISOR_STATUS_TOPIC, on_status, qos.STATUS
            )
            client.node.create_subscription(
                DiagnosticArray, names.DIAGNOSTICS_TOPIC, on_diagnostics, 10
            )
            for finger in names.FINGERS:
                client.node.create_subscription(
                    ControllerStatus,
                    names.topic(finger, "controller_status"),
                    lambda m, f=finger: shown[f].append((time.monotonic(), m)),
                    qos.CONTROLLER_STATUS,
                )
            ok, message = client.enable_when_ready(120, reset=True, retry_s=1.0)
            if not ok:
                return {"error": f"could not enable: {graph.with_exits(message)}"}
            for finger in names.FINGERS:
                client.send_setpoint(finger, "position", HOLD_M, confirm_s=10.0)
            # an SMA finger that overshoots its first step comes back only as its wire cools:
            # the joins start once every finger holds its position
            settle_end = time.monotonic() + SETTLE_HOLD_S
            while time.monotonic() < settle_end and not all(
                shown[f] and abs(shown[f][-1][1].measurement - HOLD_M) < REACHED_M / 2
                for f in names.FINGERS
            ):
                client.spin_for(0.2)
            client.spin_for(1.0)
            faults.clear()
            faulted, missed = 0, []
            kinds: collections.Counter[str] = collections.Counter()
            by_kind: collections.Counter[str] = collections.Counter()
            tool_cpu: dict[str, list[float]] = collections.defaultdict(list)
            for i in range(joins):
                kind = KINDS[i % len(KINDS)]
                argv, target = command(kind, i)
                started, times_before = time.monotonic(), os.times()
                subprocess.run(
                    argv, capture_output=True, text=True, timeout=120, env=child_environment()
                )
                times_after = os.times()
                tool_cpu[kind].append(
                    times_after.children_user
                    - times_before.children_user
                    + times_after.children_system
                    - times_before.children_system
                )
                client.spin_for(SETTLE_S)
                by_kind[kind] += 1
                if target is not None:
                    finger, value = target
                    # the statuses that came while the tool ran are taken only now, the oldest
                    # dropped by the reader's history: the start is the last one before the join
                    before = [m for t, m in shown[finger] if t < started]
                    since = [m for t, m in shown[finger] if t >= started]
                    if not since or not math.isclose(since[-1].setpoint, value, abs_tol=1e-9):
                        missed.append(
                            f"join {i + 1} ({kind} {finger} {value * 1e3:g} mm): not taken"
                        )
                    elif not reached(
                        since, value, (before or since)[-1 if before else 0].measurement
                    ):
                        missed.append(
                            f"join {i + 1} ({kind} {finger} {value * 1e3:g} mm): at "
                            f"{since[-1].measurement * 1e3:.2f} mm after {SETTLE_S:g} s"
                        )
                new = [text for t, text in faults if t >= started]
                print(
                    f"  join {i + 1}/{joins}: {kind}{'' if not new else ' -> ' + new[-1]}",
                    flush=True,
                )
                if new:
                    faulted += 1
                    kinds.update({fault_kind(part) for text in new for part in text.split("; ")})
                    ok, message = client.enable_when_ready(30, reset=True, retry_s=0.5)
                    if not ok:
                        return {"error": f"could not enable again: {message}"}
            client.spin_for(1.5)  # the supervisor's last diagnostics (1 Hz)
    finally:
        graph.stop()

    def longest_of(items):
        return max(items, key=lambda kv: kv[1][1], default=(("-", "-"), (0, 0.0)))

    longest = longest_of(gaps.items())
    # what the loss limits guard: readings and heartbeats; a unit's state report (20 Hz)
    # only names a silent unit, whose encoder falls silent with it
    sensed = longest_of(kv for kv in gaps.items() if kv[0][1] != "unit state")
    return {
        "joins": joins,
        "faulted": faulted,
        "kinds": dict(kinds),
        "missed": missed,
        "by_kind": dict(by_kind),
        "tool_cpu_s": {kind: statistics.median(cpu) for kind, cpu in tool_cpu.items()},
        "gaps": sum(count for count, _ in gaps.values()),
        "longest_gap_ms": 1e3 * longest[1][1],
        "longest_gap_stream": " ".join(longest[0]),
        "longest_sensor_gap_ms": 1e3 * sensed[1][1],
        "longest_sensor_gap_stream": " ".join(sensed[0]),
        "supervisor_quiets": quiets[0],
    }


def table(results: dict[str, dict]) -> str:
    lines = [
        "| layout | joins (setpoint, status, enable, reset, topic pub) | supervisor left ENABLED | "
        "setpoints not reached | faults named | stream gaps over 50 ms (longest) | "
        "longest sensor or heartbeat gap | supervisor quiets (longest) |",
        "|---|---|---|---|---|---|---|---|",
    ]
    for layout, r in results.items():
        if "error" in r:
            lines.append(f"| {layout} | - | {r['error']} | - | - | - | - | - |")
            continue
        kinds = ", ".join(f"{k} x{n}" for k, n in sorted(r["kinds"].items())) or "-"
        per_kind = ", ".join(str(r["by_kind"].get(k, 0)) for k in KINDS)
        lines.append(
            f"| {layout} | {r['joins']} ({per_kind}) | {r['faulted']} | {len(r['missed'])} | "
            f"{kinds} | {r['gaps']} ({r['longest_gap_ms']:.0f} ms, {r['longest_gap_stream']}) | "
            f"{r['longest_sensor_gap_ms']:.0f} ms ({r['longest_sensor_gap_stream']}) | "
            f"{r['supervisor_quiets']} |"
        )
    return "\n".join(lines) + "\n"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument(
        "--joins", type=int, default=20, help="command-line processes per layout (default 20)"
    )
    parser.add_argument(
        "--layouts",
        default="separate,composed",
        help="comma-separated layouts: separate (hems up --separate), composed (default both)",
    )
    parser.add_argument(
        "--markdown", type=Path, default=None, help="also write the result table to this file"
    )
    parser.add_argument(
        "--json", type=Path, default=None, help="also write the results as JSON to this file"
    )
    busy_option.add_option(parser)
    args = smoke.parse_args(parser, joins=len(KINDS), layouts="composed")
    results = {}
    busy = busy_option.start(args)
    try:
        for layout in args.layouts.split(","):
            print(
                f"{layout}: {args.joins} joins"
                + (", a busy loop on one core" if busy else "")
                + f"; {host_line()}",
                flush=True,
            )
            results[layout] = run(layout == "composed", args.joins)
            for miss in results[layout].get("missed", []):
                print(f"  not reached: {miss}")
    finally:
        if busy is not None:
            busy.kill()
    text = table(results)
    print(f"after the joins: {host_line()}")
    print(text)
    for layout, r in results.items():
        if "tool_cpu_s" in r:
            each = ", ".join(f"{kind} {cpu:.2f} s" for kind, cpu in r["tool_cpu_s"].items())
            print(f"{layout}: CPU of one tool in its own process (median): {each}")
    if args.markdown is not None:
        args.markdown.write_text(text)
    if args.json is not None:
        args.json.write_text(json.dumps(results, indent=1))
    failed = [layout for layout, r in results.items() if "error" in r]
    if failed:
        sys.exit(f"bench_graph_joins: no figures for {', '.join(failed)}")


if __name__ == "__main__":
    main()
