"""Plain-Python graph logic: setpoint rules, supervisor state machine, unit driver gates."""

import math

import numpy as np
import pytest

from hems_ros.graph import names
from hems_ros.graph.grasp import (
    FingerSummary,
    FingerTrace,
    GraspPlan,
    PhaseTracker,
    summarize,
    tracking_report,
)
from hems_ros.graph.setpoints import SetpointError, SetpointLimits, validate
from hems_ros.graph.supervisor_logic import (
    STREAMS,
    MonitorLimits,
    State,
    SupervisorLogic,
    gap_entries,
    gap_report,
    longest_take,
    parse_quiets,
    parse_take,
    quiet_entry,
)
from hems_ros.graph.unit_driver import UnitDriver
from hems_ros.launcher import Graph, GraphOptions
from hems_ros.physics import ActuationUnit, load_params


@pytest.mark.parametrize(
    "mode, value, reason",
    [
        ("position", math.nan, "not a finite number"),
        ("position", -1.0, "outside the tendon stroke 0-0.054 m"),
        ("position", 1e9, "outside the tendon stroke"),
        ("force", 25.5, "outside the tendon force range 0-25 N"),
        ("grip", 0.01, "unknown mode 'grip'"),
    ],
)
def test_invalid_setpoints_are_rejected_with_the_reason(mode, value, reason):
    with pytest.raises(SetpointError, match=reason):
        validate(mode, value, SetpointLimits())


def test_valid_setpoints_pass_unchanged():
    assert validate("position", 0.054, SetpointLimits()).value == 0.054
    assert validate("force", 10.0, SetpointLimits()).mode == "force"


def _streams_seen(logic, now, streams=STREAMS):
    for finger in logic.fingers:
        for stream in streams:
            logic.saw(stream, finger, now)


def _ready(logic, now):
    _streams_seen(logic, now)
    for finger in logic.fingers:
        logic.watchdog(finger, False, now)


def _report(logic, finger: str, now: float, encoder_moved: bool = True, unit: bool = True) -> None:
    """What the supervisor node does with a controller status (fresh force reading) and, at the
    same check, the unit's state report (unless ``unit`` is False)."""
    logic.saw("heartbeat", finger, now)
    if unit:
        logic.saw("unit state", finger, now)
    if encoder_moved:
        logic.encoder(finger, 0.01, now)
    else:
        logic.unchanged("encoder", finger, now)
    logic.wire_force(finger, 4.0, now)


def test_supervisor_enables_only_with_every_stream_alive_and_latches_faults():
    logic = SupervisorLogic(("index", "middle"), MonitorLimits(lost_s=0.5))
    ok, message = logic.request("enable", 0.0)
    assert not ok and "index: no encoder yet" in message
    _ready(logic, 1.0)
    assert logic.request("enable", 1.0) == (True, "ENABLED")
    # both controllers keep reporting every 20 ms; middle's encoder reading stops moving: a
    # gap, counted, until it has lasted lost_s (500 ms)
    for k in range(1, 27):
        now = 1.0 + 0.02 * k
        logic.check_streams(now)
        _report(logic, "index", now)
        _report(logic, "middle", now, encoder_moved=False)
        assert logic.state == (State.ENABLED if now < 1.51 else State.FAULT), now
    assert [(f.finger, f.kind) for f in logic.faults] == [("middle", "encoder")]
    assert "encoder lost (520 ms without a new reading)" in str(logic.faults[0])
    assert not logic.request("enable", 1.53)[0]
    ok, message = logic.request("reset", 1.54)
    assert not ok and "middle: encoder stale" in message
    _ready(logic, 1.55)
    assert logic.request("reset", 1.55)[0] and logic.state == State.IDLE and not logic.faults


def test_a_unit_whose_reports_stop_is_lost_while_its_controller_still_reports():
    """A stopped unit stops its encoder too, but its controller then reports only at its idle
    period; the unit's own reports name the loss at lost_s."""
    logic = SupervisorLogic(("index",), MonitorLimits(lost_s=0.4))
    _ready(logic, 1.0)
    logic.request("enable", 1.0)
    faulted_at = None
    for k in range(1, 23):
        now = 1.0 + 0.02 * k
        logic.check_streams(now)
        _report(logic, "index", now, unit=False)
        if faulted_at is None and logic.state == State.FAULT:
            faulted_at = now
    assert faulted_at == pytest.approx(1.40, abs=0.021)
    assert [(f.finger, f.kind) for f in logic.faults] == [("index", "unit state")]
    assert "index: unit state lost (4" in str(logic.faults[0])


def test_a_sensor_gap_shorter_than_a_loss_is_counted_not_latched():
    """A busy host (a tool joining the domain) holds a stream up for tens of ms: no FAULT; the
    units are safe meanwhile (no reading, no duty: their watchdog)."""
    logic = SupervisorLogic(("index",))
    _ready(logic, 1.0)
    logic.request("enable", 1.0)
    for now in (1.02, 1.04, 1.06, 1.08, 1.10, 1.12):  # 120 ms without a new encoder reading
        _report(logic, "index", now, encoder_moved=False)
        logic.check_streams(now)
    _report(logic, "index", 1.14)  # back
    _report(logic, "index", 1.16)
    _report(logic, "index", 1.30, encoder_moved=False)  # 140 ms: a second gap
    _report(logic, "index", 1.34)
    assert logic.state == State.ENABLED and not logic.faults
    count, longest = logic.gaps()[("index", "encoder")]
    assert count == 2 and longest == pytest.approx(0.18)


