"""``hems demo``: the main end-to-end job (`make demo`)."""

from __future__ import annotations

import argparse

from hems_ros.cli import ping


def register(subparsers) -> None:
    parser = subparsers.add_parser(
        "demo",
        help="run the end-to-end demonstration (what `make demo` runs)",
        description=(
            "Start a ping_responder node in its own process and exchange hems_msgs "
            "messages with it over Fast DDS (loopback only), checking every answer."
        ),
    )
    ping.add_arguments(parser)
    parser.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    return ping.run(args)
