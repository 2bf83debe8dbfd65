"""The measurements behind the findings on the dissertation's chapter 5 and 6 claims; each
returns data, and :mod:`hems_ros.reports.findings` states the claims and renders the evidence.


* :func:`authority_split`: where the actuator is saturated the controller has already
  given all it can; an error while the duty is 0 and the wire is above the reference is
  cooling-limited, an error at 100 % duty below the reference is heating-limited. The RMSE
  of the remaining samples is the part the controller is responsible for.
* :func:`coast_after_cutoff`: open-loop, full power from cold until the wire reaches a
  target, then zero duty; how fast the wire arrives and how far it travels with the heater
  off. Travel with the heater off is overshoot no controller of an only-pulling actuator
  can take back.
* :func:`bilinear_activity`: how often the eq. 5.36 factor changes BPID's output, i.e. the
  samples with an unsaturated duty and a factor away from 1.
* :func:`rate_check`: the chapter 5 step and staircase with BPID on
  ``ch5_straight_40n_table32``, the wire refitted to Table 3.2's displacement per pulse
  energy, which rises about as slowly as the dissertation's: does the overshoot go with the
  speed?
* :func:`pulse_gain`: the calibrated rig's displacement per joule of pulse (Table 3.2).
* :func:`wire_mass_mode`: frequency and damping ratio of the 4 kg mass on the elastic wire.
* :func:`table_4_1_stress_slope`: the BPID steps with Table 4.1's stress slopes C_M = C_A:
  how much of the ringing the wire's stress-induced transformation takes up.
* :func:`force_noise_free`: the chapter 6 force steps without sensor noise: does the
  approach overshoot without the ripple the noise drives?
* :func:`force_gain_sweep`: the same steps with other force-mode gain sets, with and without
  the noise: what the choice of FORCE_MODE_BPID trades (overshoot against step RMSE).
* :func:`filter_sweep`: BPID's step and staircase overshoot over derivative filters N the
  dissertation might have used (it does not print N).
* :func:`hems_ros.physics.validation.onset_bounds`: the energy balance of the measured short
  pulses, an upper bound on how hot the measured wire was where it had moved, against the
  model's heating branch: how early a wire with Table 4.1's temperatures can move at all.
* :func:`cold_start_floor`: the least ascending-part RMSE of a chapter 6 position reference
  for an idealised wire with Table 4.1's band that starts cold (full drive power, no heat
  loss): how much of a miss no plant with those temperatures could avoid.
* :func:`warm_start_ratios`: the chapter 6 position runs with wire and sheath started warm,
  as a rig still warm from earlier work: whether the cold start explains the misses.
* :func:`gain_grid`: BPID's step and staircase overshoot over a grid of Kp and Kd around
  Table 5.1's: whether any gain set avoids the overshoot on this plant.
* :func:`perturbation_spread`: how far the step and staircase figures move when the
  ambient temperature moves by 1e-6 degC, the run-to-run spread of a closed-loop cell.
"""

from __future__ import annotations

import math
from dataclasses import replace
from typing import TypedDict

import numpy as np

from hems_ros.control import DEFAULT_TS, DUTY_MAX, FORCE_MODE_BPID, TABLE_5_1_BPID, metrics
from hems_ros.control.bpid import bilinear_factor
from hems_ros.control.references import PROTOCOLS
from hems_ros.experiments.chapters import CH6_PARAMS, force_protocol, rest_wire_tension
from hems_ros.experiments.dissertation import CH5_TABLES, CH6_TABLES
from hems_ros.experiments.lockstep import LockstepRun, rmse_mask, run_protocol
from hems_ros.physics import ActuationUnit, load_params, validation
from hems_ros.physics.kinetics import heating_branch
from hems_ros.physics.params import Kinetics, UnitParams

RATE_CHECK_PARAMS = "ch5_straight_40n_table32"

FACTOR_2_PROTOCOLS = ("ch5_sine_0.125", "ch5_step", "ch5_staircase")
STEP_PROTOCOLS = ("ch5_step", "ch5_staircase")
FORCE_STEPS = ("ch6_force_step", "ch6_force_staircase")


