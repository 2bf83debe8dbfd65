"""argparse types for the numeric options of the ``hems`` verbs.

A bad number stops the command before it starts a node or a simulation, with argparse's
usual ``argument --rate: ...`` message naming the option and the value; float("nan") and
float("inf") parse, so each type also asks for a finite value (a NaN rate had left
``hems replay`` waiting forever for a message due at NaN seconds).
"""

from __future__ import annotations

import argparse
import math
from typing import Callable


def _number(convert: Callable[[str], float], kind: str, test: Callable[[float], bool], requirement: str):
    def parse(text: str):
        try:
            value = convert(text)
        except ValueError:
            raise argparse.ArgumentTypeError(f"{text!r} is not {kind}") from None
        if not (math.isfinite(value) and test(value)):
            raise argparse.ArgumentTypeError(f"{text!r}: must be {requirement}")
        return value

    return parse


finite = _number(float, "a number", lambda v: True, "a finite number")
positive = _number(float, "a number", lambda v: v > 0, "a finite number > 0")
non_negative = _number(float, "a number", lambda v: v >= 0, "a finite number >= 0")
positive_int = _number(int, "a whole number", lambda v: v > 0, "a whole number > 0")
