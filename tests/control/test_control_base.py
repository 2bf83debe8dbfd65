"""Clamp, anti-windup, scaling, bumpless mode switch, reset and faults of all controllers."""

import math

import pytest

from hems_ros.control import STRATEGIES, TABLE_5_1, BPIDGains, PIDGains, PIPDGains, make_controller

UM = 1e-6


def test_clamp_and_no_memory_shift_without_integral():
    c = make_controller("pid", "position", PIDGains(kp=1, ki=0, kd=0))
    assert c.update(200 * UM, 0) == 100.0
    assert c.update(-5 * UM, 0) == 0.0
    # Ki = 0: the output is the position-form P law again, 1 * 50
    assert c.update(50 * UM, 0) == pytest.approx(50.0)


def test_pid_anti_windup():
    # pure I, Ki 1, Ts 0.1: u(k) = u(k-1) + 0.1 e(k)
    c = make_controller("pid", "position", PIDGains(kp=0, ki=1, kd=0), ts=0.1)
    for _ in range(10):
        assert c.update(1000 * UM, 0) == 100.0
    # without anti-windup the memory would be 10 * 100 = 1000 and stay saturated;
    # held at 100 it answers the negative error at once: 100 + 0.1 * (-10) = 99
    assert c.update(-10 * UM, 0) == pytest.approx(99.0)
    assert c.update(-10 * UM, 0) == pytest.approx(98.0)


def test_anti_windup_ignores_saturating_derivative_kick():
    # Kp 0, Ki 1, Kd 0.5, N 10, Ts 0.1 (N Ts = 1): by parts I(k) = I(k-1) + 0.1 e(k) and
    # D(k) = (D(k-1) + 5 (e(k) - e(k-1))) / 2, so for e = 2000 from k = 0, D(k) = 5000 / 2^k.
    c = make_controller("pid", "position", PIDGains(kp=0, ki=1, kd=0.5), ts=0.1, n_filter=10)
    # k = 0..5: D >= 156.25 saturates alone, every increment of 200 is cut, I stays 0.
    # k = 6: D 78.125, I may rise to 100 - 78.125 = 21.875; k = 7: D 39.0625, I -> 60.9375.
    # The output stays at 100 throughout (clamping the memory instead would drop it to 0
    # at k = 1, when the kick starts to decay).
    assert [c.update(2000 * UM, 0) for _ in range(8)] == [100.0] * 8
    i7 = 100 - 5000 / 2**7
    # e = 0 from k = 8: D(8) = (39.0625 - 5 * 2000) / 2, then halves; I holds at 60.9375
    d8 = (5000 / 2**7 - 5 * 2000) / 2
    out = [c.update(0.0, 0.0) for _ in range(20)]
    assert out[0] == 0.0
    assert out[-1] == pytest.approx(i7 + d8 / 2**19, rel=1e-9)
    assert i7 + d8 / 2**19 == pytest.approx(60.9280, abs=1e-4)


def test_bpid_anti_windup_on_product():
    c = make_controller("bpid", "position", BPIDGains(kp=0, ki=100, kd=0, kb=0.1), ts=0.1)
    # r 10 um, y 0: PID memory 0.1*100*10 = 100, factor (1 + 1) / 1 = 2 -> 200 -> 100,
    # memory held at 100 / 2 = 50
    assert c.update(10 * UM, 0) == 100.0
    # e 0: memory 50, factor 2 / (1 + 0) -> 100
    assert c.update(10 * UM, 10 * UM) == pytest.approx(100.0)
    # factor 2 / (1 + 0.1*10) = 1 -> 50 (it would be 100 with a wound-up memory)
    assert c.update(10 * UM, 10 * UM) == pytest.approx(50.0)


def test_pipd_anti_windup_accounts_for_feed_forward():
    gains = PIPDGains(kp_pi=0, ki_pi=1, kp_pd=0, kd_pd=0, u_ff=3)
    c = make_controller("pipd", "position", gains, ts=0.1)
    # rising: uc = uc(k-1) + 0.1 e, held at 100 - 3 = 97, output 97 + 3
    assert c.update(1000 * UM, 0) == 100.0
    assert c.update(2000 * UM, 0) == 100.0
    # falling, no feed-forward: 97 + 0.1 * 10 = 98
    assert c.update(10 * UM, 0) == pytest.approx(98.0)


def test_force_mode_scale_is_400_per_newton():
    c = make_controller("pid", "force", PIDGains(kp=1, ki=0, kd=0))
    assert c.update(0.030, 0.005) == pytest.approx(10.0)
    custom = make_controller("pid", "force", PIDGains(kp=1, ki=0, kd=0, force_scale=1.0))
    assert custom.update(12.0, 2.0) == pytest.approx(10.0)