def authority_split(run: LockstepRun) -> dict[str, float]:
    """Share of the squared error by actuator state, and the RMSE where it is unsaturated.

    Over the samples the run's RMSE covers; unit of the RMSE: mm (position) or N (force).
    """
    unit = 1e3 if run.mode == "position" else 1.0
    mask = rmse_mask(run.time, run.reference, run.measurement, run.segment, float(run.reference[0]))
    e = ((run.reference - run.measurement) * unit)[mask]
    duty = run.duty[mask]
    cooling = (duty <= 0.0) & (e < 0)
    heating = (duty >= DUTY_MAX) & (e > 0)
    free = ~(cooling | heating)
    total = float(np.sum(e * e)) or 1.0
    return {
        "cooling_share": float(np.sum(e[cooling] ** 2)) / total,
        "heating_share": float(np.sum(e[heating] ** 2)) / total,
        "rmse_unsaturated": metrics.rms(e[free]),
    }


def coast_after_cutoff(params: UnitParams, target_m: float, dt: float = 1e-3) -> dict[str, float]:
    """Full duty from cold until the slider reaches ``target_m``, then 0 % for 1 s.

    Returns the time to get there (s), the speed at cut-off (mm/s) and the further travel
    with the heater off (mm).
    """
    unit = ActuationUnit(params, dt)
    r = unit.step(duty=DUTY_MAX)
    while r.slider_position_m < target_m:
        if unit.time > 30.0:
            raise RuntimeError(f"{params.name}: full duty never reaches {target_m * 1e3:.1f} mm")
        r = unit.step(duty=DUTY_MAX)
    reached, speed = unit.time, r.slider_velocity_m_s
    peak = r.slider_position_m
    for _ in range(int(round(1.0 / dt))):
        peak = max(peak, unit.step(duty=0.0).slider_position_m)
    return {"time_s": reached, "speed_mm_s": speed * 1e3, "coast_mm": (peak - target_m) * 1e3}


def bilinear_activity(run: LockstepRun, kb: float | None = None, tol: float = 0.01) -> float:
    """Fraction of samples where BPID's duty is unsaturated and its eq. 5.36 factor is off
    1 by > ``tol``."""
    gains = TABLE_5_1_BPID
    kb = gains.kb if kb is None else kb
    scale = gains.scale_for(run.mode)
    r, y = run.reference * scale, run.measurement * scale
    factor = np.array([bilinear_factor(kb, r[k], y[k - 1] if k else 0.0) for k in range(r.size)])
    active = (run.duty > 0.0) & (run.duty < DUTY_MAX) & (np.abs(factor - 1.0) > tol)
    return float(np.mean(active))


def rate_check(params: UnitParams | str = RATE_CHECK_PARAMS) -> dict[str, float]:
    """BPID (Table 5.1) step and staircase on the Table 3.2-refitted wire, plus its open-loop speed.

    ``*_overshoot_damped``: the same with the load damper b four times Table 4.1's.
    """
    prm = params if isinstance(params, UnitParams) else load_params(params)
    out = {f"coast_{k}": v for k, v in coast_after_cutoff(prm, 0.010).items()}
    for p in STEP_PROTOCOLS:
        m = run_protocol(p, "bpid", prm).metrics
        out.update({f"{p[4:]}_{k}": m[k] for k in ("rise_time_s", "overshoot", "ss_error")})
    damped = prm.replace({"load.damping_n_s_per_m": 4 * prm.load.damping_n_s_per_m})
    for p in STEP_PROTOCOLS:
        out[f"{p[4:]}_overshoot_damped"] = run_protocol(p, "bpid", damped).metrics["overshoot"]
    return out


def table_4_1_stress_slope(params: UnitParams) -> dict[str, float]:
    """BPID (Table 5.1) overshoot (mm) on the step and the staircase with Table 4.1's stress
    slopes C_M = C_A (eq. 4.25) in place of the calibrated ones: the stress-induced
    transformation that a smaller C lets the mass's swing drive is the one damping inside
    the model's wire."""
    default = Kinetics()
    table = params.replace(
        {"kinetics.cm_pa_per_c": default.cm_pa_per_c, "kinetics.ca_pa_per_c": default.ca_pa_per_c}
    )
    return {p: run_protocol(p, "bpid", table).metrics["overshoot"] for p in STEP_PROTOCOLS}


