"""Periodic work on a node's faster tick instead of a timer of its own (plain Python, no ROS).

Every timer of a node in its own process wakes it, and each wake-up of a sleeping process
costs far more CPU here than the work it does (benchmarks/bench_messages.py); a 20 Hz state
or a 50 Hz joint-state message can ride on the 100 Hz tick the node has anyway.
"""

from __future__ import annotations

import math

from hems_ros.graph import names


class Cadence:
    """Due about every ``period_s`` when asked at every tick of ``tick_s``.

    Half a tick of slack absorbs the ticks' jitter, so a period of five ticks fires on every
    fifth tick rather than slipping to the sixth when a tick comes a little early; a period
    shorter than the tick fires on every tick.
    """

    def __init__(self, period_s: float, tick_s: float) -> None:
        self.period_s = period_s
        self.slack_s = 0.5 * min(tick_s, period_s)
        self.next_s = -math.inf

    def due(self, now_s: float) -> bool:
        if now_s < self.next_s:
            return False
        self.next_s = now_s + self.period_s - self.slack_s
        return True


def grid_delay(phase_s: float, period_s: float, now_s: float) -> float:
    """Seconds from ``now_s`` to the next instant ``phase_s`` past a multiple of ``period_s``."""
    return (phase_s - now_s) % period_s


def tick_delay(finger: str, period_s: float, now_s: float) -> float:
    """Seconds from ``now_s`` to the next tick instant of ``finger``'s unit on the clock's grid.

    The two units of a shoulder module tick together, so their wire tensions reach the
    module at once and one wake-up takes both; the three modules' pairs are a third of a
    period apart, so their chains do not all compete for the cores at one instant.
    """
    modules = list(names.MODULES)
    return grid_delay(
        modules.index(names.MODULE_OF[finger]) * period_s / len(modules), period_s, now_s
    )


# Where the supervisor's check sits on the clock's grid (see supervisor_check_delay): 1.2 ms
# after the thumb pair's tick with the units' default 10 ms tick.
SUPERVISOR_PHASE_S = 0.0012


def supervisor_check_delay(period_s: float, now_s: float) -> float:
    """Seconds from ``now_s`` to the supervisor's next check instant on the clock's grid.

    The status sent at a check wakes every unit at once; at a phase left to chance it
    landed on a module pair's tick in some runs and doubled that pair's latency p99. The
    check therefore runs SUPERVISOR_PHASE_S after the first pair's tick, so its status
    (taking the reports first costs about 0.7 ms) goes out after that pair's chain (encoder,
    controller, duty: about 1.2 ms at the median) and the units have handled it before the
    next pair ticks, 3.3 ms after the first (docs/design.md).
    """
    return grid_delay(SUPERVISOR_PHASE_S, period_s, now_s)
