"""Timers on the wall clock's grid (hems_ros.graph.cadence): a node's periodic work at a
chosen phase of the period, so the graph's processes take turns on the cores."""

from __future__ import annotations

import time
from collections.abc import Callable
from typing import TYPE_CHECKING, Any

from hems_ros.ros.clock_time import seconds

if TYPE_CHECKING:
    from rclpy.node import Node
    from rclpy.timer import Timer

PHASE_TOLERANCE_S = 0.0005
ATTEMPTS = 100


def until_next_call_s(timer: Timer) -> float:
    """Seconds to the next call of ``timer``, which runs (rclpy gives none for a cancelled one)."""
    until_ns = timer.time_until_next_call()
    if until_ns is None:
        raise ValueError("the timer is cancelled")
    return until_ns * 1e-9


def create_grid_timer(
    node: Node,
    period_s: float,
    delay: Callable[[float], float],
    callback: Callable[[], Any],
) -> Timer:
    """A timer of ``period_s`` whose calls fall ``delay(now_s)`` seconds after now.

    A timer keeps the phase of its creation; while the graph starts, sixteen processes load
    at once and a sleep up to the phase may end late, so a timer more than
    PHASE_TOLERANCE_S off is made again. On sim time the grid means nothing: a plain timer.
    """
    for _ in range(ATTEMPTS if not node.get_parameter("use_sim_time").value else 0):
        time.sleep(delay(seconds(node)))
        timer = node.create_timer(period_s, callback)
        off = delay(seconds(node) + until_next_call_s(timer))
        if min(off, period_s - off) <= PHASE_TOLERANCE_S:
            return timer
        node.destroy_timer(timer)
    return node.create_timer(period_s, callback)
