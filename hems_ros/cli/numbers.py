"""argparse types for the numeric options of the ``hems`` verbs.

A bad number stops the command before it starts a node or a simulation, with argparse's
usual ``argument --rate: ...`` message naming the option and the value. The range checks
are the node parameters' (:mod:`hems_ros.ros.params`), so a value reads the same on the
command line as in a params file; float("nan") and float("inf") parse, which is why each
asks for a finite value (a NaN rate had left ``hems replay`` waiting forever for a message
due at NaN seconds).
"""

from __future__ import annotations

import argparse
import math
from typing import Callable

from hems_ros.ros import params


def _number(convert: Callable[[str], float], kind: str, check: Callable[[float], str | None]):
    def parse(text: str):
        try:
            value = convert(text)
        except ValueError:
            raise argparse.ArgumentTypeError(f"{text!r} is not {kind}") from None
        error = check(value)
        if error:
            raise argparse.ArgumentTypeError(f"{text!r}: {error}")
        return value

    return parse


finite = _number(
    float, "a number", lambda v: None if math.isfinite(v) else "must be a finite number"
)
positive = _number(float, "a number", params.positive)
non_negative = _number(float, "a number", params.non_negative)
positive_int = _number(
    int, "a whole number", lambda v: None if v > 0 else "must be a whole number > 0"
)
non_negative_int = _number(
    int, "a whole number", lambda v: None if v >= 0 else "must be a whole number >= 0"
)


def positive_or_max(text: str) -> float:
    """A number > 0, or ``max`` (0.0: no cap; the lockstep clock's ``--rate max``)."""
    return 0.0 if text == "max" else positive(text)


def namespace(text: str) -> str:
    """argparse type of ``--namespace``: a graph namespace, made absolute."""
    from hems_ros.graph.names import check_namespace

    try:
        return check_namespace(text)
    except ValueError as error:
        raise argparse.ArgumentTypeError(str(error)) from None


def add_namespace_argument(parser: argparse.ArgumentParser) -> None:
    parser.add_argument(
        "--namespace",
        type=namespace,
        default="/hems",
        help="the graph's namespace (default /hems): two hands in one ROS domain run "
        "as, e.g., hems up --namespace left and hems up --namespace right",
    )
