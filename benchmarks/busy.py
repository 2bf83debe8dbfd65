"""The ``--busy`` option of the benchmarks that measure the graph: a pure-Python loop keeps one
core busy at normal priority for the whole run, as a browser, a compiler or a user's own node
would on a two-core machine. Its CPU counts toward no figure, and it dies with the benchmark,
even a killed one, so that no later measurement shares the host with it."""

from __future__ import annotations

import argparse
import subprocess

from hems_ros.rosenv import die_with_parent

LOOP = ["python3", "-c", "while True: pass"]
HELP = 'a busy loop on one core throughout (python3 -c "while True: pass")'


def add_option(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("--busy", action="store_true", help=HELP)


def start(args: argparse.Namespace) -> subprocess.Popen | None:
    """The busy loop if ``--busy`` was given; the caller kills it at the end."""
    return subprocess.Popen(LOOP, preexec_fn=die_with_parent) if args.busy else None
