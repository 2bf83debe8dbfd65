"""PID with filtered derivative, eqs. 5.5-5.10, against hand-computed sequences."""

import pytest

from hems_ros.control import PIDGains, make_controller
from hems_ros.control.pid import pid_coefficients

UM = 1e-6  # position mode scales metres to micrometres, so r = e * UM gives a scaled error e


def test_coefficients_eq_5_8():
    # Kp 2, Ki 1, Kd 0.5, N 10, Ts 0.1 -> N Ts = 1
    # a0 = 1 + 1 = 2, a1 = -(2 + 1) = -3, a2 = 1
    # b0 = 2*2 + 1*0.1*2 + 0.5*10 = 9.2
    # b1 = -(2*3 + 1*0.1 + 2*0.5*10) = -16.1
    # b2 = 2 + 0.5*10 = 7
    assert pid_coefficients(2.0, 1.0, 0.5, 10.0, 0.1) == pytest.approx((2, -3, 1, 9.2, -16.1, 7))


def test_coefficients_table_5_1_defaults():
    # Kp 0.8, Ki 0, Kd 0.05, N 20, Ts 0.01 -> N Ts = 0.2
    # a0 = 1.2, a1 = -2.2, a2 = 1, b0 = 0.8*1.2 + 0.05*20 = 1.96,
    # b1 = -(0.8*2.2 + 2*0.05*20) = -3.76, b2 = 0.8 + 0.05*20 = 1.8
    c = make_controller("pid", "position")
    assert c.coefficients == pytest.approx((1.2, -2.2, 1, 1.96, -3.76, 1.8))


def test_sequence_eq_5_5_with_integral():
    c = make_controller("pid", "position", PIDGains(kp=2, ki=1, kd=0.5), ts=0.1, n_filter=10)
    # u(k) = 3/2 u(k-1) - 1/2 u(k-2) + 9.2/2 e(k) - 16.1/2 e(k-1) + 7/2 e(k-2)
    u0 = 4.6 * 1
    u1 = 1.5 * u0 + 4.6 * 2 - 8.05 * 1
    u2 = 1.5 * u1 - 0.5 * u0 + 4.6 * 3 - 8.05 * 2 + 3.5 * 1
    u3 = 1.5 * u2 - 0.5 * u1 + 4.6 * 3 - 8.05 * 3 + 3.5 * 2
    u4 = 1.5 * u3 - 0.5 * u2 + 4.6 * 3 - 8.05 * 3 + 3.5 * 3
    # cross-check by parts: P = 2e, I = 0.1 sum(e), D(k) = (D(k-1) + 5 (e(k) - e(k-1))) / 2
    assert [u0, u1, u2, u3, u4] == pytest.approx([4.6, 8.05, 10.975, 9.0875, 8.29375])
    out = [c.update(e * UM, 0.0) for e in (1, 2, 3, 3, 3)]
    assert out == pytest.approx([u0, u1, u2, u3, u4], rel=1e-9)


def test_sequence_table_5_1_pd():
    c = make_controller("pid", "position")
    # e = 10 um constant; u(k) = (2.2 u(k-1) - u(k-2) + 1.96 e(k) - 3.76 e(k-1) + 1.8 e(k-2)) / 1.2
    u0 = 1.96 * 10 / 1.2
    u1 = (2.2 * u0 + 1.96 * 10 - 3.76 * 10) / 1.2
    u2 = (2.2 * u1 - u0 + 1.96 * 10 - 3.76 * 10 + 1.8 * 10) / 1.2
    # by parts: P = 8, D = 10/1.2 decaying by 1/1.2 per sample
    assert [u0, u1, u2] == pytest.approx([8 + 10 / 1.2, 8 + 10 / 1.44, 8 + 10 / 1.728])
    out = [c.update(10 * UM, 0.0) for _ in range(3)]
    assert out == pytest.approx([u0, u1, u2], rel=1e-9)


def test_error_is_reference_minus_measurement():
    c = make_controller("pid", "position", PIDGains(kp=1, ki=0, kd=0))
    assert c.update(30 * UM, 10 * UM) == pytest.approx(20)
