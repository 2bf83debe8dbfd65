"""Entry point of the ``hems`` command.

Verbs are discovered from the modules of :mod:`hems_ros.cli`: every module that defines
``register(subparsers)`` adds one or more sub-commands, so a new verb is a new file and
this module never needs editing.
"""

from __future__ import annotations

import argparse
import importlib
import os
import pkgutil
import signal
import sys

import hems_ros
import hems_ros.cli as cli_pkg
from hems_ros.rosenv import apply_network_defaults, skip_code_generators


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="hems",
        description="HEMS soft hand exoskeleton digital twin: simulate, control, record.",
    )
    parser.add_argument("--version", action="version", version=f"hems {hems_ros.__version__}")
    subparsers = parser.add_subparsers(dest="verb", metavar="<verb>")
    for info in sorted(pkgutil.iter_modules(cli_pkg.__path__), key=lambda m: m.name):
        if info.name == "main":
            continue
        module = importlib.import_module(f"{cli_pkg.__name__}.{info.name}")
        register = getattr(module, "register", None)
        if register is not None:
            register(subparsers)
    return parser


_SIGNALS: list[int] = []


def _on_sigint(signum, frame) -> None:
    # Python's own reaction, remembered: rclpy's handler, which runs first once a context is
    # up, shuts the context down, and the verb may then stop on that rather than on this
    _SIGNALS.append(signum)
    raise KeyboardInterrupt


def main(argv: list[str] | None = None) -> int:
    apply_network_defaults()
    skip_code_generators()  # a verb that joins the graph starts sooner
    signal.signal(signal.SIGINT, _on_sigint)
    try:
        parser = build_parser()
        from rclpy.executors import ExternalShutdownException
    except KeyboardInterrupt:
        return 130  # Ctrl-C while the verbs and rclpy load: nothing started yet, nothing to say
    args = parser.parse_args(argv)
    if args.verb is None:
        parser.print_help()
        return 2
    try:
        return int(args.func(args) or 0)
    except KeyboardInterrupt:
        print(f"hems {args.verb}: interrupted", file=sys.stderr)
        return 130
    except BrokenPipeError:
        # the reader of stdout went away (``hems ... | head``): nothing left to tell it
        os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
        return 0
    except OSError as error:
        # a folder that cannot be made or a file that cannot be written or read
        print(f"hems {args.verb}: {error}", file=sys.stderr)
        return 1
    except ExternalShutdownException:
        # rclpy's handler shut the context down on a signal; the verb's own cleanup ran
        # on the way out
        if signal.SIGINT in _SIGNALS:
            print(f"hems {args.verb}: interrupted", file=sys.stderr)
            return 130
        print(f"hems {args.verb}: stopped by SIGTERM", file=sys.stderr)
        return 143


if __name__ == "__main__":
    sys.exit(main())
