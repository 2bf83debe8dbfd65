"""``hems bag info <bag>``: what a bag holds, and how much of a damaged one can be read."""

from __future__ import annotations

import argparse
import sys
import warnings
from datetime import datetime, timezone


def register(subparsers) -> None:
    parser = subparsers.add_parser("bag", help="inspect bags", description="Inspect MCAP bags.")
    verbs = parser.add_subparsers(dest="bag_verb", metavar="<command>", required=True)
    info = verbs.add_parser(
        "info", help="message counts per topic, duration, recovery report",
        description=("Scan a bag folder or .mcap file and print per-topic message counts and "
                     "types, the time range, and for an unfinished or cut file how many "
                     "messages were recovered and where reading stopped. Exit code 2 if the "
                     "file is not a readable MCAP file."))
    info.add_argument("bag", help="bag folder or .mcap file")
    info.set_defaults(func=run_info)


def format_info(info) -> str:
    lines = [f"bag: {info.path}"]
    lines += [f"file: {f}" for f in info.files]
    start, end = info.start_ns, info.end_ns
    if info.message_count:
        begin = datetime.fromtimestamp(start * 1e-9, tz=timezone.utc).isoformat(timespec="milliseconds")
        lines.append(f"start: {begin} ({start * 1e-9:.6f} s)")
    lines.append(f"duration: {(end - start) * 1e-9:.3f} s")
    lines.append(f"messages: {info.message_count}")
    width = max((len(t) for t in info.topics), default=5)
    for topic, entry in sorted(info.topics.items()):
        lines.append(f"  {topic:<{width}}  {entry.count:>9}  {entry.type}")
    for report in info.reports:
        lines.append(("status: " if report.complete and not report.skipped else "RECOVERED: ")
                     + report.describe())
    lines += [f"warning: {w}" for w in info.warnings]
    return "\n".join(lines)


def run_info(args: argparse.Namespace) -> int:
    from hems_ros.bag import BagFormatError, BagWarning, bag_info

    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", BagWarning)
            info = bag_info(args.bag)
    except (BagFormatError, FileNotFoundError, IsADirectoryError, PermissionError) as error:
        print(f"hems bag info: {error}", file=sys.stderr)
        return 2
    print(format_info(info))
    return 0
