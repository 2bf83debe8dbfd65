"""``hems wait``: wait until the graph is ready (every stream ``enable`` needs is present), and
the one progress line that it, ``hems enable`` and the demo show while they wait."""

from __future__ import annotations

import argparse
import sys
import time

from hems_ros.cli.numbers import add_namespace_argument, non_negative, positive

# Sixteen processes starting on two cores, among other work: about 10 s here (docs/reliability.md)
READY_TIMEOUT_S = 60.0
SHOWN = 2  # missing streams named in the progress line; the rest are counted


def describe(missing: list[str] | None) -> str:
    """What a wait is waiting for, in a few words."""
    if missing is None:
        return "no supervisor heard yet"
    if not missing:
        return "every stream present"
    more = f"; and {len(missing) - SHOWN} more" if len(missing) > SHOWN else ""
    return f"{len(missing)} missing: " + "; ".join(missing[:SHOWN]) + more


class WaitingLine:
    """One line for a wait on the graph: rewritten in place on a terminal; elsewhere (a log,
    a pipe) written once, with the outcome after it, rather than at every change."""

    def __init__(self, prefix: str, stream=None) -> None:
        self.prefix = prefix
        self.stream = sys.stderr if stream is None else stream
        self.started = time.monotonic()
        self.tty = self.stream.isatty()
        self.shown = False

    def __call__(self, missing: list[str] | None) -> None:
        if missing == []:
            return  # the caller says what comes of it
        line = (
            f"{self.prefix}: waiting for the graph ({time.monotonic() - self.started:.0f} s): "
            f"{describe(missing)}"
        )
        if self.tty:
            self.stream.write("\r\033[K" + line)
            self.stream.flush()
        elif not self.shown:
            print(line, file=self.stream, flush=True)
        self.shown = True

    def end(self) -> None:
        """Close a line rewritten in place, so that what follows starts on a line of its own."""
        if self.tty and self.shown:
            self.stream.write("\n")
            self.stream.flush()


def register(subparsers) -> None:
    parser = subparsers.add_parser(
        "wait",
        help="wait until the graph is ready (every stream present), for scripts after hems up &",
        description="Wait until the supervisor reports every stream that enable needs (each "
        "finger's encoder, wire force, unit state and controller heartbeat, and the "
        "controller's commands reaching its unit), showing what is still missing. Exit code 0 "
        "when ready, 1 after --timeout with what is missing.",
    )
    parser.add_argument(
        "--timeout",
        type=positive,
        default=READY_TIMEOUT_S,
        help=f"seconds to wait (default {READY_TIMEOUT_S:g})",
    )
    parser.add_argument(
        "--since",
        type=non_negative,
        default=None,
        help=argparse.SUPPRESS,  # `hems up`: its start, time.monotonic() (the clock is system-wide)
    )
    parser.add_argument("--prefix", default="wait", help=argparse.SUPPRESS)
    # `hems up`'s watcher: only the outcome, and a stop (the graph stopped first) says nothing
    parser.add_argument("--for-up", action="store_true", help=argparse.SUPPRESS)
    add_namespace_argument(parser)
    parser.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    from rclpy.executors import ExternalShutdownException

    from hems_ros.client.graph_client import GraphClient

    since = time.monotonic() if args.since is None else args.since
    line = WaitingLine(args.prefix)
    try:
        with GraphClient(name="hems_wait", namespace=args.namespace) as client:
            missing = client.wait_until_ready(args.timeout, None if args.for_up else line)
    except (KeyboardInterrupt, ExternalShutdownException):
        if args.for_up:
            return 0
        raise
    line.end()
    if missing == []:
        print(
            f"{args.prefix}: ready after {time.monotonic() - since:.1f} s: every stream present",
            flush=True,
        )
        return 0
    print(
        f"{args.prefix}: not ready after {args.timeout:g} s: {missing_text(missing)}",
        file=sys.stderr,
    )
    return 1


def missing_text(missing: list[str] | None) -> str:
    """Everything a wait that ran out was still missing."""
    return "; ".join(missing) if missing else "no supervisor heard (is the graph up?)"