@pytest.mark.parametrize("strategy", STRATEGIES)
def test_bumpless_switch(strategy):
    c = make_controller(strategy, "position")
    for _ in range(50):
        before = c.update(15 * UM, 10 * UM)
    assert 0 < before < 100
    c.set_mode("force", 5.0)
    assert c.mode == "force"
    # new reference at the measurement: the duty continues, then the transfer term decays
    assert c.update(5.0, 5.0) == pytest.approx(before)
    assert c.update(5.0, 5.0) == pytest.approx(before * math.exp(-0.01 / 1.0))
    # and the new loop acts on the force error (in mN)
    assert c.update(5.001, 5.0) > before * math.exp(-0.02)


def test_default_gains_per_mode():
    from hems_ros.control import FORCE_MODE_BPID, mode_gains

    assert mode_gains("bpid", "force") is FORCE_MODE_BPID
    assert mode_gains("bpid", "position") is TABLE_5_1["bpid"]
    assert (
        mode_gains("pid", "force") is TABLE_5_1["pid"]
        and mode_gains("pipd", "force") is TABLE_5_1["pipd"]
    )


def test_a_switch_can_bring_the_new_modes_gains():
    from hems_ros.control import FORCE_MODE_BPID

    switched = make_controller("bpid", "position")
    for _ in range(50):
        before = switched.update(15 * UM, 10 * UM)
    switched.set_mode("force", 5.0, FORCE_MODE_BPID)
    assert switched.gains is FORCE_MODE_BPID
    assert switched.update(5.0, 5.0) == pytest.approx(before)  # still bumpless
    fresh = make_controller("bpid", "force", FORCE_MODE_BPID)
    reference = [fresh.update(5.5, 5.0) for _ in range(5)]
    switched.reset()
    assert [switched.update(5.5, 5.0) for _ in range(5)] == reference  # and the force set acts
    with pytest.raises(TypeError, match="BPIDGains"):
        switched.set_mode("position", 0.0, TABLE_5_1["pid"])


@pytest.mark.parametrize("strategy", STRATEGIES)
def test_release_after_a_mode_switch_drops_the_transfer_term(strategy):
    c = make_controller(strategy, "force")
    for _ in range(50):
        held = c.update(20.0, 19.99)
    assert held > 0
    c.set_mode("position", 0.026)
    # release: position setpoint 0 below the measured 26 mm: no carried-over heating
    assert c.update(0.0, 0.026) == 0.0


@pytest.mark.parametrize("strategy", STRATEGIES)
def test_switch_to_same_mode_keeps_state(strategy):
    a = make_controller(strategy, "position")
    b = make_controller(strategy, "position")
    for r in (0.0, 1e-5, 2e-5, 2e-5):
        a.update(r, 5e-6)
        b.update(r, 5e-6)
    a.set_mode("position", 5e-6)
    assert a.update(2e-5, 6e-6) == b.update(2e-5, 6e-6)


@pytest.mark.parametrize("strategy", STRATEGIES)
def test_reset_restores_initial_conditions(strategy):
    c = make_controller(strategy, "position")
    fresh = [c.update(r, 0.0) for r in (1e-6, 3e-6, 3e-6, 2e-6)]
    c.set_mode("force", 1.0)
    c.update(3.0, 1.0)
    c.reset()
    assert c.fault is None
    c.set_mode("position", 0.0)
    c.reset()
    assert [c.update(r, 0.0) for r in (1e-6, 3e-6, 3e-6, 2e-6)] == fresh


@pytest.mark.parametrize("strategy", STRATEGIES)
@pytest.mark.parametrize(
    "reference, measurement, word",
    [
        (math.nan, 0.0, "reference"),
        (math.inf, 0.0, "reference"),
        (0.01, math.nan, "measurement"),
        (0.01, -math.inf, "measurement"),
    ],
)
def test_non_finite_input_gives_zero_duty_and_latched_fault(strategy, reference, measurement, word):
    c = make_controller(strategy, "position")
    assert c.update(0.01, 0.0) == 100.0
    assert c.fault is None
    assert c.update(reference, measurement) == 0.0
    assert word in c.fault
    assert c.update(0.01, 0.0) == 0.0
    assert word in c.fault
    c.reset()
    assert c.fault is None
    assert c.update(0.01, 0.0) == 100.0


def test_non_finite_measurement_at_mode_switch():
    c = make_controller("bpid", "position")
    c.update(0.01, 0.0)
    c.set_mode("force", math.nan)
    assert "measurement" in c.fault
    assert c.update(5.0, 1.0) == 0.0


def test_attributes_and_float_output():
    c = make_controller("pipd", "force")
    assert (c.strategy, c.mode, c.fault, c.ts) == ("pipd", "force", None, 0.01)
    assert type(c.update(3.0, 2.0)) is float
