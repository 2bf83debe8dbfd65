"""Four-term bilinear PID, eq. 5.36, against hand-computed sequences."""

import pytest

from hems_ros.control import BPIDGains, PIDGains, make_controller
from hems_ros.control.bpid import bilinear_factor

UM = 1e-6


def test_bilinear_factor():
    assert bilinear_factor(0.5, 10.0, 0.0) == pytest.approx((1 + 5) / 1)
    assert bilinear_factor(1.0, 10.0, 10.0) == pytest.approx(1.0)
    assert bilinear_factor(0.1, 10.0, 5.0) == pytest.approx(2 / 1.5)
    # negative values are clipped at 0: (1 + 10) / (1 + 0), not 11 / -2
    assert bilinear_factor(1.0, 10.0, -3.0) == pytest.approx(11.0)
    assert bilinear_factor(1.0, -5.0, 4.0) == pytest.approx(1 / 5)


def test_proportional_times_factor_uses_previous_measurement():
    c = make_controller("bpid", "position", BPIDGains(kp=1, ki=0, kd=0, kb=0.5))
    # r = 10 um; y = 0, 4, 8, 10 um; u = Kp e(k) (1 + 0.5*10) / (1 + 0.5 y(k-1))
    expected = [10 * 6 / 1, 6 * 6 / 1, 2 * 6 / (1 + 0.5 * 4), 0 * 6 / (1 + 0.5 * 8)]
    assert expected == pytest.approx([60, 36, 4, 0])
    out = [c.update(10 * UM, y * UM) for y in (0, 4, 8, 10)]
    assert out == pytest.approx(expected, rel=1e-9, abs=1e-9)


def test_sequence_with_filtered_derivative():
    c = make_controller("bpid", "position", BPIDGains(kp=0.8, ki=0, kd=0.05, kb=0.1))
    # PID part as eq. 5.5 with a0 1.2, a1 -2.2, a2 1, b0 1.96, b1 -3.76, b2 1.8 (N 20, Ts 0.01)
    # r = 10 um, y = 0, 5, 8 um -> e = 10, 5, 2
    p0 = 1.96 * 10 / 1.2
    p1 = (2.2 * p0 + 1.96 * 5 - 3.76 * 10) / 1.2
    p2 = (2.2 * p1 - p0 + 1.96 * 2 - 3.76 * 5 + 1.8 * 10) / 1.2
    f0 = (1 + 0.1 * 10) / (1 + 0.1 * 0)
    f1 = (1 + 0.1 * 10) / (1 + 0.1 * 0)
    f2 = (1 + 0.1 * 10) / (1 + 0.1 * 5)
    expected = [p0 * f0, p1 * f1, p2 * f2]
    assert expected == pytest.approx([32.6667, 13.5556, 1.8864], abs=1e-4)
    out = [c.update(10 * UM, y * UM) for y in (0, 5, 8)]
    assert out == pytest.approx(expected, rel=1e-9)


def test_zero_kb_is_the_pid():
    bpid = make_controller("bpid", "position", BPIDGains(kp=0.8, ki=0.3, kd=0.05, kb=0))
    pid = make_controller("pid", "position", PIDGains(kp=0.8, ki=0.3, kd=0.05))
    for r, y in [(10, 0), (10, 3), (12, 7), (12, 11), (5, 12)]:
        assert bpid.update(r * UM, y * UM) == pytest.approx(pid.update(r * UM, y * UM))


def test_factor_is_one_at_the_setpoint():
    c = make_controller("bpid", "position", BPIDGains(kp=1, ki=0, kd=0, kb=1))
    c.update(20 * UM, 20 * UM)
    # y(k-1) = r = 20 um: factor 21/21, u = Kp e = 1 * 3
    assert c.update(20 * UM, 17 * UM) == pytest.approx(3.0)
