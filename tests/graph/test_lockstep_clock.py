"""The lockstep clock's rule (hems_ros.graph.lockstep_clock): a step is taken only when every
finger taking part has published, relayed and answered the current sample, and the
supervisor keeps up; the rate caps the pace; a finger that stops answering is left out."""

from __future__ import annotations

import pytest

from hems_ros.graph.lockstep_clock import LockstepClock


def _answer_all(clock: LockstepClock, fingers, at: float) -> None:
    for finger in fingers:
        clock.encoder(finger, at)
        clock.force(finger, at)
        clock.duty(finger, at)


def test_a_step_waits_for_encoder_force_and_answer_of_every_finger():
    clock = LockstepClock(("index", "middle"), start_s=1.0, step_s=0.01, rate=0.0)
    _answer_all(clock, ("index", "middle"), 1.0)
    assert clock.joined == ["index", "middle"]
    assert clock.try_advance(0.0) == pytest.approx(1.01)
    clock.encoder("index", 1.01)
    clock.force("index", 1.01)
    assert clock.try_advance(0.001) is None and clock.waiting_for() == ["index", "middle"]
    clock.duty("index", 1.01)
    _answer_all(clock, ("middle",), 1.01)
    clock.force("middle", 1.0)  # middle's module has not relayed its sample yet
    assert clock.waiting_for() == ["middle"]
    clock.force("middle", 1.01)
    assert clock.try_advance(0.002) == pytest.approx(1.02)


def test_the_rate_caps_the_pace_and_a_slow_graph_sets_it():
    clock = LockstepClock(("index",), start_s=1.0, step_s=0.01, rate=2.0)
    _answer_all(clock, ("index",), 1.0)
    # wall 10.0 is the start: the step to 1.01 is due at 10.005 at rate 2
    assert clock.try_advance(10.0) is None
    assert clock.try_advance(10.0049) is None
    assert clock.try_advance(10.0051) == pytest.approx(1.01)
    _answer_all(clock, ("index",), 1.01)
    assert clock.try_advance(12.0) == pytest.approx(1.02)  # behind: at once


def test_the_supervisor_may_lag_by_its_limit_only():
    clock = LockstepClock(("index",), start_s=1.0, step_s=0.01, rate=0.0, supervisor_lag_s=0.2)
    clock.supervisor(1.0)
    for _ in range(25):
        _answer_all(clock, ("index",), clock.now_s)
        if clock.try_advance(0.0) is None:
            break
    assert clock.now_s == pytest.approx(1.21)  # at 1.2 a status of 1.0 was still recent enough
    assert clock.waiting_for() == ["supervisor"]
    clock.supervisor(1.1)
    assert clock.try_advance(0.0) == pytest.approx(1.22)


def test_a_finger_that_stops_answering_is_left_out_after_the_stall_and_rejoins():
    clock = LockstepClock(("index", "middle"), start_s=1.0, step_s=0.01, rate=0.0, stall_s=0.5)
    _answer_all(clock, ("index", "middle"), 1.0)
    assert clock.try_advance(0.0) is not None
    _answer_all(clock, ("index",), 1.01)
    clock.encoder("middle", 1.01)  # middle's controller is gone
    assert clock.try_advance(0.1) is None
    assert clock.try_advance(0.7) == pytest.approx(1.02)
    assert clock.stalls == 1 and clock.joined == ["index"]
    _answer_all(clock, ("index", "middle"), 1.02)
    assert clock.joined == ["index", "middle"]
    assert clock.try_advance(0.71) == pytest.approx(1.03)


def test_before_anything_answers_it_runs_at_the_cap_or_real_time():
    clock = LockstepClock(("index",), start_s=1.0, step_s=0.01, rate=0.0)
    assert clock.try_advance(5.0) is None
    assert clock.try_advance(5.011) == pytest.approx(1.01)


def test_the_supervisor_lag_leaves_a_status_sent_that_keeps_a_unit_heating_through_a_step():
    # a unit waits for the status that keeps its heating permission over the next step: the
    # clock's limit on the supervisor's lag must leave that status sent
    import yaml

    from hems_ros.graph.lockstep_clock import SUPERVISOR_LAG_S
    from hems_ros.paths import config_path

    shared = yaml.safe_load(config_path("hems.yaml").read_text())["/**"]["ros__parameters"]
    step_s = LockstepClock(("index",)).step_s
    assert step_s == shared["encoder_period_s"]
    assert SUPERVISOR_LAG_S + step_s <= shared["supervisor_timeout_s"]
