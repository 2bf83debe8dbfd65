"""PI-PD with commuted feed-forward, eqs. 5.11-5.21, against hand-computed sequences."""

import pytest

from hems_ros.control import PIPDGains, make_controller
from hems_ros.control.pipd import pd_coefficients, pi_coefficients

UM = 1e-6


def test_pi_coefficients_eq_5_15():
    # Kp 2, Ki 1, Ts 0.1: a0 1, a1 -1, b0 = 2 + 0.1 = 2.1, b1 = -2
    assert pi_coefficients(2.0, 1.0, 0.1) == pytest.approx((1, -1, 2.1, -2))


def test_pd_coefficients_eq_5_19():
    # Kp 1, Kd 0.5, N 10, Ts 0.1: a0 = 1 + 1 = 2, a1 -1, b0 = 1*2 + 0.5*10 = 7, b1 = -(1 + 5) = -6
    assert pd_coefficients(1.0, 0.5, 10.0, 0.1) == pytest.approx((2, -1, 7, -6))


def test_table_5_1_coefficients():
    c = make_controller("pipd", "position")
    # PI: b0 = 0.8 + 0.25*0.01 = 0.8025, b1 = -0.8
    assert c.pi_coefficients == pytest.approx((1, -1, 0.8025, -0.8))
    # PD (N 20, Ts 0.01): a0 1.2, b0 = 0.08*1.2 + 0.003*20 = 0.156, b1 = -(0.08 + 0.06) = -0.14
    assert c.pd_coefficients == pytest.approx((1.2, -1, 0.156, -0.14))


def test_sequence_switches_pi_pd_and_feed_forward():
    gains = PIPDGains(kp_pi=2, ki_pi=1, kp_pd=1, kd_pd=0.5, u_ff=3)
    c = make_controller("pipd", "position", gains, ts=0.1, n_filter=10)
    # PI: uc = uc(k-1) + 2.1 e(k) - 2 e(k-1);  PD: uc = (uc(k-1) + 7 e(k) - 6 e(k-1)) / 2
    # r = 0, 1, 2, 2, 2, 1 um, y = 0, r(-1) = 0
    uc0 = (0 + 7 * 0 - 6 * 0) / 2  # r constant: PD, no feed-forward
    uc1 = uc0 + 2.1 * 1 - 2 * 0  # rising: PI, + 3
    uc2 = uc1 + 2.1 * 2 - 2 * 1  # rising: PI, + 3
    uc3 = (uc2 + 7 * 2 - 6 * 2) / 2  # constant: PD
    uc4 = (uc3 + 7 * 2 - 6 * 2) / 2  # constant: PD
    uc5 = uc4 + 2.1 * 1 - 2 * 2  # falling: PI, no feed-forward
    expected = [uc0, uc1 + 3, uc2 + 3, uc3, uc4, uc5]
    assert expected == pytest.approx([0, 5.1, 7.3, 3.15, 2.575, 0.675])
    out = [c.update(r * UM, 0.0) for r in (0, 1, 2, 2, 2, 1)]
    assert out == pytest.approx(expected, rel=1e-9, abs=1e-12)
