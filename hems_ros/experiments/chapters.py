"""The dissertation's closed-loop experiments in simulation (dissertation chapters 5 and 6).

Chapter 5: the five references x three controllers (Table 5.1 gains) on the straight
sheathed actuator with a 40 N hanging mass (``ch5_straight_40n``). Chapter 6: BPID on the
HEMS index unit (``ch6_hems_index``, 2 N bias pretension on the tendon), four position and
four force references.

Force references start at the unit's rest wire tension. The protocol generators put the
rest at 2 N, the bias pretension, but that acts on the tendon behind the x2 pulley, so the
wire (where the force sensor sits, dissertation chapter 6) rests at 4 N and cannot go lower; a
reference below it would count an unreachable 2 N into the RMSE of every ascent. The top
stays at 20 N, the largest amplitude reported.
"""

from __future__ import annotations

import dataclasses
from typing import Callable, Mapping

from hems_ros.control import FORCE_MODE_BPID
from hems_ros.control.references import (
    CH6_FORCE_PEAK,
    PROTOCOLS,
    Protocol,
    sine,
    staircase,
    step_pair,
)
from hems_ros.experiments.dissertation import CH5_PROTOCOLS, CH5_STRATEGIES, CH6_FORCE, CH6_POSITION
from hems_ros.experiments.lockstep import LockstepRun, run_protocol
from hems_ros.physics.params import UnitParams, load_params

CH5_PARAMS = "ch5_straight_40n"
CH6_PARAMS = "ch6_hems_index"
Progress = Callable[[str], None] | None


def rest_wire_tension(params: UnitParams) -> float:
    """Wire tension of the unit at rest, N: the load's static force times the pulley ratio."""
    return params.load.pulley_ratio * params.load.static_force_n()


def force_protocol(name: str, rest: float) -> Protocol:
    """Chapter 6 force protocol ``name`` with its low level at ``rest`` N (module docstring)."""
    span = CH6_FORCE_PEAK - rest
    proto = PROTOCOLS[name]
    if "sine" in name:
        f = float(name.rsplit("_", 1)[1])
        make, what = (
            (lambda ts: sine(f, span, ts, base=rest)),
            f"sine {rest:g}-{CH6_FORCE_PEAK:g} N at {f} Hz",
        )
    elif name.endswith("step"):
        make, what = (
            (lambda ts: step_pair(span, ts, base=rest)),
            f"two {rest:g} -> {CH6_FORCE_PEAK:g} N steps",
        )
    else:
        make, what = (
            (lambda ts: staircase(span / 4, ts, base=rest)),
            f"{rest:g} -> {CH6_FORCE_PEAK:g} N in 4 steps and back",
        )
    return dataclasses.replace(proto, make=make, description=what)


def _report(progress: Progress, run: LockstepRun, unit: str) -> None:
    if progress is not None:
        m = run.metrics
        progress(
            f"  {run.protocol:<24} {run.strategy:<5} RMSE {m['rmse']:7.3f} {unit}  "
            f"MACSI {m['macsi']:6.2f} %  APC {m['apc_w']:5.1f} W"
            + (f"  FAULT: {run.fault}" if run.fault else "")
        )


def run_ch5(
    gains: Mapping[str, object] | None = None,
    params: UnitParams | str = CH5_PARAMS,
    progress: Progress = None,
    **kwargs,
) -> dict[tuple[str, str], LockstepRun]:
    """All chapter 5 runs by (protocol, strategy); ``gains`` overrides Table 5.1 per strategy."""
    prm = params if isinstance(params, UnitParams) else load_params(params)
    runs = {}
    for name in CH5_PROTOCOLS:
        for strategy in CH5_STRATEGIES:
            run = run_protocol(name, strategy, prm, (gains or {}).get(strategy), **kwargs)
            runs[name, strategy] = run
            _report(progress, run, "mm")
    return runs


def run_ch6(
    gains=None,
    params: UnitParams | str = CH6_PARAMS,
    progress: Progress = None,
    force_gains=FORCE_MODE_BPID,
    **kwargs,
) -> dict[str, LockstepRun]:
    """All chapter 6 runs (BPID) by protocol name.

    Position references run with ``gains`` (default Table 5.1), force references with
    ``force_gains`` (default :data:`hems_ros.control.FORCE_MODE_BPID`, see
    :mod:`hems_ros.control.gains` for why force mode needs its own set).
    """
    prm = params if isinstance(params, UnitParams) else load_params(params)
    rest = rest_wire_tension(prm)
    runs = {}
    for name in CH6_POSITION + CH6_FORCE:
        force = name in CH6_FORCE
        proto = force_protocol(name, rest) if force else PROTOCOLS[name]
        run = run_protocol(proto, "bpid", prm, force_gains if force else gains, **kwargs)
        runs[name] = run
        _report(progress, run, "mm" if run.mode == "position" else "N")
    return runs
