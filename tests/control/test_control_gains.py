"""Gain sets: Table 5.1 by name, validation naming the gain, factory arguments."""

import math

import pytest

from hems_ros.control import (
    DEFAULT_N_FILTER,
    FORCE_MODE_BPID,
    FORCE_SCALE,
    TABLE_5_1,
    UM_PER_M,
    BPIDGains,
    PIDGains,
    PIPDGains,
    make_controller,
)


def test_table_5_1_by_name():
    assert TABLE_5_1["bpid"] == BPIDGains(kp=0.8, ki=0, kd=0.05, kb=1)
    assert TABLE_5_1["pid"] == PIDGains(kp=0.8, ki=0, kd=0.05)
    assert TABLE_5_1["pipd"] == PIPDGains(kp_pi=0.8, ki_pi=0.25, kp_pd=0.08, kd_pd=0.003, u_ff=3)
    with pytest.raises(TypeError):
        TABLE_5_1["pid"] = PIDGains(kp=1, ki=0, kd=0)


def test_scales_default_to_micrometres_and_force_scale():
    g = TABLE_5_1["bpid"]
    assert (g.position_scale, g.force_scale) == (UM_PER_M, FORCE_SCALE) == (1e6, 400.0)
    assert g.scale_for("position") == 1e6
    assert g.scale_for("force") == 400.0


def test_force_mode_bpid_set():
    # Kd 0 (the HEMS force already carries the contraction rate), error in 10 mN, Ki holds it.
    assert FORCE_MODE_BPID == BPIDGains(kp=0.4, ki=0.2, kd=0.0, kb=1.0, force_scale=100.0)
    assert FORCE_MODE_BPID.scale_for("force") == 100.0


@pytest.mark.parametrize(
    "cls, kwargs, name",
    [
        (PIDGains, dict(kp=-0.1, ki=0, kd=0), "kp"),
        (PIDGains, dict(kp=1, ki=math.nan, kd=0), "ki"),
        (PIDGains, dict(kp=1, ki=0, kd=math.inf), "kd"),
        (BPIDGains, dict(kp=1, ki=0, kd=0, kb=-1), "kb"),
        (BPIDGains, dict(kp=1, ki=0, kd=0, kb=math.nan), "kb"),
        (PIPDGains, dict(kp_pi=1, ki_pi=1, kp_pd=1, kd_pd=1, u_ff=-3), "u_ff"),
        (PIPDGains, dict(kp_pi=1, ki_pi=-math.inf, kp_pd=1, kd_pd=1, u_ff=3), "ki_pi"),
        (PIDGains, dict(kp=1, ki=0, kd=0, position_scale=0), "position_scale"),
        (PIDGains, dict(kp=1, ki=0, kd=0, force_scale=-1e3), "force_scale"),
    ],
)
def test_bad_gains_rejected_naming_the_gain(cls, kwargs, name):
    with pytest.raises(ValueError, match=rf"\b{name}\b"):
        cls(**kwargs)


def test_non_numeric_gain_rejected():
    with pytest.raises(TypeError, match="kd"):
        PIDGains(kp=1, ki=0, kd="0.05")


def test_factory_defaults_and_errors():
    c = make_controller("bpid", "position")
    assert c.gains is TABLE_5_1["bpid"]
    assert (c.ts, c.n_filter) == (0.01, DEFAULT_N_FILTER)
    with pytest.raises(ValueError, match="strategy"):
        make_controller("lqr", "position")
    with pytest.raises(ValueError, match="mode"):
        make_controller("pid", "velocity")
    with pytest.raises(ValueError, match="ts"):
        make_controller("pid", "position", ts=0)
    with pytest.raises(ValueError, match="n_filter"):
        make_controller("pid", "position", n_filter=math.nan)
    with pytest.raises(TypeError, match="PIPDGains"):
        make_controller("pipd", "position", TABLE_5_1["pid"])
    with pytest.raises(ValueError, match="mode"):
        c.set_mode("torque", 0.0)
