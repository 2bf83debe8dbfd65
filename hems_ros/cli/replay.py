"""``hems replay <bag>``: republish a bag onto the live graph with its original timing."""

from __future__ import annotations

import argparse
import math
import sys
import time
from collections import Counter
from collections.abc import Iterable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import yaml

from hems_ros.cli.numbers import non_negative, positive
from hems_ros.ros.teardown import end_ros

CLOCK_TOPIC = "/clock"


def register(subparsers) -> None:
    parser = subparsers.add_parser(
        "replay",
        help="republish a bag with its original timing",
        description=(
            "Publish the messages of a bag (as stored, no re-encoding) at their recorded "
            "log-time spacing divided by --rate, with the QoS their publishers offered. "
            "--clock publishes rosgraph_msgs/Clock with the bag's time so nodes with "
            "use_sim_time follow the replay (a recorded /clock topic is then not replayed). "
            "With --loop the bag restarts (and its clock jumps back) after the last message. "
            "Ctrl-C or SIGTERM stops it and prints what was replayed so far (exit code 0)."
        ),
    )
    parser.add_argument("bag", help="bag folder or .mcap file")
    parser.add_argument(
        "--rate", type=positive, default=1.0, help="speed factor (2 = twice as fast)"
    )
    parser.add_argument("--loop", action="store_true", help="replay until interrupted")
    parser.add_argument(
        "--topic", action="append", default=[], dest="topics", help="replay this topic (repeatable)"
    )
    parser.add_argument(
        "--regex", default=None, help="replay topics fully matching this regular expression"
    )
    parser.add_argument(
        "--remap",
        action="append",
        default=[],
        metavar="FROM:=TO",
        help="publish topic FROM on TO (repeatable)",
    )
    parser.add_argument(
        "--clock",
        type=positive,
        nargs="?",
        const=100.0,
        default=0.0,
        metavar="HZ",
        help="publish /clock from the bag's time at HZ (default 100 Hz when given)",
    )
    parser.add_argument(
        "--start-delay",
        type=non_negative,
        default=1.0,
        help="seconds between creating the publishers and the first message (discovery)",
    )
    parser.add_argument(
        "--wait-subscribers",
        type=non_negative,
        default=0.0,
        metavar="SECONDS",
        help="before starting, wait up to SECONDS until every replayed topic has a subscriber",
    )
    parser.set_defaults(func=run)


@dataclass
class ReplayResult:
    published: Counter = field(default_factory=Counter)
    loops: int = 0
    wall_s: float = 0.0
    interrupted: bool = False  # stopped by SIGINT / SIGTERM before the bag (or --loop) was through


def parse_remaps(items: Iterable[str]) -> dict[str, str]:
    remaps = {}
    for item in items:
        source, sep, target = item.partition(":=")
        if not sep or not source.startswith("/") or not target.startswith("/"):
            raise ValueError(f"remap {item!r} is not of the form /from:=/to")
        remaps[source] = target
    return remaps


def replay_qos(offered: str, depth: int = 100):
    """Reliable / transient local only if every recorded publisher offered it; the shortest
    liveliness lease if every one offered a lease (a reader that asks for a lease, as the
    controllers and units do of the supervisor's status, matches no writer without one)."""
    from rclpy.duration import Duration
    from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy

    from hems_ros.bag import offered_lease_ns

    try:
        profiles = yaml.safe_load(offered) if offered else []
    except yaml.YAMLError:
        profiles = []
    profiles = [p for p in profiles or [] if isinstance(p, dict)]
    reliable = not profiles or all(str(p.get("reliability")) in ("reliable", "1") for p in profiles)
    latched = bool(profiles) and all(
        str(p.get("durability")) in ("transient_local", "1") for p in profiles
    )
    leases = [offered_lease_ns(p) for p in profiles]
    qos = QoSProfile(
        depth=depth,
        reliability=ReliabilityPolicy.RELIABLE if reliable else ReliabilityPolicy.BEST_EFFORT,
        durability=DurabilityPolicy.TRANSIENT_LOCAL if latched else DurabilityPolicy.VOLATILE,
    )
    if leases and all(leases):
        qos.liveliness_lease_duration = Duration(nanoseconds=min(leases))
    return qos


