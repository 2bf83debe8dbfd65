"""In-process lockstep of one controller and one actuation unit (dissertation chapters 5 and 6).

The plant runs at ``dt`` (1 kHz default) through the physics kernel's single step, the
controller at ``ts`` (100 Hz default); the duty is held constant between control samples
(zero-order hold), as the PWM board of the HEMS holds it between MCU updates.

Timing of one control sample k (time k Ts):

1. the controller reads the sensors as they are at k Ts: the encoder (position mode,
   integer counts of 1 um) or the force sensor (force mode, seeded noise, 0.01 N steps);
2. it returns u(k), the duty held for the next Ts;
3. the plant takes Ts/dt steps with u(k).

Sample 0 reads the initial state (noise-free: no plant step has drawn noise yet). Every
plant step draws one standard-normal force-sensor sample from the set's seeded generator,
as :class:`hems_ros.physics.ActuationUnit` does, so :func:`run_protocol` reproduces a loop
built on the stepping API reading after every step (the ROS node graph) sample for sample
(tests/experiments/test_lockstep.py).

:func:`run_protocol` is the entry point: one protocol of
:data:`hems_ros.control.references.PROTOCOLS` (or any reference array), one controller, one
physics parameter set; it returns the time, reference, measurement and duty arrays, the
simulation truth and the figures of merit (:func:`figures`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from hems_ros.control import DEFAULT_N_FILTER, DEFAULT_TS, make_controller, metrics
from hems_ros.control.references import PROTOCOLS, Protocol
from hems_ros.physics import kernel, rows, sensors
from hems_ros.physics.electrical import DRIVE_NAMES
from hems_ros.physics.params import UnitParams, load_params

DEFAULT_DT = 1e-3
_DUTY = DRIVE_NAMES["duty"]


@dataclass
class LockstepRun:
    """One closed-loop run, every array sampled at the control period.

    ``measurement`` is what the controller saw (m or N); ``duty`` in % is what it returned
    at the same sample; ``position_m`` / ``wire_force_n`` / ``power_w`` are the simulation
    truth at the sample time (power: mean electrical power of the following hold).
    """

    protocol: str
    strategy: str
    mode: str
    params_name: str
    time: np.ndarray
    reference: np.ndarray
    measurement: np.ndarray
    duty: np.ndarray
    position_m: np.ndarray
    wire_force_n: np.ndarray
    power_w: np.ndarray
    segment: str = "all"
    fault: str | None = None
    metrics: dict[str, float] = field(default_factory=dict)


def _params(params: UnitParams | str) -> UnitParams:
    return params if isinstance(params, UnitParams) else load_params(params)


def simulate_loop(
    reference: np.ndarray,
    strategy: str,
    mode: str,
    params: UnitParams | str,
    gains=None,
    ts: float = DEFAULT_TS,
    dt: float = DEFAULT_DT,
    n_filter: float = DEFAULT_N_FILTER,
    start_temperature_c: float | None = None,
):
    """Closed loop over ``reference`` (one value per control sample, SI unit of ``mode``).

    The unit starts cold (ambient) unless ``start_temperature_c`` is given
    (:func:`hems_ros.physics.rows.initial_state`). Returns (measurement, duty,
    position_m, wire_force_n, power_w, fault); the arrays are cut at the sample where a
    controller fault or a non-finite plant state stopped the run.
    """
    prm = _params(params)
    sub = int(round(ts / dt))
    if sub < 1 or not math.isclose(sub * dt, ts, rel_tol=1e-9):
        raise ValueError(f"ts = {ts} s must be a whole number of plant steps dt = {dt} s")
    ref = np.asarray(reference, dtype=float)
    n = ref.size
    controller = make_controller(strategy, mode, gains, ts=ts, n_filter=n_filter)
    p = rows.pack(prm)
    s = rows.initial_state(prm, start_temperature_c)
    out = np.zeros(rows.N_O)
    enc, fs = prm.encoder, prm.force_sensor
    # One draw per plant step, in order: the reading at sample k (after step k*sub) uses
    # draw k*sub - 1.
    noise = (
        sensors.noise_generator(fs.seed).standard_normal(n * sub)[sub - 1 :: sub] * fs.noise_std_n
    )

    meas = np.empty(n)
    duty = np.empty(n)
    pos = np.empty(n)
    force = np.empty(n)
    power = np.empty(n)
    force_now = prm.wire.cross_section_m2 * s[rows.S_SIG]
    noise_now = 0.0
    fault = None
    for k in range(n):
        x = s[rows.S_X]
        if mode == "position":
            y = sensors.encoder_counts(x, enc.resolution_m, enc.gain) * enc.resolution_m
        else:
            y = sensors.force_reading(
                force_now,
                noise_now,
                fs.range_max_n,
                fs.resolution_n,
                fs.offset_n,
                fs.drift_n_per_s,
                k * sub * dt,
            )[0]
        u = controller.update(ref[k], y)
        meas[k], duty[k], pos[k], force[k] = y, u, x, force_now
        if controller.fault is not None:
            fault = f"controller fault at t = {k * ts:.2f} s: {controller.fault}"
            n = k + 1
            power[k] = 0.0
            break
        if kernel.steps(p, s, _DUTY, u, dt, out, sub) < sub:
            fault = f"plant state non-finite during the hold from t = {k * ts:.2f} s"
            n = k + 1
            power[k] = math.nan
            break
        power[k] = out[rows.O_P]
        force_now = out[rows.O_FW]
        noise_now = noise[k]
    return meas[:n], duty[:n], pos[:n], force[:n], power[:n], fault


def settled_mask(t, r, y, rest: float, settle: float = 1.0, arrive: float = 0.9):
    """Chapter 6 "stationary parts": reference constant >= ``settle`` s above ``rest``, rise over.

    :func:`hems_ros.control.metrics.stationary_mask` with ``min_level=rest`` (the plateaus,
    not the rest level the wire cools back to), and a plateau counts only from the sample
    where y first covers ``arrive`` of the jump: the model's wire starts moving later than
    the dissertation's (docs/validation.md, 1.0 s pulse row), so a fixed settle time would
    put part of the rise into a figure meant to measure holding.
    """
    t, r, y = (np.asarray(a, dtype=float) for a in (t, r, y))
    mask = metrics.stationary_mask(t, r, settle=settle, min_level=rest)
    for seg in metrics.step_segments(r):
        span = seg.after - seg.before
        progress = (y[seg.start : seg.stop] - seg.before) / span
        arrived = np.flatnonzero(progress >= arrive)
        first = seg.stop if arrived.size == 0 else seg.start + int(arrived[0])
        mask[seg.start : first] = False
    return mask


def rmse_mask(t, r, y, segment: str, rest: float | None = None):
    """Samples the RMSE covers: ``segment`` "all", "ascending" or "stationary"
    (:func:`settled_mask`)."""
    if segment == "stationary":
        return settled_mask(t, r, y, r[0] if rest is None else rest)
    return metrics.segment_mask(segment, t, r)


def figures(
    t, r, y, u, mode: str, segment: str = "all", rest: float | None = None, y_true=None
) -> dict[str, float]:
    """Figures of merit of one run in the dissertation's units (mm or N, %, W, s).

    ``rmse`` over the protocol's ``segment`` (chapter 5: all; chapter 6: ascending parts,
    or stationary parts by :func:`settled_mask`); ``iae`` is the sample sum of |e| in mm
    or N (Table 5.3 prints it /1e3); ``macsi`` in % per sample; ``apc_w`` by the
    formula. On piecewise-constant references: ``rise_time_s`` (10-90 %, mean over the
    rising jumps), ``overshoot`` (first peak past the new level, largest over the jumps, mm
    or N, on ``y_true`` when given: force-sensor noise is not a motion of the wire),
    ``excursion`` (the same over the whole of each plateau, so the hold ripple counts too)
    and ``ss_error`` (largest |mean error| over the last second of the jumps that rise);
    nan otherwise.
    """
    unit = 1e3 if mode == "position" else 1.0
    r_u, y_u = np.asarray(r) * unit, np.asarray(y) * unit
    mask = rmse_mask(t, r, y, segment, rest)
    out = {
        "rmse": metrics.rmse(r_u, y_u, mask),
        "iae": metrics.iae_sum(r_u, y_u),
        "macsi": metrics.macsi(u),
        "apc_w": metrics.apc(u),
    }
    segs = metrics.step_segments(r_u)
    rising = [g for g in segs if g.after > g.before]
    out["rise_time_s"] = (
        float(np.mean([metrics.rise_time(t, y_u, g) for g in rising])) if rising else math.nan
    )
    y_os = y_u if y_true is None else np.asarray(y_true) * unit
    out["overshoot"] = max((metrics.overshoot(y_os, g) for g in segs), default=math.nan)
    out["excursion"] = max((metrics.hold_excursion(y_os, g) for g in segs), default=math.nan)
    out["ss_error"] = max(
        (metrics.steady_state_error(t, r_u, y_u, g) for g in rising), default=math.nan
    )
    return out


def run_protocol(
    protocol: Protocol | str,
    strategy: str = "bpid",
    params: UnitParams | str = "ch5_straight_40n",
    gains=None,
    ts: float = DEFAULT_TS,
    dt: float = DEFAULT_DT,
    n_filter: float = DEFAULT_N_FILTER,
    start_temperature_c: float | None = None,
) -> LockstepRun:
    """Run ``protocol`` (a :data:`PROTOCOLS` name or object) with ``strategy`` on ``params``.

    ``gains`` default to Table 5.1; ``params`` is a :class:`UnitParams` or the name of a set
    in config/physics. E.g. the graph comparison's index step::

        run = run_protocol("ch6_position_step", "bpid", "ch6_hems_index")
        run.time, run.reference, run.measurement, run.duty, run.metrics["rmse"]
    """
    proto = PROTOCOLS[protocol] if isinstance(protocol, str) else protocol
    prm = _params(params)
    t, r = proto.generate(ts)
    y, u, pos, force, power, fault = simulate_loop(
        r, strategy, proto.mode, prm, gains, ts, dt, n_filter, start_temperature_c
    )
    t, r = t[: y.size], r[: y.size]
    run = LockstepRun(
        protocol=proto.name,
        strategy=strategy,
        mode=proto.mode,
        params_name=prm.name,
        time=t,
        reference=r,
        measurement=y,
        duty=u,
        position_m=pos,
        wire_force_n=force,
        power_w=power,
        segment=proto.segment,
        fault=fault,
    )
    truth = pos if proto.mode == "position" else force
    run.metrics = figures(t, r, y, u, proto.mode, proto.segment, rest=float(r[0]), y_true=truth)
    return run
