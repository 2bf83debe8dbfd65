"""Discrete controllers of the SMA actuators (dissertation chapter 5), plain Python, no ROS.

``make_controller`` is the entry point for the per-finger node and the lockstep
experiments; :mod:`.metrics` and :mod:`.references` hold the figures of merit and the
dissertation's test protocols.
"""

from __future__ import annotations

from hems_ros.control.base import (
    DEFAULT_N_FILTER,
    DEFAULT_TRANSFER_TAU,
    DEFAULT_TS,
    MODES,
    Controller,
)
from hems_ros.control.bpid import BPIDController
from hems_ros.control.gains import (
    FORCE_MODE_BPID,
    FORCE_SCALE,
    MN_PER_N,
    TABLE_5_1,
    TABLE_5_1_BPID,
    UM_PER_M,
    BPIDGains,
    Gains,
    PIDGains,
    PIPDGains,
    mode_gains,
)
from hems_ros.control.pid import PIDController
from hems_ros.control.pipd import PIPDController
from hems_ros.duty import DUTY_MAX, DUTY_MIN

CONTROLLERS = {cls.strategy: cls for cls in (BPIDController, PIDController, PIPDController)}
STRATEGIES = tuple(CONTROLLERS)


def make_controller(
    strategy: str,
    mode: str,
    gains: Gains | None = None,
    ts: float = DEFAULT_TS,
    n_filter: float = DEFAULT_N_FILTER,
    transfer_tau: float = DEFAULT_TRANSFER_TAU,
) -> Controller:
    """Make the ``strategy`` controller ("bpid", "pid", "pipd") in ``mode`` ("position", "force").

    ``gains`` defaults to the Table 5.1 set of the strategy; ``ts`` is the sample period in
    s, ``n_filter`` the derivative filter pole N in rad/s, ``transfer_tau`` the decay time
    in s of the bumpless mode-switch term.
    """
    try:
        cls = CONTROLLERS[strategy]
    except KeyError:
        raise ValueError(f"strategy must be one of {STRATEGIES}, got {strategy!r}") from None
    chosen = TABLE_5_1[strategy] if gains is None else gains
    return cls(chosen, mode, ts=ts, n_filter=n_filter, transfer_tau=transfer_tau)


__all__ = [
    "BPIDController",
    "BPIDGains",
    "CONTROLLERS",
    "Controller",
    "DEFAULT_N_FILTER",
    "DEFAULT_TRANSFER_TAU",
    "DEFAULT_TS",
    "DUTY_MAX",
    "DUTY_MIN",
    "FORCE_MODE_BPID",
    "FORCE_SCALE",
    "Gains",
    "MN_PER_N",
    "MODES",
    "PIDController",
    "PIDGains",
    "PIPDController",
    "PIPDGains",
    "STRATEGIES",
    "TABLE_5_1",
    "TABLE_5_1_BPID",
    "mode_gains",
    "UM_PER_M",
    "make_controller",
]
