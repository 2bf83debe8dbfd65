"""Real-time driving of one simulated actuation unit (plain Python, no ROS).

The node calls :meth:`UnitDriver.advance` from a timer with the current clock time; the
driver integrates the physics in fixed 1 ms steps up to that time, so the model runs at
1 kHz of simulated time whatever the timer rate, and returns the encoder samples that fell
due on the way (every ``sample_period_s``, stamped with their own time).

A duty command that answers the latest encoder sample (its measurement stamp) and arrives
before the next sample takes effect from that sample's instant: the driver keeps a snapshot
of the unit at the latest sample and re-integrates from it (on wall-clock time the node
takes commands at its ticks, when the unit has not moved past the sample yet). The HEMS
board computes and applies a duty within microseconds of its sample (the lockstep loop of
the control experiments does the same); over DDS the command comes 1-3 ms later, and
applying it on arrival made the loop's overshoot depend on that transport jitter, so a run
on /clock could not repeat a wall-clock run. A later command (a stalled controller) takes
effect on arrival.

Safety gates on the applied duty, checked at every physics step (re-integration included):
- duty watchdog: no command for ``watchdog_timeout_s`` (three control periods) -> 0 duty,
  flagged, until the next command;
- heating permission from the supervisor (ENABLED only), which also lapses when the
  supervisor's status is older than ``permission_timeout_s`` and never reaches back before
  the status that granted it: the supervisor sends it every 20 ms, so a stopped or killed
  supervisor stops the heating within that timeout, at the physics step where it runs out
  (:attr:`UnitDriver.permission_lapses` counts the lapses a later ENABLED ended);
- an invalid command (non-finite, outside 0-100 %) is rejected and applies 0 duty.
"""

from __future__ import annotations

import math
from collections import deque
from typing import Any, NamedTuple

import numpy as np

from hems_ros.duty import valid_duty
from hems_ros.physics import ActuationUnit, StepResult

MAX_STEPS_PER_ADVANCE = 500  # a stalled process catches up over several ticks, not at once


def _step_end(start_s: float, k: int, dt: float) -> float:
    """Clock time at the end of step ``k``: the same float arithmetic as ``time_s`` before and
    after the step (epoch times leave a quarter microsecond of resolution, enough to move a
    gate's boundary)."""
    return (start_s + (k - 1) * dt) + dt


def _last_step_by(start_s: float, first: int, last: int, dt: float, limit: float) -> int:
    """The last step after ``first`` (at most ``last``) that ends by ``limit``, or ``first``;
    found from an estimate and checked on :func:`_step_end`, as a loop over the steps would."""
    k = min(last, max(first, first + int((limit - _step_end(start_s, first + 1, dt)) / dt) + 1))
    while k < last and _step_end(start_s, k + 1, dt) <= limit:
        k += 1
    while k > first and _step_end(start_s, k, dt) > limit:
        k -= 1
    return k


class Sample(NamedTuple):
    """An encoder sample and the wire tension at the same instant (ActuationUnit.readings), and
    what the drive board measured over the period that ended: the applied duty, the wire's
    current and voltage while on (NaN at 0 %)."""

    time_s: float
    encoder_counts: int
    encoder_position_m: float
    wire_force_n: float
    duty_percent: float
    on_current_a: float
    on_voltage_v: float


