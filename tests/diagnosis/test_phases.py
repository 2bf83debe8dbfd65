"""Phases and cycles of measured runs (hems_ros.diagnosis.phases) on synthetic motions whose
phases are known by construction."""

from __future__ import annotations

import numpy as np
import pytest

from hems_ros.diagnosis import phases
from hems_ros.diagnosis.candidates import COOLING, HEATING, HOLD, PHASES, REST, TRANSFORMATION
from hems_ros.diagnosis.runs import TimeSeriesRun

DT = 0.01
PERIOD = 8.0
STROKE = 10e-3
# one actuation, seconds from the drive coming on: the wire warms for 0.4 s, contracts for
# 0.6 s, is held until the drive goes off at 2 s, extends for 3 s and rests until the next
PHASE_TIMES = (
    (HEATING, 0.0, 0.4),
    (TRANSFORMATION, 0.4, 1.0),
    (HOLD, 1.0, 2.0),
    (COOLING, 2.0, 5.0),
    (REST, 5.0, PERIOD),
)


def _pulses(n: int, lead: float, floor: float = 0.0, duty_on: float = 100.0) -> TimeSeriesRun:
    """``n`` actuations one PERIOD apart after ``lead`` s of rest; after the first the wire
    extends only down to ``floor`` (a share of the stroke)."""
    t = np.arange(int(round((lead + n * PERIOD) / DT))) * DT
    duty, x = np.zeros(t.size), np.zeros(t.size)
    for i in range(n):
        on = lead + i * PERIOD
        s = t - on
        here = (s >= -1e-9) & (s < PERIOD - 1e-9)
        duty[here & (s < 2.0 - 1e-9)] = duty_on
        low = 0.0 if i == 0 else floor * STROKE
        up = np.clip((s - 0.4) / 0.6, 0.0, 1.0)
        down = np.clip((s - 2.0) / 3.0, 0.0, 1.0)
        x[here] = (low + (STROKE - low) * up - (STROKE - floor * STROKE) * down)[here]
    return TimeSeriesRun("pulses", "synthetic", "driven", t, "duty", duty, {"position": x})


def _starts(run: TimeSeriesRun, seg: phases.Segmentation) -> list[float]:
    return [round(float(run.time[k]), 2) for k in np.flatnonzero(np.diff(seg.cycle)) + 1]


def test_pulse_run_phases_sit_where_they_were_made() -> None:
    run = _pulses(5, lead=0.5)
    seg = phases.segment(run)
    assert seg.n_cycles == 5
    assert _starts(run, seg) == [8.5, 16.5, 24.5, 32.5]
    s = (run.time - 0.5) % PERIOD
    for name, a, b in PHASE_TIMES:
        # away from the edges the 0.1 s smoothing blurs
        inside = (s > a + 0.1) & (s < b - 0.1) & (run.time > 0.5)
        assert inside.sum() > 5 * (b - a - 0.25) / DT
        labels = seg.phase[inside]
        assert np.all(labels == PHASES.index(name)), (name, np.bincount(labels, minlength=5))
    # each phase takes its share of the run to within the smoothing's 0.05 s per edge
    counts = np.bincount(seg.phase, minlength=5) * DT
    expected = {
        HEATING: 5 * 0.4,
        TRANSFORMATION: 5 * 0.6,
        HOLD: 5 * 1.0,
        COOLING: 5 * 3.0,
        REST: 5 * 3.0 + 0.5,
    }
    for name, seconds in expected.items():
        assert counts[PHASES.index(name)] == pytest.approx(seconds, abs=5 * 0.12), name
    assert seg.mask(HOLD).sum() == np.sum(seg.phase == PHASES.index(HOLD))


def test_cycles_hold_every_sample_and_split_at_the_drive_onsets() -> None:
    run = _pulses(4, lead=1.0, duty_on=60.0)
    seg = phases.segment(run)
    assert seg.cycle.size == run.n_samples
    assert np.all(np.diff(seg.cycle) >= 0)
    assert np.bincount(seg.cycle).tolist() == [
        900,
        800,
        800,
        800,
    ]  # the lead-in belongs to the first


def test_wire_that_never_returns_to_rest_falls_back_to_drive_only_cycles() -> None:
    # after the first actuation the wire stays above 40 % of its stroke: never near rest
    run = _pulses(5, lead=2.0, floor=0.4)
    seg = phases.segment(run)
    near_rest_starts = phases._cycle_starts(
        run.time, run.drive_values > 0.5, run.outputs["position"] <= 0.1 * STROKE, phases.MIN_OFF_S
    )
    assert len(near_rest_starts) == 1 < phases.MIN_CYCLES
    assert seg.n_cycles == 5
    assert _starts(run, seg) == [10.0, 18.0, 26.0, 34.0]
    # the drive is on with the wire still contracted: holding, not heating from rest
    s = (run.time - 2.0) % PERIOD
    later = (run.time > 2.0 + PERIOD) & (s > 0.1) & (s < 0.3)
    assert np.all(seg.phase[later] == PHASES.index(HOLD))


