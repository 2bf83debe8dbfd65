"""``hems record``: record topics of the running graph into an MCAP bag (rosbag2 layout)."""

from __future__ import annotations

import argparse

from hems_ros.bag.selection import DEFAULT_RECORD_REGEX
from hems_ros.cli.numbers import non_negative, positive, positive_int


def register(subparsers) -> None:
    parser = subparsers.add_parser(
        "record",
        help="record topics into an MCAP bag folder (rosbag2 layout)",
        description=(
            "Run a recorder node in this process: it subscribes to every topic named with "
            f"--topic or matching --regex (default {DEFAULT_RECORD_REGEX!r}), found by querying "
            "the graph, and writes the serialized messages as received into "
            "<output>/<output>_0.mcap plus metadata.yaml. Ctrl-C, SIGTERM or --duration "
            "finish the bag; after a crash every flushed chunk stays readable."
        ),
    )
    parser.add_argument(
        "-o", "--output", default="", help="bag folder (default hems_<date>_<time>)"
    )
    parser.add_argument(
        "--topic", action="append", default=[], dest="topics", help="record this topic (repeatable)"
    )
    parser.add_argument(
        "--regex", default=None, help="record topics fully matching this regular expression"
    )
    parser.add_argument(
        "--duration",
        type=non_negative,
        default=0.0,
        help="stop after this many seconds (0: until Ctrl-C)",
    )
    parser.add_argument("--compression", choices=("zstd", "lz4", "none"), default="zstd")
    parser.add_argument(
        "--chunk-size",
        type=positive_int,
        default=262144,
        help="chunk size in bytes (default 256 KiB)",
    )
    parser.add_argument(
        "--flush-period",
        type=positive,
        default=0.5,
        help="seconds between chunk flushes: at most this much is lost on a crash",
    )
    parser.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    from hems_ros.bag.recording import recorder_command
    from hems_ros.nodes import recorder

    command = recorder_command(
        args.output,
        args.topics,
        args.regex,
        args.duration,
        flush_period=args.flush_period,
        chunk_size=args.chunk_size,
        compression=args.compression,
    )
    return recorder.main(["hems record"] + command[command.index("--ros-args") :])