def test_heartbeat_and_unit_state_gaps_are_counted_with_their_longest():
    """The margin of the loss limits is judged against the longest gap of every stream, the
    controller's heartbeat and the unit's state reports included."""
    logic = SupervisorLogic(("index",))
    _ready(logic, 1.0)
    logic.request("enable", 1.0)
    _report(logic, "index", 1.02)
    _report(logic, "index", 1.17)  # 150 ms without a status: heartbeat, sensors and state
    _report(logic, "index", 1.19, unit=False)
    _report(logic, "index", 1.21, unit=False)
    _report(logic, "index", 1.25)  # the state 80 ms apart: within its 50 ms period's slack
    gaps = logic.gaps()
    assert gaps[("index", "heartbeat")] == (1, pytest.approx(0.15))
    assert gaps[("index", "unit state")] == (1, pytest.approx(0.15))
    assert gaps[("index", "encoder")] == (1, pytest.approx(0.15))
    assert logic.state == State.ENABLED


def _checks_with_unit_states(logic, finger: str, ks: range) -> None:
    """Checks every 10 ms (at 0.01 k s); the unit's state report comes every 50 ms."""
    for k in ks:
        if k % 5 == 0:
            logic.saw("unit state", finger, 0.01 * k)
        logic.check_streams(0.01 * k)


def test_a_silent_controller_is_its_heartbeat_fault_not_its_sensors():
    logic = SupervisorLogic(("index",), MonitorLimits(heartbeat_timeout_s=0.2))
    _ready(logic, 0.0)
    logic.request("enable", 0.0)
    _checks_with_unit_states(logic, "index", range(1, 20))  # no status for 190 ms
    assert logic.state == State.ENABLED  # the sensors cannot be judged
    # the controller was only late: its next report carries fresh readings
    _report(logic, "index", 0.195)
    logic.check_streams(0.2)
    assert logic.state == State.ENABLED
    _checks_with_unit_states(logic, "index", range(21, 42))
    assert [(f.finger, f.kind) for f in logic.faults] == [("index", "heartbeat")]


def test_a_late_check_does_not_blame_the_streams():
    logic = SupervisorLogic(("index",), MonitorLimits(heartbeat_timeout_s=0.2))
    _ready(logic, 0.0)
    logic.request("enable", 0.0)
    _checks_with_unit_states(logic, "index", range(1, 13))
    logic.saw("unit state", "index", 0.15)  # received while the supervisor stalled
    logic.check_streams(0.21)  # the supervisor itself stalled 90 ms, under half the limit
    assert logic.state == State.ENABLED
    logic.saw("unit state", "index", 0.2)
    logic.check_streams(0.22)  # on time now, the heartbeat still silent: a real fault
    assert [(f.finger, f.kind) for f in logic.faults] == [("index", "heartbeat")]
    assert "heartbeat stale (220 ms without a message)" in str(logic.faults[0])


def test_a_supervisor_stopped_for_a_second_does_not_fault_its_streams_for_its_own_stop():
    """Stopped (SIGSTOP) or starved for longer than half a loss limit, the supervisor resumes
    to streams that look silent for the whole stop while their messages are still on their
    way: it judges silences from its resume. One that stays silent faults a limit later."""
    limits = MonitorLimits(lost_s=0.4, heartbeat_timeout_s=0.4)
    logic = SupervisorLogic(("index", "middle"), limits)
    _ready(logic, 0.0)
    logic.request("enable", 0.0)
    for k in range(1, 51):
        now = 0.02 * k
        logic.check_streams(now)
        _report(logic, "index", now)
        _report(logic, "middle", now)
    faulted_at = None
    for k in range(0, 30):  # stopped from 1.0 s to 2.0 s; index is back 60 ms after the resume
        now = 2.0 + 0.02 * k
        logic.check_streams(now)
        if now >= 2.06:
            _report(logic, "index", now)
        if faulted_at is None and logic.state == State.FAULT:
            faulted_at = now
    # middle never came back: named 400 ms after the resume, not at the first check after it
    assert faulted_at == pytest.approx(2.42, abs=0.001)
    assert {(f.finger, f.kind) for f in logic.faults} == {
        ("middle", "heartbeat"),
        ("middle", "unit state"),
    }
    assert "middle: heartbeat stale (420 ms without a message)" in [str(f) for f in logic.faults]
    # index's gap is the 60 ms it took after the resume, not the supervisor's stop
    assert logic.gaps()[("index", "heartbeat")] == (1, pytest.approx(0.06))


def _enabled_and_reporting(fingers, until: float) -> SupervisorLogic:
    """ENABLED at 0 s, every finger reporting every 20 ms up to ``until``."""
    logic = SupervisorLogic(fingers, MonitorLimits(lost_s=0.4, heartbeat_timeout_s=0.4))
    _ready(logic, 0.0)
    logic.request("enable", 0.0)
    for k in range(1, round(until / 0.02) + 1):
        for finger in fingers:
            _report(logic, finger, 0.02 * k)
        logic.check_streams(0.02 * k)
    return logic