def pulse_gain() -> dict[str, float]:
    """Displacement per joule of pulse of the calibrated rig between the Table 3.2 1.6 and
    2.2 s rows (mm/J), and its displacement after the 1.0 s pulse (mm)."""
    short, a, b = validation.sweep(pulses=(1.0, 1.6, 2.2))
    return {
        "mm_per_j": (b.max_displacement_m - a.max_displacement_m) * 1e3 / (b.energy_j - a.energy_j),
        "x_1.0_mm": short.max_displacement_m * 1e3,
    }


def wire_mass_mode(params: UnitParams) -> dict[str, float]:
    """Undamped frequency (Hz) and damping ratio of the hanging mass on the martensitic wire.

    Wire stiffness S E_M / L (the stiffest the wire gets while it holds martensite), the
    load's mass and damper b of eq. 4.33.
    """
    k = params.wire.cross_section_m2 * params.constitutive.e_martensite_pa / params.wire.length_m
    m, b = params.load.mass_kg, params.load.damping_n_s_per_m
    return {
        "frequency_hz": math.sqrt(k / m) / (2 * math.pi),
        "damping_ratio": b / (2 * math.sqrt(k * m)),
    }


COLD_WIRE_PARAMS = "table41"


def cold_start_floor(
    protocol: str, params: UnitParams | str = COLD_WIRE_PARAMS
) -> dict[str, float]:
    """Least RMSE (mm) any wire with ``params``' transformation band can reach on the ascending
    parts of ``protocol`` when it is cold as the reference starts to rise.

    Every step below only moves the wire earlier or further than a real one could, so no
    controller and no plant with that band and heat capacity does better: the wire starts
    at ambient, takes the drive's ceiling V I (dissertation chapter 6: 20 V, 4 A, at most 80 W)
    from the first sample the reference leaves its base, loses no heat and takes no latent
    heat (the heat balance of eqs. 4.7-4.12 without Q_out and the dH term:
    T = T_amb + P t / (rho V c_p)), turns to
    austenite along the major heating branch with the stress-free As0, Af0 (eq. 4.21; stress
    only raises them, eq. 4.25) and gives the full recoverable stroke eps_L L for it.
    Returns the floor, its ratio to Table 6.1 and how long the bound's wire takes to catch up
    with the reference (s).
    """
    prm = params if isinstance(params, UnitParams) else load_params(params)
    proto = PROTOCOLS[protocol]
    if proto.segment != "ascending":
        raise ValueError(
            f"{protocol}: the cold-start floor bounds ascending-part RMSE, "
            f"not {proto.segment!r} segments"
        )
    t, r = proto.generate(DEFAULT_TS)
    start = t[np.flatnonzero(r > r[0])[0] - 1]
    power = prm.drive.supply_voltage_v * prm.drive.current_limit_a
    temp = (
        prm.ambient_temperature_c
        + power * np.clip(t - start, 0.0, None) / prm.wire_heat_capacity_j_per_k
    )
    k = prm.kinetics
    inv_width = 1.0 / (k.af0_c - k.as0_c)
    austenite = 1.0 - np.fromiter(
        (heating_branch(float(x), k.as0_c, inv_width)[0] for x in temp), float, temp.size
    )
    y = r[0] + prm.constitutive.max_recoverable_strain * prm.wire.length_m * austenite
    behind = np.clip(r - y, 0.0, None)
    floor = metrics.rmse(behind * 1e3, np.zeros_like(behind), metrics.ascending_mask(r))
    caught = np.flatnonzero((t > start) & (y >= r))
    return {
        "rmse_mm": floor,
        "ratio": floor / CH6_TABLES["position"][2][protocol]["rmse"],
        "catch_up_s": float(t[caught[0]] - start) if caught.size else math.nan,
        "power_w": power,
    }


