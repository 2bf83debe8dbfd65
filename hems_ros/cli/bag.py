"""``hems bag info <bag>``: what a bag holds, and how much of a damaged one can be read."""

from __future__ import annotations

import argparse
import sys
import warnings
from datetime import datetime, timezone
from pathlib import Path


def register(subparsers) -> None:
    parser = subparsers.add_parser("bag", help="inspect bags", description="Inspect MCAP bags.")
    verbs = parser.add_subparsers(dest="bag_verb", metavar="<command>", required=True)
    info = verbs.add_parser(
        "info",
        help="message counts per topic, duration, recovery report",
        description=(
            "Scan a bag folder or .mcap file and print per-topic message counts and "
            "types, the time range, and for an unfinished or cut file how many "
            "messages were recovered and where reading stopped. Exit code 2 if the "
            "file is not a readable MCAP file."
        ),
    )
    info.add_argument("bag", help="bag folder or .mcap file")
    info.set_defaults(func=run_info)
    export = verbs.add_parser(
        "export",
        help="one CSV file per topic (spreadsheets, MATLAB, plotting tools)",
        description=(
            "Decode a bag and write one CSV file per topic: time_s (log time since the "
            "start of the bag, s), log_time_ns, stamp_s (header stamp, s) and every "
            "field under its dotted name in the topic's SI units; booleans as 1/0, "
            "variable-length sequences joined by ';', nested messages as JSON. An "
            "unfinished or cut bag is exported as far as it can be read, and said so. "
            "Exit code 2 if the file is not a readable MCAP file."
        ),
    )
    export.add_argument("bag", help="bag folder or .mcap file")
    export.add_argument(
        "-o",
        "--output",
        default=None,
        help="folder for the CSV files (default: <bag>_csv beside the bag)",
    )
    export.add_argument(
        "--topics", nargs="+", default=None, metavar="TOPIC", help="only these topics"
    )
    export.add_argument(
        "--regex",
        default=None,
        help="only topics this regular expression matches in full, e.g. '/hems/index/.*'",
    )
    export.set_defaults(func=run_export)


def format_info(info) -> str:
    lines = [f"bag: {info.path}"]
    lines += [f"file: {f}" for f in info.files]
    start, end = info.start_ns, info.end_ns
    if info.message_count:
        begin = datetime.fromtimestamp(start * 1e-9, tz=timezone.utc).isoformat(
            timespec="milliseconds"
        )
        lines.append(f"start: {begin} ({start * 1e-9:.6f} s)")
    lines.append(f"duration: {(end - start) * 1e-9:.3f} s")
    lines.append(f"messages: {info.message_count}")
    width = max((len(t) for t in info.topics), default=5)
    for topic, entry in sorted(info.topics.items()):
        lines.append(f"  {topic:<{width}}  {entry.count:>9}  {entry.type}")
    for report in info.reports:
        lines.append(
            ("status: " if report.complete and not report.skipped else "RECOVERED: ")
            + report.describe()
        )
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


def default_export_dir(bag: str) -> Path:
    """``<bag folder>_csv`` (or ``<file stem>_csv``) beside the bag."""
    path = Path(bag).resolve()
    stem = path.stem if path.suffix == ".mcap" else path.name
    return path.parent / f"{stem}_csv"


def run_export(args: argparse.Namespace) -> int:
    from hems_ros.bag import BagFormatError, BagWarning, load_bag
    from hems_ros.bag.export import export_csv

    out_dir = Path(args.output) if args.output else default_export_dir(args.bag)
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", BagWarning)
            bag = load_bag(args.bag, topics=args.topics, regex=args.regex)
    except (
        BagFormatError,
        FileNotFoundError,
        IsADirectoryError,
        PermissionError,
        ValueError,
    ) as error:
        print(f"hems bag export: {error}", file=sys.stderr)
        return 2
    for report in bag.reports:
        if not (report.complete and not report.skipped):
            print(f"RECOVERED: {report.describe()}", file=sys.stderr)
    for warning in bag.warnings:
        print(f"warning: {warning}", file=sys.stderr)
    if not bag.topics:
        print(f"hems bag export: no messages on the selected topics in {args.bag}", file=sys.stderr)
        return 1
    written = export_csv(
        bag, out_dir, progress=lambda e: print(f"{e.path}  {e.rows} rows, {e.columns} columns")
    )
    print(f"wrote {len(written)} CSV files to {out_dir}")
    return 0