def test_a_quiet_of_every_stream_at_once_is_the_supervisors_not_each_streams():
    """A join's discovery held the supervisor's reception on a busy host: every stream of
    every finger came 170-200 ms late at once. Such a quiet beyond quiet_s (150 ms) is no
    stream's silence; here 450 ms, which faulted every stream before."""
    logic = _enabled_and_reporting(("index", "middle"), until=1.0)
    for k in range(1, 23):  # checks on time, nothing received until 1.45 s
        logic.check_streams(1.0 + 0.02 * k)
    for finger in ("index", "middle"):
        _report(logic, finger, 1.45)
    logic.check_streams(1.46)
    assert logic.state == State.ENABLED, [str(f) for f in logic.faults]
    assert logic.gaps()[("middle", "heartbeat")] == (1, pytest.approx(0.15))
    assert logic.quiets() == (1, pytest.approx(0.45))
    key, value = quiet_entry(logic.quiets())
    assert (key, value) == ("supervisor quiets", "1, longest 450 ms")
    assert parse_quiets(value) == (1, pytest.approx(0.45))


def test_one_stream_silent_while_the_others_are_heard_faults_on_time():
    """A killed unit in a one-finger graph: its controller, without new encoder readings,
    reports only every 100 ms (late by up to 40 ms on a busy host), under quiet_s, so the
    unit's silence counts in full."""
    logic = _enabled_and_reporting(("index",), until=1.0)
    faulted_at = None
    for k in range(1, 40):
        now = 1.0 + 0.02 * k
        if k % 7 == 0:  # every 140 ms
            logic.saw("heartbeat", "index", now)
            logic.unchanged("encoder", "index", now)
        logic.check_streams(now)
        if faulted_at is None and logic.state == State.FAULT:
            faulted_at = now
    assert faulted_at == pytest.approx(1.42, abs=1e-6)
    # the unit's encoder, in the controller's report, is named at the check's moment
    assert [str(f) for f in logic.faults] == ["index: encoder lost (420 ms without a new reading)"]
    assert logic.quiets() == (0, 0.0)


def test_a_graph_silent_as_a_whole_still_faults_a_loss_limit_later():
    """Every process gone: the supervisor cannot tell that from not hearing, so it excuses at
    most one loss limit (400 ms) of the quiet beyond quiet_s, and faults every stream."""
    logic = _enabled_and_reporting(("index", "middle"), until=1.0)
    faulted_at = None
    for k in range(1, 60):
        now = 1.0 + 0.02 * k
        logic.check_streams(now)
        if faulted_at is None and logic.state == State.FAULT:
            faulted_at = now
    assert faulted_at == pytest.approx(1.82, abs=1e-6)
    assert "middle: heartbeat stale (420 ms without a message)" in [str(f) for f in logic.faults]
    assert {f.kind for f in logic.faults} == {"heartbeat", "unit state"}


def test_enable_waits_for_every_units_state_with_its_watchdog_clear():
    """A unit whose duty reader has not matched its controller's writer yet shows a tripped
    watchdog; enabling it then latched FAULT some 100 ms later."""
    logic = SupervisorLogic(
        ("index", "middle"), MonitorLimits(watchdog_hold_s=0.5, heartbeat_timeout_s=0.2)
    )
    _streams_seen(logic, 1.0, ("encoder", "wire_force", "heartbeat"))
    logic.saw("unit state", "index", 1.0)
    logic.watchdog("index", False, 1.0)
    ok, message = logic.request("enable", 1.0)
    assert not ok and message == "cannot enable: middle: no unit state yet"
    logic.saw("unit state", "middle", 1.01)
    logic.watchdog("middle", True, 1.01)  # no command since the unit started
    ok, message = logic.request("enable", 1.01)
    assert (
        not ok
        and message
        == "cannot enable: middle: no duty commands reach the unit (its watchdog is tripped)"
    )
    logic.watchdog("middle", False, 1.02)
    logic.watchdog("index", True, 1.02)  # late commands: not held for watchdog_hold_s yet
    _streams_seen(logic, 1.19)
    assert logic.request("enable", 1.2) == (True, "ENABLED")
    logic.request("disable", 1.21)
    _streams_seen(logic, 1.52)
    ok, message = logic.request("enable", 1.53)  # held past 500 ms now: the commands do not arrive
    assert (
        not ok
        and message
        == "cannot enable: index: no duty commands reach the unit (its watchdog is tripped)"
    )
    logic.watchdog("index", False, 1.54)
    ok, message = logic.request("enable", 1.8)  # the 20 Hz state reports stopped 280 ms ago
    assert "index: unit state stale" in message and "middle: unit state stale" in message


@pytest.mark.parametrize(
    "component, consequence", [("unit", "it does not heat"), ("controller", "it sends 0 % duty")]
)
def test_a_unit_or_controller_that_has_not_taken_enabled_faults_after_the_grace(
    component, consequence
):
    logic = SupervisorLogic(("index", "ring"), MonitorLimits(enable_grace_s=0.5))
    _ready(logic, 1.0)
    logic.sees_enabled("ring", component, False, 0.9)  # before enabling: nothing to take yet
    logic.request("enable", 1.0)
    for k in range(1, 27):  # reports every 20 ms; the grace runs from the first after enabling
        now = 1.0 + 0.02 * k
        logic.sees_enabled("index", component, k > 2, now)  # took it after 60 ms
        logic.sees_enabled("ring", component, False, now)
        assert logic.state == (State.ENABLED if k < 26 else State.FAULT), now
    assert [(f.finger, f.kind) for f in logic.faults] == [("ring", f"{component} not enabled")]
    assert (
        str(logic.faults[0]) == f"ring: {component} has not taken ENABLED for 500 ms: {consequence}"
    )


