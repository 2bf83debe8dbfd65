"""The finger controller's core without DDS: the duty is 0 unless the supervisor enabled
the finger and the other mode's reading is fresh and finite on the unit's stamps; invalid
setpoints are counted and leave the last valid one; a mode switch takes that mode's gains
and feedback."""

from __future__ import annotations

import math

import pytest

from hems_ros.control import make_controller, mode_gains
from hems_ros.graph.finger_loop import FingerLoop, lag_ns
from hems_ros.graph.setpoints import SetpointError, SetpointLimits
from hems_ros.graph.thermal_guard import ThermalGuard
from hems_ros.physics import load_params

MS = 1_000_000  # ns


def stamp(ms: int) -> tuple[int, int]:
    return divmod(ms * MS, 1_000_000_000)


@pytest.fixture
def loop() -> FingerLoop:
    gains = {mode: mode_gains("bpid", mode) for mode in ("position", "force")}
    return FingerLoop(
        make_controller("bpid", "position", gains["position"]),
        gains,
        SetpointLimits(),
        pulley_ratio=2.0,
        feedback_lag_s=0.025,
        guard=ThermalGuard(load_params("ch6_hems_index"), 150.0, 140.0, 0.01),
    )


def _sample(loop: FingerLoop, ms: int, position_m: float, force_n: float = 10.0) -> float:
    """A unit's sample: force then encoder at the same stamp; the duty of the step."""
    loop.reading("force", force_n, stamp(ms))
    assert loop.reading("position", position_m, stamp(ms))  # the feedback: a step is due
    return loop.step(loop.enabled and loop.other_fresh(stamp(ms)))


def test_stamps_lag_across_a_second():
    assert lag_ns((2, 5_000_000), (1, 995_000_000)) == 10 * MS


def test_no_duty_until_the_supervisor_enables_then_the_controller_heats(loop):
    loop.set_point("position", 0.02)
    assert _sample(loop, 10, 0.0) == 0.0
    loop.supervisor(True)
    assert _sample(loop, 20, 0.0) > 0.0
    loop.supervisor(False)
    assert _sample(loop, 30, 0.0) == 0.0


def test_a_stale_or_failed_force_reading_holds_the_duty_at_zero(loop):
    loop.set_point("position", 0.02)
    loop.supervisor(True)
    loop.reading("force", 10.0, stamp(100))
    assert not loop.other_fresh(stamp(130))  # 30 ms older than the encoder's sample
    assert loop.other_fresh(stamp(125))
    loop.reading("position", 0.0, stamp(130))
    assert loop.step(loop.other_fresh(stamp(130))) == 0.0
    loop.reading("force", math.nan, stamp(130))
    assert not loop.other_fresh(stamp(130))  # a failed sensor says nothing of over-force


def test_an_invalid_setpoint_is_counted_and_the_last_valid_one_kept(loop):
    loop.set_point("position", 0.02)
    for mode, value in (("position", 1.0), ("force", math.inf), ("speed", 1.0)):
        with pytest.raises(SetpointError):
            loop.set_point(mode, value)
    assert loop.rejected == 3 and "speed" in loop.last_rejection
    assert (loop.setpoint.mode, loop.setpoint.value) == ("position", 0.02)


def test_a_switch_to_force_mode_takes_its_gains_and_feeds_back_on_force(loop):
    loop.set_point("position", 0.02)
    loop.supervisor(True)
    for k in range(1, 5):
        _sample(loop, 10 * k, 0.001 * k, force_n=20.0)
    loop.set_point("force", 12.0)
    assert loop.controller.mode == "force" and loop.other_mode == "position"
    assert loop.controller.gains == loop.gains["force"]
    loop.reading("position", 0.005, stamp(50))
    assert not loop.reading("position", 0.005, stamp(50))  # the encoder is not the feedback now
    assert loop.reading("force", 22.0, stamp(50))
    assert loop.step(loop.other_fresh(stamp(50))) >= 0.0 and not loop.controller.fault
    # the tendon side of the 2x pulley: 22 N on the wire is 11 N on the tendon
    assert loop.tendon_measurement() == pytest.approx(11.0)


def test_the_status_key_changes_with_mode_setpoint_permission_and_fault(loop):
    keys = {loop.status_key()}
    loop.set_point("position", 0.01)
    keys.add(loop.status_key())
    loop.supervisor(True)
    keys.add(loop.status_key())
    loop.reading("force", 10.0, stamp(10))
    loop.reading("position", math.nan, stamp(10))
    loop.step(True)  # a non-finite measurement trips the controller
    keys.add(loop.status_key())
    assert len(keys) == 4 and loop.controller.fault and loop.duty == 0.0


def test_the_status_reports_tendon_side_setpoint_and_wire_side_readings(loop):
    before = loop.status_fields()
    assert math.isnan(before["measurement"]) and math.isnan(before["wire_position"])
    assert before["encoder_stamp_sec"] == 0 and before["fault"] == ""
    loop.set_point("position", 0.02)
    loop.supervisor(True)
    duty = _sample(loop, 1010, 0.004, force_n=12.0)
    status = loop.status_fields()
    # 4 mm of wire is 8 mm of tendon through the 2x pulley; the error is tendon side too
    assert status["measurement"] == pytest.approx(0.008)
    assert status["error"] == pytest.approx(0.012)
    assert status["wire_position"] == 0.004 and status["wire_force"] == 12.0
    assert (status["encoder_stamp_sec"], status["encoder_stamp_nanosec"]) == (1, 10 * MS)
    assert status["duty_percent"] == duty > 0.0 and status["active"] is True
    assert status["strategy"] == "bpid" and status["mode"] == "position"
    with pytest.raises(SetpointError):
        loop.set_point("position", -1.0)
    assert loop.status_fields()["rejected_setpoints"] == 1
    assert loop.status_fields()["last_rejection"]