class UnitDriver:
    def __init__(
        self,
        unit: ActuationUnit,
        start_time_s: float,
        sample_period_s: float = 0.01,
        watchdog_timeout_s: float = 0.03,
        permission_timeout_s: float = 0.035,
        require_permission: bool = True,
        latency_window_s: float = 60.0,
    ) -> None:
        self.unit = unit
        self.start_time_s = start_time_s
        self.sample_period_s = sample_period_s
        self.watchdog_timeout_s = watchdog_timeout_s
        self.permission_timeout_s = permission_timeout_s
        self.require_permission = require_permission
        self.commanded_duty = 0.0
        self.last_command_s: float | None = None
        self.permission_s: float | None = None
        self.permitted_since_s: float | None = None
        self.permission_lapses = 0
        self.watchdog_tripped = True
        self.applied_duty = 0.0
        self.rejected_commands = 0
        self.commands = 0
        self.missed_periods = 0
        # one latency per duty command, one command per sample period: the window holds the
        # commands of the last latency_window_s, so the statistics describe the graph now,
        # not its start-up (discovery stalls of seconds would otherwise stay in them)
        self.latency_window_s = latency_window_s
        self.latencies_s: deque[float] = deque(
            maxlen=max(1, round(latency_window_s / sample_period_s))
        )
        self.late_commands = 0
        self._samples_taken = 0
        # the latest sample: its clock time, the unit's step count then, and a snapshot of the
        # unit there, taken only when an advance leaves it and stops short of the next sample
        # (on wall-clock time the node advances from tick to tick, sample to sample, and takes
        # commands while the unit is still at the sample: no snapshot and no restore)
        self._sample_time_s: float | None = None
        self.answered_sample_s: float | None = (
            None  # the sample the latest answering command answered
        )
        self._sample_steps = 0
        self._sample_snapshot: tuple[Any, ...] | None = None

    @property
    def last_result(self) -> StepResult | None:
        """Measurements and truth at :attr:`time_s` (None before the first step)."""
        return self.unit.result() if self.unit.time > 0 else None

    @property
    def time_s(self) -> float:
        """Clock time the physics has been integrated to."""
        return self.start_time_s + self.unit.time

    def command(
        self, duty_percent: float, now_s: float, measurement_stamp_s: float | None = None
    ) -> None:
        """Accept a duty command; ValueError (and 0 duty) for a non-finite or out-of-range one.

        Call :meth:`advance` up to ``now_s`` first (needless when :meth:`will_rewind`) and again
        afterwards: a command answering the latest sample rewinds the physics to that sample
        (see the module documentation).
        """
        if not valid_duty(duty_percent):
            self.reject()
            raise ValueError(
                f"duty command {duty_percent!r} % rejected: must be finite and within 0-100 %"
            )
        effective_s = now_s
        if self._answers_latest_sample(measurement_stamp_s):
            assert self._sample_time_s is not None  # _answers_latest_sample checked it
            effective_s = self._sample_time_s
            self.answered_sample_s = self._sample_time_s
            if self.unit.steps != self._sample_steps:  # moved on: the snapshot was taken on leaving
                assert self._sample_snapshot is not None
                self.unit.restore(self._sample_snapshot)
        elif measurement_stamp_s is not None and measurement_stamp_s > 0:
            self.late_commands += 1
        if self.last_command_s is not None:
            gap_periods = round((effective_s - self.last_command_s) / self.sample_period_s)
            self.missed_periods += max(0, gap_periods - 1)
        self.commands += 1
        self.commanded_duty = float(duty_percent)
        self.last_command_s = effective_s
        if measurement_stamp_s is not None and measurement_stamp_s > 0:
            self.latencies_s.append(now_s - measurement_stamp_s)

    @property
    def latest_sample_answered(self) -> bool:
        """A valid command answering the latest encoder sample has come."""
        return self._sample_time_s is not None and self.answered_sample_s == self._sample_time_s

    def reject(self) -> None:
        """A command that cannot be applied: counted, and 0 duty until the next valid one."""
        self.rejected_commands += 1
        self.commanded_duty = 0.0

    def will_rewind(
        self, duty_percent: float, measurement_stamp_s: float | None, now_s: float
    ) -> bool:
        """This command, given at ``now_s``, takes effect from the latest sample: it is valid,
        answers that sample, and the next one does not fall due by ``now_s`` (1 us to spare for
        the rounding of epoch times). Integrating up to ``now_s`` before it is then wasted."""
        return (
            valid_duty(duty_percent)
            and self._answers_latest_sample(measurement_stamp_s)
            and now_s < self._next_sample_due_s() - 1e-6
        )

    def _next_sample_due_s(self) -> float:
        """Clock time of the next encoder sample (a nanosecond early against float rounding)."""
        return self.start_time_s + (self._samples_taken + 1) * self.sample_period_s - 1e-9

    def _answers_latest_sample(self, measurement_stamp_s: float | None) -> bool:
        return (
            measurement_stamp_s is not None
            and self._sample_time_s is not None
            and abs(measurement_stamp_s - self._sample_time_s) < 0.5 * self.unit.dt
        )

    def permit_heating(self, allowed: bool, now_s: float) -> None:
        """Supervisor's word: heating allowed (ENABLED) or not; refreshed by every status."""
        if allowed:
            if self.permission_s is None:
                self.permitted_since_s = now_s
            elif now_s - self.permission_s > self.permission_timeout_s:
                self.permission_lapses += 1  # a late status: the heating paused meanwhile
            self.permission_s = now_s
        else:
            self.permission_s = self.permitted_since_s = None
            self.applied_duty = 0.0

    def permission_lapses_by(self, now_s: float) -> bool:
        """Heating is allowed, but by ``now_s`` the latest status no longer covers it: a status
        is due before the physics may run there with the heating on."""
        return (
            self.require_permission
            and self.permission_s is not None
            and now_s - self.permission_s > self.permission_timeout_s
        )

    def permitted(self, now_s: float) -> bool:
        """The supervisor's ENABLED taken and not lapsed: what the unit reports as its
        permission (the supervisor faults a unit that has not taken its ENABLED)."""
        if not self.require_permission:
            return True
        return (
            self.permission_s is not None
            and self.permitted_since_s is not None
            and self.permitted_since_s <= now_s + 1e-9
            and now_s - self.permission_s <= self.permission_timeout_s
        )

    def gate(self, now_s: float) -> float:
        """The duty the PWM stage applies at ``now_s`` after the safety gates."""
        self.watchdog_tripped = (
            self.last_command_s is None or now_s - self.last_command_s > self.watchdog_timeout_s
        )
        if self.watchdog_tripped or not self.permitted(now_s):
            return 0.0
        return self.commanded_duty

    def advance(self, now_s: float) -> list[Sample]:
        """Integrate up to ``now_s``; return the encoder samples that fell due.

        The gates are checked at every 1 ms step; the steps between a change of the gated
        duty and the next sample go to the physics in one call. Over an advance the watchdog
        trips at most once and the permission holds over one interval of steps, so a gated
        duty that is the same at the first and the last step, and not 0 (or a command of 0 %),
        is the duty of every step between: the steps then go to the physics without a gate
        per step, in the same calls, with the same bits (a node advances 100 times a second,
        and the per-step loop was a fifth of a unit's Python).
        """
        unit, dt, start = self.unit, self.unit.dt, self.start_time_s
        first = unit.steps
        limit = now_s + 1e-9
        last = first + MAX_STEPS_PER_ADVANCE
        end = _last_step_by(start, first, last, dt, limit)
        if end == first:
            return []
        duty = self.gate(_step_end(start, first + 1, dt))
        if duty == self.gate(_step_end(start, end, dt)) and (
            duty != 0.0 or not self.commanded_duty
        ):
            return self._advance_at(duty, first, end, last, limit)
        return self._advance_gated(first, last, limit)

    def _advance_at(
        self, duty: float, first: int, end: int, last: int, limit: float
    ) -> list[Sample]:
        """:meth:`advance` of steps ``first + 1`` to ``end`` at one gated duty."""
        samples: list[Sample] = []
        k, sample_k = first, self._next_sample_step()
        while k < end:
            stop = min(sample_k, end)
            self._integrate(duty, stop - k, sample_k, last, limit)
            k = stop
            if k == sample_k:
                samples.append(self._take_sample(duty))
                sample_k = self._next_sample_step()
        self.applied_duty = duty
        return samples

    def _take_sample(self, duty: float) -> Sample:
        """The encoder sample at the unit's present step, which becomes the latest sample."""
        unit = self.unit
        self._samples_taken += 1
        sample = Sample(self.time_s, *unit.readings(), *self._board(duty))
        self._sample_time_s, self._sample_steps, self._sample_snapshot = (
            self.time_s,
            unit.steps,
            None,
        )
        return sample

    def _advance_gated(self, first: int, last: int, limit: float) -> list[Sample]:
        """:meth:`advance` with the gates checked at every step."""
        samples: list[Sample] = []
        unit, dt, start = self.unit, self.unit.dt, self.start_time_s
        run_duty, run = 0.0, 0
        sample_k = self._next_sample_step()
        for k in range(first + 1, last + 1):
            step_end = _step_end(start, k, dt)
            if step_end > limit:
                break
            duty = self.gate(step_end)
            if run and duty != run_duty:
                self._integrate(run_duty, run, sample_k, last, limit)
                run = 0
            run_duty, run = duty, run + 1
            if k == sample_k:
                self._integrate(run_duty, run, sample_k, last, limit)
                run = 0
                samples.append(self._take_sample(run_duty))
                sample_k = self._next_sample_step()
        if run:
            self._integrate(run_duty, run, sample_k, last, limit)
        if unit.steps > first:
            self.applied_duty = run_duty
        return samples

    def _board(self, duty: float) -> tuple[float, float, float]:
        """(duty %, on-current A, on-voltage V) of the last step, as the drive board
        measures them."""
        if duty <= 0.0:
            return 0.0, math.nan, math.nan
        resistance, mean_current = self.unit.electrical()
        on_current = mean_current / (duty * 0.01)
        return duty, on_current, on_current * resistance

    def _next_sample_step(self) -> int:
        """The step at whose end the next encoder sample falls due."""
        start, dt, due = self.start_time_s, self.unit.dt, self._next_sample_due_s()
        k = self.unit.steps + 1
        while start + k * dt < due:
            k += 1
        return k

    def _integrate(self, duty: float, steps: int, sample_k: int, last: int, limit: float) -> None:
        """``steps`` steps at ``duty`` in an advance that may go to step ``last`` and to the clock
        time ``limit``; leaving the latest sample without reaching the next one (due at step
        ``sample_k``), keep a snapshot of it for a rewind."""
        if (
            self._sample_snapshot is None
            and self.unit.steps == self._sample_steps
            and (sample_k > last or _step_end(self.start_time_s, sample_k, self.unit.dt) > limit)
        ):
            self._sample_snapshot = self.unit.snapshot()
        self.unit.advance(duty=duty, steps=steps)

    def latency_percentiles(self) -> tuple[float, float, float]:
        """(p50, p99, max) of measurement-to-applied latency over the duty commands of the last
        ``latency_window_s``, s (nan before any command)."""
        n = len(self.latencies_s)
        if not n:
            return math.nan, math.nan, math.nan
        # a partial sort in numpy: sorting a 20,000-value window in Python took ~3 ms, a
        # stall of the node's loop once a second (of all nodes in a composed process)
        ranks = [min(n - 1, int(q * n)) for q in (0.5, 0.99)] + [n - 1]
        picked = np.partition(np.fromiter(self.latencies_s, float, n), ranks)[ranks]
        return float(picked[0]), float(picked[1]), float(picked[2])
