"""BPID gains tuned on the model (scipy.optimize), compared with Table 5.1.

The rig follows the protocol: a chapter 5 protocol tunes on the straight actuator with the
40 N mass and compares on the five chapter 5 references, a chapter 6 position protocol on
the HEMS index unit the node graph simulates and its four position references.

Nelder-Mead over log Kp, log Kd, log Kb (and log Ki with ``with_ki``), so the gains stay
positive and the search is scale-free; the cost is the RMSE (mm) of one chapter 5 protocol
plus ``macsi_weight`` x MACSI (% per sample), the dissertation's two concerns (tracking
and control effort, Tables 5.2 and 5.4).
"""

from __future__ import annotations

import math
from dataclasses import fields
from typing import Callable

import numpy as np
from scipy.optimize import minimize

from hems_ros.control import TABLE_5_1_BPID, BPIDGains
from hems_ros.experiments.chapters import CH5_PARAMS, CH6_PARAMS
from hems_ros.experiments.dissertation import CH5_PROTOCOLS, CH6_POSITION
from hems_ros.experiments.lockstep import run_protocol
from hems_ros.physics.params import load_params

KI_START = 0.01
TUNABLE = CH5_PROTOCOLS + CH6_POSITION


def rig(protocol: str) -> tuple[str, tuple[str, ...]]:
    """(physics set, references to compare on) of the chapter ``protocol`` belongs to."""
    if protocol in CH5_PROTOCOLS:
        return CH5_PARAMS, CH5_PROTOCOLS
    if protocol in CH6_POSITION:
        return CH6_PARAMS, CH6_POSITION
    raise ValueError(f"cannot tune on {protocol!r}: expected one of {', '.join(TUNABLE)}")


def _gains(x: np.ndarray, with_ki: bool) -> BPIDGains:
    kp, kd, kb = np.exp(x[:3])
    ki = float(np.exp(x[3])) if with_ki else 0.0
    return BPIDGains(kp=float(kp), ki=ki, kd=float(kd), kb=float(kb))


def tune_bpid(
    protocol: str = "ch5_step",
    macsi_weight: float = 0.1,
    with_ki: bool = False,
    max_evaluations: int = 120,
    progress: Callable[[int, BPIDGains, float], None] | None = None,
):
    """(tuned gains, cost of Table 5.1, tuned cost) on ``protocol`` with its chapter's rig."""
    params = load_params(rig(protocol)[0])
    start = TABLE_5_1_BPID
    x0 = np.log([start.kp, start.kd, start.kb] + ([KI_START] if with_ki else []))
    count = [0]

    def cost_of(gains: BPIDGains) -> float:
        m = run_protocol(protocol, "bpid", params, gains).metrics
        return m["rmse"] + macsi_weight * m["macsi"]

    def cost(x):
        gains = _gains(x, with_ki)
        value = cost_of(gains)
        count[0] += 1
        if progress is not None:
            progress(count[0], gains, value)
        return value if math.isfinite(value) else 1e9

    # Simplex edges of a factor 3 per gain: the cost is piecewise flat (chattering loops), so
    # scipy's default 5 % edges would stall at the start.
    simplex = np.vstack([x0, x0 + np.log(3.0) * np.eye(x0.size)])
    result = minimize(
        cost,
        x0,
        method="Nelder-Mead",
        options={
            "maxfev": max_evaluations,
            "xatol": 1e-2,
            "fatol": 1e-3,
            "initial_simplex": simplex,
        },
    )
    tuned = _gains(result.x, with_ki)
    return tuned, cost_of(start), cost_of(tuned)


def compare(
    tuned: BPIDGains, protocol: str = "ch5_step"
) -> list[tuple[str, dict[str, float], dict[str, float]]]:
    """(reference, Table 5.1 metrics, tuned metrics) on every reference of ``protocol``'s rig."""
    name, references = rig(protocol)
    params = load_params(name)
    return [
        (p, run_protocol(p, "bpid", params).metrics, run_protocol(p, "bpid", params, tuned).metrics)
        for p in references
    ]


def params_file_text(gains: BPIDGains, note: str) -> str:
    """A ROS params file giving every finger controller ``gains`` in position mode (the
    ``gains.*`` parameters of hems_ros.nodes.finger_controller), with ``note`` as a comment:
    applied over config/hems.yaml by ``hems up --extra-params FILE`` or a second
    ``--params-file`` of ``ros2 run``."""
    lines = [f"# {line}" for line in note.splitlines()]
    lines += ["/**:", "  ros__parameters:", "    strategy: bpid"]
    lines += [f"    gains.{f.name}: {float(getattr(gains, f.name))!r}" for f in fields(gains)]
    return "\n".join(lines) + "\n"