WARM_START_C = (40.0, 50.0, 60.0, 70.0)
"""Start temperatures of wire and sheath for :func:`warm_start_ratios`: up to just below the
71-74 degC at which the model's wire is back at the characterization's "cooled" 0.5 % strain
(docs/validation.md), the warmest start that reading allows."""


def warm_start_ratios(
    protocols, temperatures=WARM_START_C, params: UnitParams | str = CH6_PARAMS
) -> dict[float, dict[str, float]]:
    """RMSE / Table 6.1 of chapter 6 position ``protocols`` (BPID, Table 5.1) with wire and
    sheath starting at each of ``temperatures`` (degC, fully martensite) instead of cold: what
    a rig still warm from earlier work would have done with the model's wire."""
    table = CH6_TABLES["position"][2]
    return {
        temp: {
            p: run_protocol(p, "bpid", params, start_temperature_c=temp).metrics["rmse"]
            / table[p]["rmse"]
            for p in protocols
        }
        for temp in temperatures
    }


def _force_steps(gains, noise: bool) -> list[dict[str, float]]:
    """Figures of the chapter 6 force step and staircase (FORCE_STEPS order) with ``gains``,
    the force sensor with or without its noise."""
    prm = load_params(CH6_PARAMS)
    if not noise:
        prm = prm.replace({"force_sensor.noise_std_n": 0.0})
    rest = rest_wire_tension(prm)
    return [
        run_protocol(force_protocol(name, rest), "bpid", prm, gains).metrics for name in FORCE_STEPS
    ]


def force_noise_free(gains=FORCE_MODE_BPID) -> dict[str, float]:
    """Overshoot (first peak, N) of the chapter 6 force step and staircase with a
    noise-free sensor."""
    return {name: m["overshoot"] for name, m in zip(FORCE_STEPS, _force_steps(gains, noise=False))}


FORCE_GAIN_SWEEP = ((0.3, 0.2), (0.4, 0.2), (0.5, 0.3), (0.6, 0.3), (0.8, 0.5))
"""(Kp, Ki) force-mode BPID sets of :func:`force_gain_sweep`, error in 10 mN as FORCE_MODE_BPID."""


class ForceGainFigures(TypedDict):
    """The figures of one gain set in :func:`force_gain_sweep`."""

    noisy: float
    quiet: float
    quiet_by: dict[str, float]
    ss_error: float
    rmse_step: float


def force_gain_sweep(sets=FORCE_GAIN_SWEEP) -> dict[tuple[float, float], ForceGainFigures]:
    """Force-step figures (N, the larger of step and staircase) of force-mode gain sets:
    overshoot with the sensor noise (``noisy``) and without it (``quiet``; per protocol in
    ``quiet_by``), and with the noise the steady-state error (``ss_error``) and the step's
    RMSE (``rmse_step``)."""
    out: dict[tuple[float, float], ForceGainFigures] = {}
    for kp, ki in sets:
        gains = replace(FORCE_MODE_BPID, kp=kp, ki=ki)
        noisy, quiet = _force_steps(gains, noise=True), _force_steps(gains, noise=False)
        out[(kp, ki)] = {
            "noisy": max(m["overshoot"] for m in noisy),
            "quiet": max(m["overshoot"] for m in quiet),
            "quiet_by": {name: m["overshoot"] for name, m in zip(FORCE_STEPS, quiet)},
            "ss_error": max(m["ss_error"] for m in noisy),
            "rmse_step": noisy[0]["rmse"],
        }
    return out


FILTER_SWEEP_RAD_S = (2.0, 5.0, 10.0, 50.0, 100.0)


def filter_sweep(params: UnitParams, n_values=FILTER_SWEEP_RAD_S) -> dict[str, float]:
    """Smallest BPID overshoot (mm) on the step and the staircase over derivative filters
    ``n_values`` (rad/s; the runs use DEFAULT_N_FILTER otherwise), Table 5.1 gains."""
    return {
        p: min(run_protocol(p, "bpid", params, n_filter=n).metrics["overshoot"] for n in n_values)
        for p in STEP_PROTOCOLS
    }