def test_the_longest_take_of_enabled_is_kept_over_enables_and_named():
    logic = SupervisorLogic(("index", "ring"))
    _ready(logic, 1.0)
    logic.sees_enabled("index", "unit", True, 0.99)  # before enabling: not a take
    logic.request("enable", 1.0)
    logic.sees_enabled("ring", "controller", True, 0.995)  # received before, taken from the queue
    logic.sees_enabled("index", "unit", True, 1.04)
    logic.sees_enabled("ring", "controller", False, 1.04)
    logic.sees_enabled("ring", "controller", True, 1.12)
    logic.sees_enabled("ring", "controller", True, 1.30)  # already taken: not a longer take
    logic.request("enable", 1.5)  # a repeated enable while ENABLED: nothing to take again
    logic.sees_enabled("index", "unit", True, 1.9)
    assert logic.enable_takes() == pytest.approx(
        {("index", "unit"): 0.04, ("ring", "controller"): 0.12}
    )
    logic.request("disable", 2.0)
    _ready(logic, 3.0)
    logic.request("enable", 3.0)
    logic.sees_enabled("index", "unit", True, 3.2)
    assert logic.enable_takes()[("index", "unit")] == pytest.approx(0.2)
    assert longest_take(logic.enable_takes()) == "200 ms (index unit)"


def test_the_fingers_heard_are_those_whose_heartbeat_is_fresh():
    logic = SupervisorLogic(("index", "ring", "little"), MonitorLimits(heartbeat_timeout_s=0.4))
    assert logic.heard_fingers(0.0) == []
    logic.saw("heartbeat", "index", 1.0)
    logic.saw("heartbeat", "ring", 1.3)
    logic.saw("encoder", "little", 1.3)  # a sensor is no heartbeat
    assert logic.heard_fingers(1.35) == ["index", "ring"]
    assert logic.heard_fingers(1.45) == ["ring"]  # index silent for 0.45 s
    assert logic.heard_fingers(1.75) == []


def test_the_gap_report_gives_scripts_the_diagnostics_figures_as_numbers():
    takes = {("index", "unit"): 0.085, ("ring", "controller"): 0.2134}
    assert parse_take(longest_take(takes)) == (213.0, "ring controller")
    pairs = [
        ("state", "ENABLED"),
        *gap_entries({("index", "encoder"): (2, 0.0712), ("ring", "heartbeat"): (3, 0.1384)}),
        ("gap floor ms", "50"),
        ("loss limit ms", "400"),
        quiet_entry((2, 0.2216)),
        ("enable taken", longest_take(takes)),
        ("enable grace ms", "1000"),
    ]
    assert gap_report(pairs) == {
        "gaps": 5,
        "longest_gap_ms": 138,
        "longest_gap_stream": "ring heartbeat",
        "gap_floor_ms": 50.0,
        "loss_limit_ms": 400.0,
        "quiets": 2,
        "longest_quiet_ms": 222,
        "enable_taken_ms": 213.0,
        "enable_taken_by": "ring controller",
        "enable_grace_ms": 1000.0,
    }
    # before any gap, quiet or enable: nulls, not made-up zeros
    bare = gap_report([("gap floor ms", "50"), ("loss limit ms", "400"), quiet_entry((0, 0.0))])
    assert (bare["gaps"], bare["longest_gap_ms"], bare["longest_gap_stream"]) == (0, None, None)
    assert (bare["quiets"], bare["longest_quiet_ms"], bare["enable_taken_ms"]) == (0, None, None)
    assert bare["enable_grace_ms"] is None and bare["loss_limit_ms"] == 400.0


def test_a_brief_lapse_of_the_enabled_view_and_a_new_enable_start_the_grace_again():
    logic = SupervisorLogic(("index",), MonitorLimits(enable_grace_s=0.5))
    _ready(logic, 0.0)
    logic.request("enable", 0.0)
    logic.sees_enabled("index", "unit", False, 0.4)
    logic.request("disable", 0.45)
    _ready(logic, 1.0)
    logic.request("enable", 1.0)
    logic.sees_enabled(
        "index", "unit", False, 1.4
    )  # 1.0 s after the first no, 0.4 s into this ENABLED
    logic.sees_enabled("index", "unit", True, 1.45)
    logic.sees_enabled("index", "unit", False, 1.6)  # a lapse (a stalled unit lost its permission)
    logic.sees_enabled("index", "unit", False, 2.0)
    assert logic.state == State.ENABLED
    logic.sees_enabled("index", "unit", False, 2.1)
    assert logic.state == State.FAULT


def test_estop_latches_and_over_force_faults_in_any_state():
    logic = SupervisorLogic(("index",), MonitorLimits(max_wire_force_n=50.0))
    logic.wire_force("index", 50.0, 0.0)
    assert logic.state == State.FAULT and "over-force 50.0 N" in str(logic.faults[0])
    logic.request("estop", 0.1)
    assert logic.state == State.ESTOP and not logic.heating_allowed
    assert not logic.request("disable", 0.2)[0]