def replay(
    bag: str | Path,
    rate: float = 1.0,
    loop: bool = False,
    topics: Iterable[str] | None = None,
    regex: str | None = None,
    remap: dict[str, str] | None = None,
    clock_hz: float = 0.0,
    start_delay: float = 1.0,
    wait_subscribers: float = 0.0,
) -> ReplayResult:
    """Republish ``bag`` on the live graph (rclpy must not be initialised by the caller)."""
    import rclpy
    from rclpy.duration import Duration
    from rclpy.node import Node
    from rosgraph_msgs.msg import Clock

    from hems_ros.bag import iter_messages
    from hems_ros.ros.wire import message_class

    if not (math.isfinite(rate) and rate > 0):
        raise ValueError(f"rate must be a finite number > 0, not {rate}")
    for name, value in (
        ("clock_hz", clock_hz),
        ("start_delay", start_delay),
        ("wait_subscribers", wait_subscribers),
    ):
        if not (math.isfinite(value) and value >= 0):
            raise ValueError(f"{name} must be a finite number >= 0, not {value}")
    remap = remap or {}
    messages = sorted(
        (m for m in iter_messages(bag, topics, regex) if not (clock_hz and m.topic == CLOCK_TOPIC)),
        key=lambda m: m.log_time_ns,
    )
    result = ReplayResult()
    if not messages:
        return result
    rclpy.init(args=[])
    node = Node("replay", namespace="/hems", enable_rosout=False)
    try:
        publishers: dict[str, Any] = {}
        for message in messages:
            if message.topic not in publishers:
                publishers[message.topic] = node.create_publisher(
                    message_class(message.type),
                    remap.get(message.topic, message.topic),
                    replay_qos(message.offered_qos_profiles),
                )
        clock = node.create_publisher(Clock, CLOCK_TOPIC, 10) if clock_hz > 0 else None
        time.sleep(start_delay)
        deadline = time.monotonic() + wait_subscribers
        while (
            any(p.get_subscription_count() == 0 for p in publishers.values())
            and time.monotonic() < deadline
        ):
            time.sleep(0.02)
        if wait_subscribers:
            time.sleep(0.2)  # matched here; the subscribers' side matches us a moment later
        started = time.perf_counter()
        try:
            while _play(messages, publishers, clock, clock_hz, rate, result):
                result.loops += 1
                if not loop:
                    break
            else:
                result.interrupted = True
        except KeyboardInterrupt:
            result.interrupted = True
        result.wall_s = time.perf_counter() - started
        if not result.interrupted:
            # Destroying a publisher drops what reliable readers have not acknowledged yet,
            # so the last messages of a bag would otherwise be lost. After SIGTERM the context
            # is gone and there is nothing left to wait with.
            for publisher in publishers.values():
                publisher.wait_for_all_acked(Duration(seconds=2.0))
    finally:
        end_ros([node])
    return result


def _play(messages, publishers, clock, clock_hz: float, rate: float, result: ReplayResult) -> bool:
    """One pass over ``messages`` at their recorded spacing / ``rate`` (and /clock from their
    time); False when ROS shut down before the pass was through (SIGTERM)."""
    import rclpy
    from rosgraph_msgs.msg import Clock

    first = messages[0].log_time_ns
    wall_start = time.perf_counter()
    next_tick = wall_start
    for message in messages:
        due = wall_start + (message.log_time_ns - first) * 1e-9 / rate
        while True:
            now = time.perf_counter()
            if clock is not None and now >= next_tick:
                bag_ns = first + int((now - wall_start) * rate * 1e9)
                clock.publish(Clock(clock=_time_msg(min(bag_ns, message.log_time_ns))))
                next_tick += 1.0 / clock_hz
            if now >= due or not rclpy.ok():
                break
            wake = min(due, next_tick) if clock is not None else due
            time.sleep(max(0.0, min(wake - now, 0.05)))
        if not rclpy.ok():
            return False
        publishers[message.topic].publish(message.data)
        result.published[message.topic] += 1
    if clock is not None:
        clock.publish(Clock(clock=_time_msg(messages[-1].log_time_ns)))
    return True


def _time_msg(nanoseconds: int):
    from builtin_interfaces.msg import Time

    sec, nanosec = divmod(nanoseconds, 1_000_000_000)
    return Time(sec=sec, nanosec=nanosec)


def run(args: argparse.Namespace) -> int:
    from hems_ros.bag import BagFormatError

    try:
        remaps = parse_remaps(args.remap)
        result = replay(
            args.bag,
            args.rate,
            args.loop,
            args.topics,
            args.regex,
            remaps,
            args.clock,
            args.start_delay,
            args.wait_subscribers,
        )
    except (BagFormatError, FileNotFoundError, ValueError) as error:
        print(f"hems replay: {error}", file=sys.stderr)
        return 2
    total = sum(result.published.values())
    if not total and (args.topics or args.regex):
        from hems_ros.bag import bag_info

        have = ", ".join(sorted(bag_info(args.bag).topics)) or "none"
        print(
            f"hems replay: no message of {args.bag} on the selected topics; its topics: {have}",
            file=sys.stderr,
        )
        return 2
    print(
        f"replayed {total} messages on {len(result.published)} topics in {result.wall_s:.3f} s "
        f"({result.loops} full pass{'es' if result.loops != 1 else ''}"
        f"{'; stopped by a signal' if result.interrupted else ''})"
    )
    return 0
