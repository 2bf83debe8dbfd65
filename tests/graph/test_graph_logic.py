"""Plain-Python graph logic: setpoint rules, supervisor state machine, unit driver gates."""

import math

import pytest

from hems_ros.graph import names
from hems_ros.graph.setpoints import SetpointError, SetpointLimits, validate
from hems_ros.graph.supervisor_logic import MonitorLimits, State, SupervisorLogic
from hems_ros.graph.unit_driver import UnitDriver
from hems_ros.physics import ActuationUnit, load_params


@pytest.mark.parametrize("mode, value, reason", [
    ("position", math.nan, "not a finite number"),
    ("position", -1.0, "outside the tendon stroke 0-0.054 m"),
    ("position", 1e9, "outside the tendon stroke"),
    ("force", 25.5, "outside the tendon force range 0-25 N"),
    ("grip", 0.01, "unknown mode 'grip'"),
])
def test_invalid_setpoints_are_rejected_with_the_reason(mode, value, reason):
    with pytest.raises(SetpointError, match=reason):
        validate(mode, value, SetpointLimits())


def test_valid_setpoints_pass_unchanged():
    assert validate("position", 0.054, SetpointLimits()).value == 0.054
    assert validate("force", 10.0, SetpointLimits()).mode == "force"


def _ready(logic, now):
    for finger in logic.fingers:
        for stream in ("encoder", "wire_force", "heartbeat"):
            logic.saw(stream, finger, now)


def test_supervisor_enables_only_with_every_stream_alive_and_latches_faults():
    logic = SupervisorLogic(("index", "middle"))
    ok, message = logic.request("enable", 0.0)
    assert not ok and "index: no encoder yet" in message
    _ready(logic, 1.0)
    assert logic.request("enable", 1.0) == (True, "ENABLED")
    logic.check_streams(1.02)
    logic.check_streams(1.04)
    assert logic.state == State.ENABLED
    logic.saw("encoder", "index", 1.05)
    logic.saw("wire_force", "index", 1.05)
    logic.saw("heartbeat", "index", 1.05)
    logic.check_streams(1.06)  # middle silent for 60 ms
    assert logic.state == State.FAULT
    assert {f.finger for f in logic.faults} == {"middle"}
    assert not logic.request("enable", 1.07)[0]
    ok, message = logic.request("reset", 1.08)
    assert not ok and "middle" in message  # still silent
    _ready(logic, 1.09)
    assert logic.request("reset", 1.09)[0] and logic.state == State.IDLE and not logic.faults


def test_a_late_check_does_not_blame_the_streams():
    logic = SupervisorLogic(("index",))
    _ready(logic, 0.0)
    logic.request("enable", 0.0)
    logic.check_streams(0.01)
    logic.check_streams(0.2)  # the supervisor itself stalled 190 ms
    assert logic.state == State.ENABLED
    logic.check_streams(0.21)  # on time now, streams still silent: a real fault
    assert logic.state == State.FAULT


def test_estop_latches_and_over_force_faults_in_any_state():
    logic = SupervisorLogic(("index",), MonitorLimits(max_wire_force_n=50.0))
    logic.wire_force("index", 50.0, 0.0)
    assert logic.state == State.FAULT and "over-force 50.0 N" in str(logic.faults[0])
    logic.request("estop", 0.1)
    assert logic.state == State.ESTOP and not logic.heating_allowed
    assert not logic.request("disable", 0.2)[0]


def test_watchdog_flag_faults_only_when_held_while_enabled():
    logic = SupervisorLogic(("index",))
    logic.watchdog("index", True, 0.5)
    assert logic.state == State.IDLE
    _ready(logic, 1.0)
    logic.request("enable", 1.0)
    logic.watchdog("index", True, 1.01)
    logic.watchdog("index", False, 1.03)
    logic.watchdog("index", True, 1.05)
    assert logic.state == State.ENABLED
    logic.watchdog("index", True, 1.10)
    assert logic.state == State.FAULT and logic.faults[0].kind == "watchdog"


def test_unit_driver_watchdog_permission_and_bad_commands_end_at_zero_duty():
    driver = UnitDriver(ActuationUnit(load_params("ch6_hems_index")), start_time_s=100.0)
    driver.permit_heating(True, 100.0)
    driver.command(50.0, 100.0)
    driver.advance(100.02)
    assert driver.applied_duty == 50.0 and not driver.watchdog_tripped
    driver.advance(100.04)  # 40 ms without a command: three 10 ms periods passed
    assert driver.applied_duty == 0.0 and driver.watchdog_tripped
    driver.command(40.0, 100.04)
    driver.permit_heating(False, 100.04)
    driver.advance(100.05)
    assert driver.applied_duty == 0.0
    driver.permit_heating(True, 100.05)
    with pytest.raises(ValueError, match="rejected"):
        driver.command(math.nan, 100.05)
    driver.advance(100.06)
    assert driver.applied_duty == 0.0 and driver.rejected_commands == 1


def test_unit_driver_publishes_one_sample_per_encoder_period_at_1khz_physics():
    driver = UnitDriver(ActuationUnit(load_params("ch6_hems_index")), start_time_s=5.0, require_permission=False)
    samples = driver.advance(5.1)
    assert [round(s.time_s - 5.0, 6) for s in samples] == [round(0.01 * k, 6) for k in range(1, 11)]
    assert driver.unit.time == pytest.approx(0.1)


def test_all_sixteen_nodes_are_named():
    nodes = names.node_names()
    assert len(nodes) == 16
    assert len({n for _, n, _ in nodes}) == 16
    assert {m for m in names.MODULES} == {"thumb", "index_middle", "ring_little"}