def test_watchdog_flag_faults_only_when_held_while_enabled():
    logic = SupervisorLogic(("index",), MonitorLimits(watchdog_hold_s=0.5))
    logic.watchdog("index", True, 0.5)
    assert logic.state == State.IDLE
    _ready(logic, 1.0)
    logic.request("enable", 1.0)
    logic.watchdog("index", True, 1.01)
    logic.watchdog("index", False, 1.03)
    logic.watchdog("index", True, 1.05)
    logic.watchdog("index", True, 1.14)  # a controller held up 90 ms by a busy host
    logic.watchdog("index", False, 1.15)
    logic.watchdog("index", True, 1.2)
    logic.watchdog("index", True, 1.41)  # a lost duty sample's repair: 210 ms
    logic.watchdog("index", False, 1.42)
    logic.watchdog("index", True, 1.5)
    logic.watchdog("index", True, 1.99)
    assert logic.state == State.ENABLED
    logic.watchdog("index", True, 2.01)  # held past 500 ms: the commands do not arrive
    assert logic.state == State.FAULT and logic.faults[0].kind == "watchdog"
    assert str(logic.faults[0]) == "index: duty watchdog tripped for 510 ms: no duty commands"


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


def test_heating_stops_35_ms_after_the_last_supervisor_status_at_that_step():
    """A stopped or killed supervisor sends no status: the permission runs out
    permission_timeout_s (35 ms) after the last one, at that 1 ms physics step, whenever the
    unit next looks; the next ENABLED lets it heat again, counted as a lapse."""
    driver = UnitDriver(ActuationUnit(load_params("ch6_hems_index")), start_time_s=100.0)
    driver.permit_heating(True, 100.0)
    driver.command(100.0, 100.0)
    energy = []
    for k in range(1, 8):  # commands keep coming every 10 ms; the statuses stopped at 100.0
        driver.advance(100.0 + 0.01 * k)
        energy.append(driver.last_result.energy_joule_j)
        driver.command(100.0, 100.0 + 0.01 * k)
    per_period = [b - a for a, b in zip(energy, energy[1:])]
    assert all(p > 0.6 for p in per_period[:2])  # about 0.67 J per 10 ms at 100 %
    # four or five of the period's ten steps (the epoch clock's rounding decides the fifth)
    assert 0.35 < per_period[2] / per_period[1] < 0.55
    assert per_period[3:] == [0.0, 0.0, 0.0]  # from 100.035 on
    assert driver.applied_duty == 0.0 and driver.permission_lapses == 0
    driver.permit_heating(True, 100.075)
    driver.advance(100.08)
    assert driver.applied_duty == 100.0 and driver.permission_lapses == 1


def test_unit_driver_publishes_one_sample_per_encoder_period_at_1khz_physics():
    driver = UnitDriver(
        ActuationUnit(load_params("ch6_hems_index")), start_time_s=5.0, require_permission=False
    )
    samples = driver.advance(5.1)
    assert [round(s.time_s - 5.0, 6) for s in samples] == [round(0.01 * k, 6) for k in range(1, 11)]
    assert driver.unit.time == pytest.approx(0.1)


def _driven(
    arrival_delay_s: float, stamp_offset_s: float | None = 0.0, permit_at_s: float = 5.0
) -> UnitDriver:
    """A driver heated by 60 % answers to the samples at 5.01, 5.02, ... each arriving
    ``arrival_delay_s`` after its sample and stamped ``stamp_offset_s`` off it (None: no stamp)."""
    driver = UnitDriver(ActuationUnit(load_params("ch6_hems_index")), start_time_s=5.0)
    driver.permit_heating(True, permit_at_s)
    for k in range(1, 31):
        sample_s = 5.0 + 0.01 * k
        driver.advance(sample_s + arrival_delay_s)
        driver.permit_heating(True, max(permit_at_s, sample_s + arrival_delay_s))
        driver.command(
            60.0,
            sample_s + arrival_delay_s,
            None if stamp_offset_s is None else sample_s + stamp_offset_s,
        )
        driver.advance(sample_s + arrival_delay_s)
    driver.advance(5.35)
    return driver


def test_a_duty_answering_the_latest_sample_takes_effect_at_that_sample():
    on_time = _driven(0.0)
    for delay in (0.0012, 0.0037, 0.0099):  # transport delays within one control period
        delayed = _driven(delay)
        assert delayed.unit.state == on_time.unit.state
        assert delayed.last_result == on_time.last_result  # the same sensor noise draws too
        assert delayed.late_commands == 0 and delayed.missed_periods == 0
    assert on_time.unit.state["energy_joule_j"] > 1.0


def test_a_driver_stepping_from_sample_to_sample_copies_no_state():
    """On wall-clock time a unit advances tick to tick and takes the commands at the ticks:
    the unit is still at the sample a command answers, so no snapshot and no restore; the
    same commands arriving between samples need both and give the same plant."""
    copies = {}

    def counted(driver: UnitDriver, name: str) -> UnitDriver:
        unit = driver.unit
        copy = unit.snapshot

        def snapshot():
            copies[name] = copies.get(name, 0) + 1
            return copy()

        unit.snapshot = snapshot
        return driver

    at_ticks, between = (
        counted(
            UnitDriver(
                ActuationUnit(load_params("ch6_hems_index")),
                start_time_s=5.0,
                require_permission=False,
            ),
            name,
        )
        for name in ("ticks", "between")
    )
    for k in range(1, 31):
        sample_s = 5.0 + 0.01 * k
        at_ticks.advance(sample_s)
        at_ticks.command(60.0, sample_s + 0.004, sample_s)  # taken at the next tick
        between.advance(sample_s + 0.004)
        between.command(60.0, sample_s + 0.004, sample_s)
    for driver in (at_ticks, between):
        driver.advance(5.35)
    assert at_ticks.unit.state == between.unit.state and at_ticks.last_result == between.last_result
    assert at_ticks.unit.state["energy_joule_j"] > 1.0
    assert copies == {"between": 30}


