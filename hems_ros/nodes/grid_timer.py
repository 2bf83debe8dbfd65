"""A wall-clock timer whose calls fall at a fixed phase of the clock's grid."""

from __future__ import annotations

import time

from hems_ros.graph.cadence import grid_delay
from hems_ros.nodes.clock_time import seconds

PHASE_TOLERANCE_S = 0.0005
PHASE_ATTEMPTS = 100


def create_grid_timer(node, period_s: float, phase_s: float, callback):
    """A timer of ``node`` calling ``callback`` every ``period_s`` at ``phase_s`` past the
    multiples of ``period_s`` on the node's (wall) clock (:func:`grid_delay`).

    A timer keeps the phase of its creation; while the graph starts, sixteen processes load
    at once and a sleep up to the phase may end late, so a timer more than
    PHASE_TOLERANCE_S off is made again (at most PHASE_ATTEMPTS times, then kept)."""
    for _ in range(PHASE_ATTEMPTS):
        time.sleep(grid_delay(phase_s, period_s, seconds(node)))
        timer = node.create_timer(period_s, callback)
        off = grid_delay(phase_s, period_s, seconds(node) + timer.time_until_next_call() * 1e-9)
        if min(off, period_s - off) <= PHASE_TOLERANCE_S:
            return timer
        node.destroy_timer(timer)
    return node.create_timer(period_s, callback)