def test_drive_only_cycles_need_a_second_off() -> None:
    # drive off for only 0.5 s between pulses: without returns to rest there are no cycles
    t = np.arange(2000) * DT
    duty = np.where((t % 2.5) < 2.0, 100.0, 0.0)
    x = np.where(t < 0.5, 0.0, 8e-3 + 1e-3 * np.sin(t))
    run = TimeSeriesRun("busy", "synthetic", "driven", t, "duty", duty, {"position": x})
    assert phases.segment(run).n_cycles == 1


@pytest.mark.parametrize("lead, floor", [(0.5, 0.4), (0.0, 0.0)])
def test_a_short_lead_in_does_not_merge_the_first_two_cycles(lead: float, floor: float) -> None:
    run = _pulses(5, lead=lead, floor=floor)
    assert phases.segment(run).n_cycles == 5


def _thermal(temps: np.ndarray, strain: np.ndarray) -> TimeSeriesRun:
    t = np.arange(temps.size) * 1.0
    return TimeSeriesRun(
        "tc",
        "synthetic",
        "thermal_cycle",
        t,
        "temperature",
        temps,
        {"strain": strain},
        stress_pa=150e6,
    )


def _three_cycles() -> tuple[np.ndarray, np.ndarray]:
    one = np.r_[np.arange(40.0, 140.0), np.arange(140.0, 40.0, -1.0)]
    temps = np.r_[np.tile(one, 3), 40.0]
    # a transformation 105-120 degC on heating, 95-80 on cooling
    rising = np.r_[np.diff(temps) > 0, False]
    xi = np.where(
        rising, np.clip((120.0 - temps) / 15.0, 0, 1), np.clip((95.0 - temps) / 15.0, 0, 1)
    )
    # the cooling branch starts austenite, the heating branch martensite
    return temps, -0.04 * (1.0 - xi)


def test_thermal_cycles_split_at_temperature_minima() -> None:
    temps, strain = _three_cycles()
    run = _thermal(temps, strain)
    seg = phases.segment(run)
    assert seg.n_cycles == 3
    assert [int(k) for k in np.flatnonzero(np.diff(seg.cycle)) + 1] == [200, 400]
    assert np.all(temps[[200, 400]] == 40.0)
    heating = np.r_[np.diff(temps) > 0, False]
    transforming = ((temps > 106) & (temps < 119) & heating) | (
        (temps > 81) & (temps < 94) & ~heating
    )
    inner = (temps > 40.0) & (temps < 140.0)  # the turning points have no direction
    quiet_heat = heating & inner & ((temps < 100) | (temps > 125))
    quiet_cool = ~heating & inner & ((temps < 75) | (temps > 100))
    assert np.all(seg.phase[transforming] == PHASES.index(TRANSFORMATION))
    assert np.all(seg.phase[quiet_heat] == PHASES.index(HEATING))
    assert np.all(seg.phase[quiet_cool] == PHASES.index(COOLING))
    assert quiet_heat.sum() == quiet_cool.sum() == 3 * 73


def test_thermal_cycles_of_a_noisy_thermometer() -> None:
    # 3 degC/min logged at 1 Hz: 0.05 degC a sample, as much as the thermometer's noise
    one = np.r_[np.linspace(40.0, 140.0, 2001)[:-1], np.linspace(140.0, 40.0, 2001)[:-1]]
    temps = np.r_[np.tile(one, 3), 40.0]
    noisy = temps + np.random.default_rng(0).normal(0.0, 0.05, temps.size)
    strain = -0.04 * (temps > 110.0)
    assert phases.segment(_thermal(temps, strain)).n_cycles == 3
    assert phases.segment(_thermal(noisy, strain)).n_cycles == 3


@pytest.mark.parametrize(
    "n, select, test",
    [
        (0, [], []),
        (2, [], []),
        (3, [1], []),
        (6, [1, 4], []),
        (8, [1, 4, 7], [2, 5]),
        (9, [1, 4, 7], [2, 5, 8]),
    ],
)
def test_cycle_roles(n: int, select: list[int], test: list[int]) -> None:
    assert phases.cycle_roles(n) == (select, test)


def test_motion_prefers_position_then_strain_then_force() -> None:
    t = np.arange(30) * DT
    base = dict(
        name="m", source="s", kind="driven", time=t, drive="duty", drive_values=np.zeros(30)
    )
    x, e, f = np.linspace(0, 1, 30), np.linspace(0, -2, 30), np.linspace(5, 6, 30)

    def motion(**outputs) -> np.ndarray:
        return phases.motion(TimeSeriesRun(**base, outputs=outputs))

    np.testing.assert_array_equal(motion(wire_force=f, strain=e, position=x), x)
    np.testing.assert_array_equal(motion(wire_force=f, strain=e), -e)  # contraction positive
    np.testing.assert_array_equal(motion(wire_force=f), f)
    with pytest.raises(ValueError, match="no output to segment"):
        motion()