def test_a_late_duty_takes_effect_on_arrival_and_is_counted():
    late = _driven(0.003, stamp_offset_s=-0.01)  # answers the sample before the latest one
    assert late.late_commands == 30
    assert late.unit.state == _driven(0.003, stamp_offset_s=None).unit.state
    assert late.unit.state != _driven(0.0).unit.state


def test_rewinding_to_a_sample_never_heats_before_the_supervisor_allowed_it():
    # permission comes 4 ms after the first sample; that sample's duty arrives 5 ms after it
    driver = UnitDriver(ActuationUnit(load_params("ch6_hems_index")), start_time_s=5.0)
    driver.advance(5.015)
    driver.permit_heating(True, 5.014)
    driver.command(100.0, 5.015, 5.01)
    joule_at = {}
    for t in (5.011, 5.012, 5.013, 5.014, 5.015, 5.016):
        driver.advance(t)
        joule_at[round(t, 3)] = driver.unit.state["energy_joule_j"]
    assert joule_at[5.011] == joule_at[5.013] == 0.0  # rewound to 5.01 but not yet allowed
    assert joule_at[5.015] > joule_at[5.014] > 0.0


def test_all_sixteen_nodes_are_named():
    nodes = names.node_names()
    assert len(nodes) == 16
    assert len({n for _, n, _ in nodes}) == 16
    assert {m for m in names.MODULES} == {"thumb", "index_middle", "ring_little"}


def test_grasp_phases_start_at_the_sample_that_first_used_each_setpoint():
    tracker = PhaseTracker()
    tracker.feed("position", 0.0, True, 0.99, 0.0)  # before the grasp
    tracker.feed("position", 0.02, False, 1.00, 0.0)  # not enabled: no step taken
    tracker.feed("position", 0.02, True, 1.01, 1.009)
    tracker.feed("position", 0.02, True, 1.02, 1.019)
    tracker.feed("force", 10.0, True, 1.03, 1.029)
    tracker.feed("position", 0.0, True, 1.05, 1.049)
    assert tracker.starts == [1.01, 1.029, 1.05]


def test_grasp_summary_numbers():
    plan = GraspPlan(approach_s=2.0, hold_s=2.0, release_s=1.0, settle_window_s=0.5)
    t = np.round(np.arange(0.0, 5.0, 0.01), 2)
    position = np.where(t < 1.0, 0.0, plan.approach_m)  # reaches the target after 1 s
    force = np.where(t < 2.5, 5.0, plan.force_n + 0.1)  # 0.1 N high once built up
    # the unit's accumulator, read between samples: 7 J at the start (0 s), 45 J at the end (5 s)
    trace = FingerTrace(
        list(t), list(position), list(force), [-0.5, 4.5, 5.5], [3.0, 43.0, 47.0], [], []
    )
    summary = summarize("index", trace, plan, [0.0, 2.0, 4.0])
    assert summary.approach_rmse_mm == pytest.approx(1e3 * plan.approach_m * math.sqrt(0.5))
    assert summary.position_rmse_mm == 0.0
    assert summary.hold_rmse_n == pytest.approx(math.sqrt((0.5 * 25.0 + 1.5 * 0.01) / 2.0))
    assert summary.force_rmse_n == pytest.approx(0.1)
    assert summary.peak_force_n == pytest.approx(10.1) and summary.energy_j == pytest.approx(
        45.0 - 7.0
    )
    cut_short = FingerTrace(list(t), list(position), list(force), [0.5, 4.5], [5.0, 43.0], [], [])
    assert math.isnan(summarize("index", cut_short, plan, [0.0, 2.0, 4.0]).energy_j)


def test_a_finger_that_did_not_follow_makes_the_grasp_invalid():
    plan = GraspPlan()
    good = FingerSummary("index", 0.06, 0.02, 10.1, 299.0, 10.0, 1.3)
    # the demo once reported this as a valid run: the ring unit never heated, nothing faulted
    still = FingerSummary(
        "ring", 1e3 * plan.approach_m, plan.force_n - 2.0, 2.04, 0.0, 1e3 * plan.approach_m, 8.0
    )
    weak = FingerSummary("middle", 0.06, 0.3 * plan.force_n, 7.0, 250.0, 10.0, 3.5)
    assert tracking_report([good], plan, ["index"]) is None
    assert tracking_report([good, still, weak], plan, ["index", "ring", "middle"]) == (
        f"fingers did not follow their setpoints: ring approach error {1e3 * plan.approach_m:.2f} "
        f"mm; middle hold error {0.3 * plan.force_n:.2f} N"
    )
    assert tracking_report([good], plan, ["index", "little"]) == (
        "fingers did not follow their setpoints: little has no summary (its controller did not run "
        "every phase)"
    )
    nan = FingerSummary("index", math.nan, math.nan, math.nan, 0.0, math.nan, math.nan)
    assert "index approach error nan mm" in tracking_report([nan], plan, ["index"])


