"""Declaring and validating node parameters.

Every parameter is declared with a description; values are checked at start-up (a bad one
raises ``ValueError`` naming the parameter, which stops the node with exit code 2) and on
every later ``set_parameters`` call (rejected with the same message, node keeps running).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

from rcl_interfaces.msg import ParameterDescriptor, SetParametersResult
from rclpy.exceptions import InvalidParameterTypeException
from rclpy.node import Node


@dataclass(frozen=True)
class Spec:
    name: str
    default: Any
    description: str
    check: Callable[[Any], str | None] | None = None  # returns an error text or None
    read_only: bool = False


def positive(value: Any) -> str | None:
    if (
        isinstance(value, bool)
        or not isinstance(value, (int, float))
        or not math.isfinite(value)
        or value <= 0
    ):
        return "must be a finite number > 0"
    return None


def within(low: float, high: float, unit: str = "s") -> Callable[[Any], str | None]:
    """A number from ``low`` to ``high``: a period or window the node turns into timers, clock
    stamps or buffer sizes, which a value of 1e308 (or 1e-300) would overflow."""

    def check(value: Any) -> str | None:
        problem = positive(value)
        if problem is None and not low <= value <= high:
            problem = f"must be from {low:g} to {high:g} {unit}".rstrip()
        return problem

    return check


#: a period of a node's timers, s (a microsecond to a minute)
PERIOD_LIMIT = within(1e-6, 60.0)
#: a time window a node keeps, s (up to a day)
WINDOW_LIMIT = within(1e-6, 86400.0)


def non_negative(value: Any) -> str | None:
    if (
        isinstance(value, bool)
        or not isinstance(value, (int, float))
        or not math.isfinite(value)
        or value < 0
    ):
        return "must be a finite number >= 0"
    return None


def one_of(*choices: str) -> Callable[[Any], str | None]:
    def check(value: Any) -> str | None:
        return None if value in choices else f"must be one of {', '.join(choices)}"

    return check


def declare(node: Node, specs: list[Spec]) -> dict[str, Any]:
    """Declare, validate and return the parameters; reject invalid later changes.

    The returned dict follows every accepted change (``ros2 param set``): a node reads a
    parameter it lets change at run time from it, at the cost of a dict lookup, where
    ``get_parameter`` builds a Parameter object at every call."""
    by_name = {spec.name: spec for spec in specs}
    values = {}
    for spec in specs:
        descriptor = ParameterDescriptor(description=spec.description, read_only=spec.read_only)
        try:
            values[spec.name] = node.declare_parameter(spec.name, spec.default, descriptor).value
        except InvalidParameterTypeException as error:
            # `-p physics_dt_s:=1` is an integer to ROS; say so instead of a traceback
            hint = (
                " (write a decimal point for a floating-point value, e.g. 1.0)"
                if isinstance(spec.default, float)
                else ""
            )
            raise ValueError(f"parameter '{spec.name}': wrong type: {error}{hint}") from None
        problem = _error(spec, values[spec.name])
        if problem:
            raise ValueError(problem)

    def on_set(parameters) -> SetParametersResult:
        for parameter in parameters:
            spec = by_name.get(parameter.name)
            error = _error(spec, parameter.value) if spec else None
            if error:
                return SetParametersResult(successful=False, reason=error)
        return SetParametersResult(successful=True)

    def after_set(parameters) -> None:
        for parameter in parameters:
            if parameter.name in values:
                values[parameter.name] = parameter.value

    node.add_on_set_parameters_callback(on_set)
    node.add_post_set_parameters_callback(after_set)
    return values


def _error(spec: Spec, value: Any) -> str | None:
    if spec.check is None:
        return None
    problem = spec.check(value)
    return f"parameter '{spec.name}' = {value!r}: {problem}" if problem else None
