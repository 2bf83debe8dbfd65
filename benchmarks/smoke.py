"""The ``--smoke`` option of every benchmark: the same code paths in seconds, no floors.

`make test` runs each benchmark with it (tests/foundation/test_benchmarks.py), so a change
that breaks a benchmark fails there instead of at the next `make bench`. A smoke run still
prints its table, but its numbers measure nothing.
"""

from __future__ import annotations

import argparse

HELP = "a run of seconds through the same code: shorter durations and counts, no floors"


def parse_args(parser: argparse.ArgumentParser, **smoke_defaults) -> argparse.Namespace:
    """The command line with ``--smoke`` added; under ``--smoke`` the options the command line
    leaves out take ``smoke_defaults`` instead of their defaults."""
    parser.add_argument("--smoke", action="store_true", help=HELP)
    args = parser.parse_args()
    if args.smoke and smoke_defaults:
        parser.set_defaults(**smoke_defaults)
        args = parser.parse_args()
    return args