def test_latency_window_holds_the_commands_of_its_last_seconds():
    # 1 s at 10 ms per command: 100 latencies; start-up stalls older than that drop out
    driver = UnitDriver(ActuationUnit(), 0.0, sample_period_s=0.01, latency_window_s=1.0)
    driver.latencies_s.extend([2.4] * 50 + [1e-3] * 99 + [3e-3])
    assert len(driver.latencies_s) == 100
    assert driver.latency_percentiles() == (1e-3, 3e-3, 3e-3)


def test_latency_percentiles_are_the_ranked_window_values():
    driver = UnitDriver(ActuationUnit(), 0.0)
    assert all(math.isnan(v) for v in driver.latency_percentiles())
    values = [((7919 * k) % 1000) * 1e-5 for k in range(1000)]  # 0 .. 9.99 ms, shuffled
    driver.latencies_s.extend(values)
    assert driver.latency_percentiles() == (500e-5, 990e-5, 999e-5)


def test_extra_ros_args_reach_every_node_separate_or_composed():
    extra = ("-p", "latency_window_s:=5")
    separate = Graph(GraphOptions(extra_ros_args=extra, composed=False)).commands()
    composed = Graph(GraphOptions(extra_ros_args=extra)).commands()
    assert len(separate) == 16 and all(cmd[-2:] == list(extra) for cmd in separate.values())
    assert list(composed) == ["composed"] and composed["composed"][-2:] == list(extra)


def test_only_the_separate_processes_leave_their_parameter_services_out_and_only_when_asked():
    def flagged(**options) -> list[bool]:
        return [
            "--no-parameter-services" in cmd[: cmd.index("--ros-args")]
            for cmd in Graph(GraphOptions(**options)).commands().values()
        ]

    assert flagged(composed=False) == [False] * 16
    assert flagged(parameter_services=False, composed=False) == [True] * 16
    assert flagged(parameter_services=False) == [False]


def test_extra_environment_reaches_only_the_named_nodes():
    graph = Graph(GraphOptions(composed=False))
    graph.node_env = {"supervisor": {"PYTHONPATH": "/elsewhere"}}
    assert graph.environment("supervisor")["PYTHONPATH"] == "/elsewhere"
    assert graph.environment("finger_controller_index").get("PYTHONPATH") != "/elsewhere"
    assert graph.environment("supervisor")["ROS_AUTOMATIC_DISCOVERY_RANGE"] == "LOCALHOST"


def test_a_graph_that_does_not_come_up_names_the_nodes_that_exited():
    import subprocess
    import sys

    graph = Graph(GraphOptions())
    sleeper = "import time; print('ready', flush=True); time.sleep(30)"
    graph.processes = {
        "running": subprocess.Popen(
            [sys.executable, "-c", sleeper], stdout=subprocess.PIPE, text=True
        ),
        "crashed": subprocess.Popen([sys.executable, "-c", "raise SystemExit(3)"]),
    }
    try:
        assert graph.processes["running"].stdout.readline() == "ready\n"
        graph.processes["crashed"].wait(10)
        assert (
            graph.with_exits("little: no encoder yet")
            == "little: no encoder yet (exited: crashed with code 3)"
        )
    finally:
        graph.stop()
        graph.processes["running"].stdout.close()
    assert graph.with_exits("x") == "x (exited: crashed with code 3, running killed by SIGTERM)"


def test_the_log_level_reaches_every_node_separate_or_composed():
    for composed in (False, True):
        commands = Graph(GraphOptions(composed=composed, log_level="error")).commands()
        assert all("--log-level error" in " ".join(cmd) for cmd in commands.values())


def test_cadence_fires_every_nth_tick_despite_jitter():
    from hems_ros.graph.cadence import Cadence

    every5 = Cadence(0.05, 0.01)
    ticks = [k * 0.01 + (0.0004 if k % 3 else -0.0004) for k in range(100)]  # jitter both ways
    fired = [k for k, t in zip(range(100), ticks) if every5.due(t)]
    assert fired == list(range(0, 100, 5))
    every_tick = Cadence(0.005, 0.01)
    assert all(every_tick.due(t) for t in ticks)


def test_units_of_one_shoulder_module_tick_together_and_modules_a_third_apart():
    from hems_ros.graph.cadence import tick_delay

    now = 1_795_461_707.123_456

    def phase_off(finger: str, phase: float) -> float:
        off = (now + tick_delay(finger, 0.01, now) - phase) % 0.01
        return min(off, 0.01 - off)

    for fingers, phase in (
        (("thumb_flexion", "thumb_abduction"), 0.0),
        (("index", "middle"), 0.01 / 3),
        (("ring", "little"), 0.02 / 3),
    ):
        assert all(phase_off(f, phase) < 1e-6 for f in fingers)
    assert all(0.0 <= tick_delay(f, 0.01, now) < 0.01 for f in names.FINGERS)


