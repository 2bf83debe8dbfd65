"""``hems ping``: DDS round trips to a ping_responder in another process."""

from __future__ import annotations

import argparse
import statistics
import subprocess
import sys
import time

from hems_ros.cli.numbers import positive, positive_int
from hems_ros.processes import exit_description, stop_process
from hems_ros.ros.teardown import end_ros
from hems_ros.rosenv import child_environment


def register(subparsers) -> None:
    parser = subparsers.add_parser(
        "ping",
        help="check DDS between processes: round trips to a ping_responder node",
        description=(
            "Send hems_msgs/DutyCommand probes on /hems/ping/request to a ping_responder "
            "node (started here as a separate process unless --no-spawn) and check every "
            "hems_msgs/EncoderReading answer on /hems/ping/reply: sequence number and field "
            "values must come back intact. Prints round-trip times in milliseconds."
        ),
    )
    add_arguments(parser)
    parser.set_defaults(func=run)


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument(
        "--count", type=positive_int, default=50, help="number of probes (default 50)"
    )
    parser.add_argument(
        "--rate", type=positive, default=50.0, help="probes per second (default 50 Hz)"
    )
    parser.add_argument(
        "--timeout",
        type=positive,
        default=15.0,
        help="seconds to wait for discovery and for answers (default 15 s)",
    )
    parser.add_argument(
        "--no-spawn", action="store_true", help="do not start a responder; use one already running"
    )


def spawn_responder() -> subprocess.Popen:
    return subprocess.Popen(
        [sys.executable, "-m", "hems_ros.nodes.ping_responder"], env=child_environment()
    )


def ping(count: int, rate: float, timeout: float) -> dict:
    """Send ``count`` probes; return round-trip times (s) and the list of bad answers."""
    import rclpy
    from hems_msgs.msg import DutyCommand, EncoderReading
    from rclpy.node import Node

    from hems_ros.client.graph_client import checked
    from hems_ros.nodes.ping_responder import (
        COUNTS_PER_PERCENT,
        METRES_PER_PERCENT,
        PING_QOS,
        REPLY_TOPIC,
        REQUEST_TOPIC,
    )

    rclpy.init(args=[])
    node = Node("ping_client", namespace="/hems")
    sent: dict[int, tuple[float, float]] = {}
    rtts: list[float] = []
    errors: list[str] = []

    def on_reply(reply: EncoderReading) -> None:
        if reply.sequence not in sent:
            errors.append(f"answer with unknown sequence {reply.sequence}")
            return
        t_sent, duty = sent.pop(reply.sequence)
        rtts.append(time.monotonic() - t_sent)
        if (
            reply.counts != round(duty * COUNTS_PER_PERCENT)
            or abs(reply.position - duty * METRES_PER_PERCENT) > 1e-12
        ):
            errors.append(
                f"sequence {reply.sequence}: counts {reply.counts}, position {reply.position} "
                f"for duty {duty}"
            )
        if reply.finger != "ping":
            errors.append(f"sequence {reply.sequence}: finger {reply.finger!r}")

    publisher = node.create_publisher(DutyCommand, REQUEST_TOPIC, PING_QOS)
    subscription = node.create_subscription(EncoderReading, REPLY_TOPIC, on_reply, PING_QOS)
    try:
        deadline = time.monotonic() + timeout
        while publisher.get_subscription_count() == 0 or subscription.get_publisher_count() == 0:
            if time.monotonic() > deadline:
                raise TimeoutError(f"no ping_responder discovered within {timeout:.0f} s")
            checked(rclpy.spin_once, node, timeout_sec=0.05)
        for sequence in range(count):
            message = DutyCommand(
                finger="ping", duty_percent=(sequence * 7.3) % 100.0, sequence=sequence
            )
            message.header.stamp = node.get_clock().now().to_msg()
            sent[sequence] = (time.monotonic(), message.duty_percent)
            publisher.publish(message)
            next_send = time.monotonic() + 1.0 / rate
            while time.monotonic() < next_send:
                checked(rclpy.spin_once, node, timeout_sec=max(0.0, next_send - time.monotonic()))
        deadline = time.monotonic() + timeout
        while sent and time.monotonic() < deadline:
            checked(rclpy.spin_once, node, timeout_sec=0.05)
    finally:
        end_ros([node])
    errors.extend(f"no answer to sequence {s}" for s in sorted(sent))
    return {"rtts": rtts, "errors": errors, "count": count}


def report(result: dict) -> int:
    rtts_ms = sorted(1e3 * r for r in result["rtts"])
    print(f"ping: {len(rtts_ms)}/{result['count']} answers over DDS")
    if rtts_ms:
        p99 = rtts_ms[min(len(rtts_ms) - 1, int(0.99 * len(rtts_ms)))]
        print(
            f"round trip ms: min {rtts_ms[0]:.3f}  median {statistics.median(rtts_ms):.3f}  "
            f"p99 {p99:.3f}  max {rtts_ms[-1]:.3f}"
        )
    for error in result["errors"][:10]:
        print(f"  error: {error}", file=sys.stderr)
    return 0 if not result["errors"] else 1


def run(args: argparse.Namespace) -> int:
    responder = None if args.no_spawn else spawn_responder()
    try:
        result = ping(args.count, args.rate, args.timeout)
    except TimeoutError as error:
        print(f"ping: {error}", file=sys.stderr)
        return 1
    finally:
        if responder is not None:
            code = stop_process(responder)
            if code not in (0, None):
                print(f"ping: ping_responder exited {exit_description(code)}", file=sys.stderr)
    return report(result)
