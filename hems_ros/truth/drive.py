"""A PWM drive fed by a real supply, and a position loop closed on the truth.

The supply: an open-circuit voltage behind the source's, the cable's and the switch's
resistances, and a droop, a polarisation branch (a battery's or a bench supply's output
stage sagging over seconds under load) whose voltage settles at ``droop_ohm`` times the mean
current with the time constant ``droop_s``. While on, the board limits the current to
``current_limit_a``. The PWM is taken over a period: its switching is far faster than the
wire's heat.

The loop: a PI on the encoder's reading of the contraction, its duty computed every period
from the truth's own motion, so that a run's duty profile is what a controller made of the
rig, not of any model of it.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass

import numpy as np

from hems_ros.truth import rig as rigs


@dataclass(frozen=True)
class Supply:
    """SI units."""

    voltage_v: float = 20.0
    current_limit_a: float = 4.0
    source_ohm: float = 0.0
    cable_ohm: float = 0.0
    switch_ohm: float = 0.0
    droop_ohm: float = 0.0
    droop_s: float = 3.0

    def __post_init__(self) -> None:
        ohms = (self.source_ohm, self.cable_ohm, self.switch_ohm, self.droop_ohm)
        if min(ohms) < 0.0 or min(self.voltage_v, self.current_limit_a, self.droop_s) <= 0.0:
            raise ValueError("supply: resistances must be >= 0, voltage, limit and droop_s > 0")

    def heating(self, share: float, droop_v: float) -> Callable[[float], float]:
        """The wire's mean power at the wire's resistance, on for ``share`` of each period."""
        return lambda wire_ohm: share * self.on_current_a(wire_ohm, droop_v) ** 2 * wire_ohm

    def on_current_a(self, wire_ohm: float, droop_v: float) -> float:
        """The current while the switch is on, with the droop's voltage ``droop_v``."""
        series = self.source_ohm + self.cable_ohm + self.switch_ohm
        return min(self.current_limit_a, max(self.voltage_v - droop_v, 0.0) / (wire_ohm + series))


@dataclass(frozen=True)
class PositionLoop:
    """A PI on the contraction, duty in % (anti-windup: it integrates while unsaturated)."""

    kp_per_mm: float = 8.0
    ki_per_mm_s: float = 6.0
    period_s: float = 0.01
    encoder_m: float = 1e-6  # the reading the loop acts on is quantised to this


def simulate_closed_loop(
    rig: rigs.WireRig,
    supply: Supply,
    targets: Sequence[tuple[float, float, float]],
    duration_s: float,
    loop: PositionLoop = PositionLoop(),
) -> rigs.RigRun:
    """The rig from its cold state for ``duration_s``, driven by ``loop`` through ``supply``,
    sampled every loop period.

    ``targets``: (start s, end s, contraction m); the duty is 0 outside them."""
    state = rig.cold_state()
    network = rig.network()
    rest_m = float(state[1])
    decay = math.exp(-loop.period_s / supply.droop_s)
    integral = droop_v = 0.0
    rows, duties = [], []
    steps = round(duration_s / loop.period_s)
    for k in range(steps + 1):
        t = k * loop.period_s
        target = next((x for start, end, x in targets if start <= t < end), None)
        duty = 0.0
        if target is None:
            integral = 0.0
        else:
            measured = loop.encoder_m * round((rest_m - state[1]) / loop.encoder_m)
            error_mm = (target - measured) * 1e3
            step_integral = integral + error_mm * loop.period_s
            raw = loop.kp_per_mm * error_mm + loop.ki_per_mm_s * step_integral
            duty = min(max(raw, 0.0), 100.0)
            if duty == raw:
                integral = step_integral
        share = duty / 100.0
        on_a = supply.on_current_a(rigs.resistance_ohm(rig, rest_m, state), droop_v)
        rows.append((t, share * on_a, *state))
        duties.append(duty)
        if k == steps:
            break
        _, states = rigs.integrate(
            rig,
            network,
            rest_m,
            state,
            t,
            np.array([t + loop.period_s]),
            supply.heating(share, droop_v),
        )
        state = states[-1]
        settled = supply.droop_ohm * share * on_a
        droop_v = settled + (droop_v - settled) * decay
    return rigs.sampled(rig, rest_m, np.array(rows), np.array(duties))