def test_skipping_the_integration_a_rewinding_command_undoes_changes_no_bit():
    """A unit integrates up to a command's arrival before applying it, except when the command
    will rewind to the latest sample anyway (UnitDriver.will_rewind): same state, same samples."""
    import random

    import numpy as np

    rng = random.Random(7)
    start = 1_795_000_000.123
    full, lean = (
        UnitDriver(
            ActuationUnit(load_params("ch6_hems_index")),
            start_time_s=start,
            require_permission=False,
        )
        for _ in range(2)
    )
    now, skipped, kept = start, 0, 0
    for _ in range(600):
        now += 0.01 + rng.uniform(-0.002, 0.002)
        assert full.advance(now) == lean.advance(now)
        latest = full._sample_time_s
        stamp = rng.choice([latest, latest, latest, now - 0.02, None])
        duty = rng.choice([30.0, 80.0, rng.uniform(0, 100), float("nan"), 150.0])
        received = now + rng.choice([rng.uniform(0, 0.004), rng.uniform(0.008, 0.012)])
        rewinds = lean.will_rewind(duty, stamp, received)
        skipped, kept = skipped + rewinds, kept + (not rewinds)
        for driver, integrate_first in ((full, True), (lean, not rewinds)):
            got = driver.advance(received) if integrate_first else []
            try:
                driver.command(duty, received, stamp)
            except ValueError:
                pass
            driver.got = got + driver.advance(received)
        assert full.got == lean.got
        assert np.array_equal(full.unit._s, lean.unit._s) and full.unit.steps == lean.unit.steps
        assert (full.applied_duty, full.late_commands, full.rejected_commands) == (
            lean.applied_duty,
            lean.late_commands,
            lean.rejected_commands,
        )
    assert skipped > 50 and kept > 200


def test_a_reading_that_jumps_or_is_not_a_number_is_a_failed_sensor():
    logic = SupervisorLogic(("index", "middle", "ring"))
    _ready(logic, 1.0)
    logic.request("enable", 1.0)
    # 5 mm in 20 ms of the unit's stamps (250 mm/s): a slipped encoder, whatever the host did
    logic.encoder("index", 0.010, 1.02, stamp_s=100.00)
    logic.encoder("index", 0.011, 1.30, stamp_s=100.02)  # 50 mm/s, late to arrive: a motion
    assert not logic.faults
    logic.encoder("index", 0.016, 1.31, stamp_s=100.04)
    logic.wire_force("middle", float("nan"), 1.32)
    logic.controller_fault("ring", "measurement is nan", active=True)
    kinds = [(f.finger, f.kind) for f in logic.faults]
    assert kinds == [("index", "encoder jump"), ("middle", "wire_force"), ("ring", "controller")]
    assert "encoder jump +5.0 mm in 20 ms" in str(logic.faults[0]) and logic.state == State.FAULT


def test_a_controller_fault_reported_while_inactive_does_not_undo_the_reset():
    logic = SupervisorLogic(("index",))
    _ready(logic, 1.0)
    logic.request("enable", 1.0)
    logic.controller_fault("index", "measurement is nan", active=True)
    assert logic.state == State.FAULT
    _ready(logic, 1.1)  # the repaired sensor reports again
    assert logic.request("reset", 1.1)[0]
    # until its next enable the controller reports the fault it tripped on
    logic.controller_fault("index", "measurement is nan", active=False)
    assert logic.state == State.IDLE and not logic.faults
    assert logic.request("enable", 1.12)[0] and logic.state == State.ENABLED


def test_advancing_at_one_gated_duty_gives_the_bits_of_gating_every_step():
    """UnitDriver.advance skips the per-step gates when the gated duty is the same at the
    first and last step: a random run of ticks, commands (some answering the latest sample,
    some late), permissions, lapses and watchdog trips gives the same samples, state and flags
    as a driver that gates every step."""

    class GatedEveryStep(UnitDriver):
        def advance(self, now_s: float) -> list:
            return self._advance_gated(self.unit.steps, self.unit.steps + 500, now_s + 1e-9)

    rng = np.random.default_rng(7)
    params = load_params("ch6_hems_index")
    drivers = [
        cls(ActuationUnit(params), start_time_s=1000.0) for cls in (UnitDriver, GatedEveryStep)
    ]
    now = 1000.0
    for _ in range(3000):
        now += float(rng.choice([0.0, 0.0005, 0.004, 0.01, 0.01, 0.01, 0.05]))
        action = rng.integers(10)
        outputs = []
        for driver in drivers:
            if action == 0:
                driver.permit_heating(True, now)
            elif action == 1:
                driver.permit_heating(False, now)
            elif action <= 5:
                answering = driver._sample_time_s if action <= 4 else None
                if not driver.will_rewind(30.0 * action, answering, now):
                    driver.advance(now)
                driver.command(30.0 * (action - 2) % 101, now, answering)
            outputs.append(driver.advance(now))
        assert outputs[0] == outputs[1]
        fast, gated = drivers
        assert np.array_equal(fast.unit._s, gated.unit._s)
        assert (fast.applied_duty, fast.watchdog_tripped, fast.permission_lapses) == (
            gated.applied_duty,
            gated.watchdog_tripped,
            gated.permission_lapses,
        )


def test_a_status_is_due_only_while_heating_is_allowed_and_the_last_one_runs_out():
    driver = UnitDriver(ActuationUnit(load_params("ch6_hems_index")), start_time_s=100.0)
    assert not driver.permission_lapses_by(101.0)  # nothing allowed: nothing to keep
    driver.permit_heating(True, 100.0)
    assert not driver.permission_lapses_by(100.035)
    assert driver.permission_lapses_by(100.036)
    driver.permit_heating(False, 100.02)
    assert not driver.permission_lapses_by(101.0)
