"""The wire temperature from the drive board's readings (hems_ros.graph.thermal_guard) against
the simulation truth, and the heating cut-off that holds a wire a stuck sensor keeps heating."""

from __future__ import annotations

import math

import pytest

from hems_ros.graph.thermal_guard import ThermalGuard
from hems_ros.graph.unit_driver import UnitDriver
from hems_ros.physics import ActuationUnit, load_params

PARAMS = load_params("ch6_hems_index")
PERIOD = 0.01


def _truth() -> UnitDriver:
    driver = UnitDriver(ActuationUnit(PARAMS), start_time_s=0.0, require_permission=False)
    return driver


def _run(
    seconds: float, duty_of, guard: ThermalGuard | None = None, truth: UnitDriver | None = None
):
    """Drive the truth at ``duty_of(k)`` per 10 ms sample (0 while the guard holds it); the
    truth's peak temperature and the largest |estimate - truth|."""
    truth = truth or _truth()
    peak, worst = -math.inf, 0.0
    for k in range(int(round(seconds / PERIOD))):
        duty = 0.0 if guard is not None and guard.limited else duty_of(k)
        truth.command(duty, k * PERIOD)
        [sample] = truth.advance((k + 1) * PERIOD)
        temperature = truth.unit.state["wire_temperature_c"]
        peak = max(peak, temperature)
        if guard is not None:
            estimate = guard.reading(sample.duty_percent, sample.on_current_a, sample.on_voltage_v)
            worst = max(worst, abs(estimate - temperature))
    return peak, worst


def test_the_estimate_follows_the_wire_through_heating_holding_and_cooling():
    guard = ThermalGuard(PARAMS, cut_c=500.0, resume_c=490.0, period_s=PERIOD)
    # 2 s at full duty, 3 s at 30 %, 5 s off
    peak, worst = _run(10.0, lambda k: 100.0 if k < 200 else (30.0 if k < 500 else 0.0), guard)
    assert peak > 100.0  # the wire transformed: not a trivial run
    assert worst < 0.5  # degC: the board's readings carry the heat the wire took


def test_a_wire_a_stuck_encoder_keeps_heating_is_held_below_the_cut_off():
    # a position loop whose encoder froze sees no motion and asks for 100 % without end
    unguarded, _ = _run(10.0, lambda k: 100.0)
    assert unguarded > 200.0
    guard = ThermalGuard(PARAMS, cut_c=150.0, resume_c=140.0, period_s=PERIOD)
    guarded, _ = _run(10.0, lambda k: 100.0, guard)
    assert 145.0 < guarded < 152.0  # it heats to the cut-off, one sample of overshoot at most
    assert guard.limited or guard.estimate_c > 140.0


def test_the_resistance_pulls_a_model_that_drifted_towards_the_wire():
    """A model 15 degC off in ambient: on heating, the measured resistance moves its estimate
    towards the wire's temperature (eqs. 4.3-4.5), each reading within MAX_CORRECTION_K."""
    truth = UnitDriver(
        ActuationUnit(PARAMS.replace({"ambient_temperature_c": 37.0})),
        start_time_s=0.0,
        require_permission=False,
    )
    drifted = ThermalGuard(PARAMS, cut_c=500.0, resume_c=490.0, period_s=PERIOD)
    off = []
    for k in range(50):  # 0.5 s at 20 %: martensite, warming
        truth.command(20.0, k * PERIOD)
        [sample] = truth.advance((k + 1) * PERIOD)
        estimate = drifted.reading(sample.duty_percent, sample.on_current_a, sample.on_voltage_v)
        off.append(
            (
                truth.unit.state["wire_temperature_c"] - drifted.model.state["wire_temperature_c"],
                truth.unit.state["wire_temperature_c"] - estimate,
            )
        )
    model_error, corrected_error = off[-1]
    assert model_error > 14.0  # the model alone is as far off as its ambient
    assert abs(corrected_error) < 0.3 * model_error  # the wire's own resistance says where it is


def test_resume_must_be_below_the_cut_off():
    with pytest.raises(ValueError, match="must be below the cut-off"):
        ThermalGuard(PARAMS, cut_c=140.0, resume_c=150.0, period_s=PERIOD)