GAIN_GRID_KP = (0.05, 0.1, 0.2, 0.4, 0.8)  # %/um; Table 5.1: 0.8
GAIN_GRID_KD = (0.02, 0.05, 0.1, 0.2, 0.5)  # % s/um; Table 5.1: 0.05


def gain_grid(
    params: UnitParams, kp_values=GAIN_GRID_KP, kd_values=GAIN_GRID_KD
) -> dict[str, dict]:
    """BPID step and staircase over a grid of Kp x Kd (Ki 0, Kb 1 as Table 5.1).

    For each protocol: ``least`` the set with the least overshoot, ``holding`` the one with the
    least overshoot among the sets whose steady-state error is at most 0.05 mm on both
    protocols (None when no set holds); each as (overshoot mm, steady-state error mm, (Kp, Kd)).
    """
    table = TABLE_5_1_BPID
    figs = {}
    for kp in kp_values:
        for kd in kd_values:
            gains = replace(table, kp=kp, kd=kd)
            figs[kp, kd] = {
                p: run_protocol(p, "bpid", params, gains).metrics for p in STEP_PROTOCOLS
            }
    holding = [g for g, f in figs.items() if all(m["ss_error"] <= 0.05 for m in f.values())]

    def best(p, sets):
        if not sets:
            return None
        g = min(sets, key=lambda g: figs[g][p]["overshoot"])
        return figs[g][p]["overshoot"], figs[g][p]["ss_error"], g

    return {p: {"least": best(p, list(figs)), "holding": best(p, holding)} for p in STEP_PROTOCOLS}


SPREAD_SHIFT_C = 1e-6


def perturbation_spread(
    ch5: dict, params: UnitParams, protocols=STEP_PROTOCOLS, metrics=("rmse", "macsi")
) -> dict[str, float]:
    """Largest relative change of each of ``metrics`` over ``protocols`` and the three
    controllers (Table 5.1 gains) when the ambient temperature moves by SPREAD_SHIFT_C.

    No lab holds anything that constant, yet the 1 um encoder counts and the saturating duty
    turn the difference into other switching decisions, and the hysteresis keeps their
    consequences: this is the spread a cell of the tables carries from run to run.
    """
    shifted = params.replace(
        {"ambient_temperature_c": params.ambient_temperature_c + SPREAD_SHIFT_C}
    )
    spread = dict.fromkeys(metrics, 0.0)
    for p in protocols:
        for s in ("pid", "pipd", "bpid"):
            moved = run_protocol(p, s, shifted).metrics
            for k in metrics:
                spread[k] = max(spread[k], abs(moved[k] / ch5[p, s].metrics[k] - 1.0))
    return spread


REPEAT_SHIFT_C = 0.1


def repeated_ratios(
    ch5: dict, params: UnitParams, metric: str, cells
) -> dict[tuple[str, str], tuple]:
    """Ours / dissertation for ``metric`` of each (protocol, strategy) in ``cells`` with the
    ambient REPEAT_SHIFT_C lower, as run, and higher: three repetitions as a lab's drift between
    runs would make them (the dissertation averaged three); the last entry is their mean."""
    _, _, table, factor = CH5_TABLES[metric]
    out = {}
    for p, s in cells:
        values = []
        for shift in (-REPEAT_SHIFT_C, 0.0, REPEAT_SHIFT_C):
            run = (
                ch5[p, s]
                if shift == 0.0
                else run_protocol(
                    p,
                    s,
                    params.replace({"ambient_temperature_c": params.ambient_temperature_c + shift}),
                )
            )
            values.append(run.metrics[metric] * factor / table[p, s])
        out[p, s] = (*values, sum(values) / len(values))
    return out


def ratios(ch5: dict, metric: str, protocols=FACTOR_2_PROTOCOLS) -> dict[tuple[str, str], float]:
    """Ours / dissertation for ``metric`` (a CH5_TABLES key) per (protocol, strategy)."""
    _, _, table, factor = CH5_TABLES[metric]
    return {
        (p, s): ch5[p, s].metrics[metric] * factor / table[p, s]
        for (p, s) in table
        if p in protocols
    }
