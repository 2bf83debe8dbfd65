"""Timers on the wall clock's grid (hems_ros.graph.cadence): a node's periodic work at a
chosen phase of the period, so the graph's processes take turns on the cores."""

from __future__ import annotations

import time

from hems_ros.ros.clock_time import seconds

PHASE_TOLERANCE_S = 0.0005
ATTEMPTS = 100


def create_grid_timer(node, period_s: float, delay, callback):
    """A timer of ``period_s`` whose calls fall ``delay(now_s)`` seconds after now.

    A timer keeps the phase of its creation; while the graph starts, sixteen processes load
    at once and a sleep up to the phase may end late, so a timer more than
    PHASE_TOLERANCE_S off is made again. On sim time the grid means nothing: a plain timer.
    """
    for _ in range(ATTEMPTS if not node.get_parameter("use_sim_time").value else 0):
        time.sleep(delay(seconds(node)))
        timer = node.create_timer(period_s, callback)
        off = delay(seconds(node) + timer.time_until_next_call() * 1e-9)
        if min(off, period_s - off) <= PHASE_TOLERANCE_S:
            return timer
        node.destroy_timer(timer)
    return node.create_timer(period_s, callback)
