"""Validation scenarios: every number of the ``hems validate`` report (rendered by
:mod:`hems_ros.reports.validation`) comes from the functions here, which the tests call too:
- :func:`mass_loops` — 4 A x 1.8 s with 1, 3, 5 kg hanging masses (Table 4.1, bare wire);
- :func:`six_pulses` — six 4 A pulses of 0.5-1.0 s with 2 s pauses, 12 N spring (minor loops);
- :func:`voltage_runaway` — constant-voltage drive, bare vs sheathed;
- :func:`sheath_facts` — cold-sheath 106.8 J displacement ratio, controlled-displacement
  cooling times, heat build-up over repeated cycles;
- :func:`sweep` — the Table 3.2/3.3 pulse sweep on the calibrated sheathed rig;
- :func:`sweep_traces` — the same sweep's time series, for its figure;
- :func:`onset_bounds` — how hot the measured wires can have been where they had moved
  (energy balance with no loss) against where the model's heating branch is;
- :func:`closed_form` — the closed-form quantities the dissertation prints (convection,
  sheath resistances, capstan ratio).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from hems_ros.physics import heat, kinetics, scenarios
from hems_ros.physics.batch import SimResult, simulate
from hems_ros.physics.friction import capstan_ratio
from hems_ros.physics.params import UnitParams, load_params
from hems_ros.physics.sheath import SheathResistances, sheath_resistances

DT = 1e-3


# ------------------------------------------------------------------ scenarios
@dataclass
class MassLoops:
    masses_kg: tuple
    result: SimResult
    heating_midpoint_c: list  # wire temperature where xi crosses 0.5 on heating (NaN if never)
    heating_onset_c: list  # wire temperature where xi crosses 0.95 on heating
    min_martensite: list
    cooling_capacity_ratio: list  # peak apparent heat capacity on cooling / c_p rho V


def mass_loops(
    params: UnitParams | None = None,
    masses=(1.0, 3.0, 5.0),
    pulse_s: float = 1.8,
    total_s: float = 25.0,
) -> MassLoops:
    base = params or load_params("table41")
    sets = [
        base.replace(
            {
                "load.kind": "hanging_mass",
                "load.mass_kg": m,
                "load.pretension_n": 0.0,
                "load.stiffness_n_per_m": 0.0,
                "sheath.enabled": False,
            }
        )
        for m in masses
    ]
    res = simulate(sets, DT, current=scenarios.pulse_train(pulse_s, total_s, DT))
    end = int(round(pulse_s / DT))
    mid, onset, ximin, cap = [], [], [], []
    for i, p in enumerate(sets):
        temp, xi = res.wire_temperature_c[i], res.martensite_fraction[i]
        mid.append(_crossing(temp[:end], xi[:end], 0.5))
        onset.append(_crossing(temp[:end], xi[:end], 0.95))
        ximin.append(float(xi.min()))
        cap.append(_cooling_capacity_ratio(p, temp[end:], xi[end:]))
    return MassLoops(tuple(masses), res, mid, onset, ximin, cap)


def _crossing(temp: np.ndarray, xi: np.ndarray, level: float) -> float:
    below = np.flatnonzero(xi <= level)
    return float(temp[below[0]]) if below.size else float("nan")


def _cooling_capacity_ratio(p: UnitParams, temp: np.ndarray, xi: np.ndarray) -> float:
    """Peak of (convective loss / |C dT/dt|) while cooling: 1 without latent heat."""
    c_w = p.wire_heat_capacity_j_per_k
    q = heat.convection_loss(
        temp,
        p.ambient_temperature_c,
        p.thermal.h0_w_m2_c,
        p.thermal.h2_w_m2_c3,
        p.wire.surface_area_m2,
    )
    rate = -np.gradient(temp, DT)
    ok = rate > 1e-3
    return float(np.max(q[ok] / (c_w * rate[ok]))) if ok.any() else float("nan")


@dataclass
class SixPulses:
    result: SimResult
    drive: np.ndarray
    reversal_temperature_c: list  # peak temperature of each pulse
    reversal_martensite: list  # xi at that peak
    pause_martensite: list  # xi at the end of the following pause
    return_deviation: list  # xi when the next pulse passes the previous peak - xi at the peak
    return_deviation_effective: list  # same, passing the peak's effective temperature T - sigma/C_A
    effective_temperature_c: np.ndarray  # u_A = T - sigma/C_A of the run (kinetics.py)


def six_pulses(
    params: UnitParams | None = None, pulses=(0.5, 0.6, 0.7, 0.8, 0.9, 1.0), pause_s: float = 2.0
) -> SixPulses:
    base = params or load_params("table41")
    seg = []
    for p in pulses:
        seg += [scenarios.PULSE_CURRENT_A] * int(round(p / DT)) + [0.0] * int(round(pause_s / DT))
    drive = np.array(seg)
    res = simulate(base, DT, current=drive)
    temp, xi = res.wire_temperature_c[0], res.martensite_fraction[0]
    u_a = temp - res.stress_pa[0] / base.kinetics.ca_pa_per_c
    on = drive > 0
    ends = np.flatnonzero(on[:-1] & ~on[1:])
    starts = np.flatnonzero(~on[:-1] & on[1:]) + 1
    t_rev, xi_rev, xi_pause, dev, dev_u = [], [], [], [], []
    for j, e in enumerate(ends):
        t_rev.append(float(temp[e]))
        xi_rev.append(float(xi[e]))
        if j + 1 < len(ends):
            s, nxt = starts[j], ends[j + 1]
            xi_pause.append(float(xi[s - 1]))
            dev.append(_passing(temp[s : nxt + 1], xi[s : nxt + 1], temp[e]) - xi[e])
            dev_u.append(_passing(u_a[s : nxt + 1], xi[s : nxt + 1], u_a[e]) - xi[e])
    return SixPulses(res, drive, t_rev, xi_rev, xi_pause, dev, dev_u, u_a)


def _passing(temp: np.ndarray, xi: np.ndarray, level: float) -> float:
    """xi at the first sample with temp >= level (NaN if never): one step past the point."""
    k = int(np.argmax(temp >= level))
    return float(xi[k]) if temp[k] >= level else float("nan")


@dataclass
class Runaway:
    voltage_v: float
    result: SimResult  # set 0 bare, set 1 sheathed
    power_gain: list  # peak power / initial power
    peak_temperature_c: list
    peak_velocity_m_s: list


def voltage_runaway(
    params: UnitParams | None = None, voltage_v: float = 16.0, total_s: float = 4.0
) -> Runaway:
    base = params or load_params("sheathed_calibrated")
    sets = [scenarios.characterization_rig(base, False), scenarios.characterization_rig(base, True)]
    res = simulate(sets, DT, voltage=np.full(int(round(total_s / DT)), voltage_v))
    power = res.electrical_power_w
    return Runaway(
        voltage_v,
        res,
        list(power.max(axis=1) / power[:, 0]),
        list(res.wire_temperature_c.max(axis=1)),
        list(res.slider_velocity_m_s.max(axis=1)),
    )


@dataclass
class SheathFacts:
    bare_106j_m: float
    sheathed_106j_m: float
    displacement_ratio: float
    cooling_bare_s: float
    cooling_sheathed_s: float
    cooling_ratio: float
    cycle_sheath_start_c: list  # sheath temperature at the start of each repeated cycle
    cycle_cooling_s: list  # cooling time of each repeated cycle
    cycles: SimResult


def sheath_facts(
    params: UnitParams | None = None, cycles: int = 6, period_s: float = 30.0
) -> SheathFacts:
    base = params or load_params("sheathed_calibrated")
    bare, sheathed = (
        scenarios.characterization_rig(base, False),
        scenarios.characterization_rig(base, True),
    )
    resp = scenarios.pulse_responses([bare, sheathed], [1.6, 1.6], DT)
    cb, cs = scenarios.controlled_cooling_times([bare, sheathed], dt=DT)
    one = scenarios.pulse_train(1.6, period_s, DT)
    rep = simulate(
        sheathed,
        DT,
        current=np.tile(one, cycles),
        channels=["slider_position_m", "sheath_temperature_c", "wire_temperature_c"],
    )
    n = one.size
    end = int(round(1.6 / DT)) - 1
    starts, cool = [], []
    for c in range(cycles):
        x = rep.slider_position_m[0, c * n : (c + 1) * n]
        starts.append(float(rep.sheath_temperature_c[0, c * n]))
        cool.append(scenarios.cooling_time(x, end, DT))
    return SheathFacts(
        resp[0].max_displacement_m,
        resp[1].max_displacement_m,
        resp[1].max_displacement_m / resp[0].max_displacement_m,
        cb,
        cs,
        cs / cb,
        starts,
        cool,
        rep,
    )


def sweep(
    params: UnitParams | None = None, pulses=tuple(scenarios.TABLE_32_33)
) -> list[scenarios.PulseResponse]:
    """Table 3.2/3.3 protocol on the calibrated sheathed rig, each pulse from a cold start."""
    rig = scenarios.characterization_rig(params or load_params("sheathed_calibrated"), True)
    return scenarios.pulse_responses([rig] * len(pulses), list(pulses), DT)


def sweep_traces(
    params: UnitParams | None = None, pulses=tuple(scenarios.TABLE_32_33)
) -> SimResult:
    """Slider position and wire force over the 16 s of each :func:`sweep` pulse, one row each."""
    rig = scenarios.characterization_rig(params or load_params("sheathed_calibrated"), True)
    return simulate(
        [rig] * len(pulses),
        DT,
        current=np.stack([scenarios.pulse_train(p, 16.0, DT) for p in pulses]),
        channels=["slider_position_m", "wire_force_n"],
    )


@dataclass
class OnsetBound:
    """One measured short pulse on the 50 N characterization rig, and what it says of the wire."""

    source: str  # where the fact is printed
    pulse_s: float
    energy_j: float  # measured pulse energy
    displacement_mm: float  # measured maximum displacement
    fraction: float  # of the saturated stroke: the austenite fraction reached
    lossless_c: float  # the hottest the measured wire can have been (no heat loss)
    branch_c: float  # where the model's heating branch reaches that fraction under 50 N
    branch_unloaded_c: float  # the same with no stress (the lowest it can be)
    model_displacement_mm: float  # the model on the same rig, same pulse length at 4 A
    start_c: float  # the coldest start from which a lossless wire reaches branch_c


ONSET_FACTS = (
    ("Table 3.2", 1.0, *scenarios.TABLE_32_33[1.0][:2], scenarios.TABLE_32_33[2.8][1]),
    ("Table 3.2", 1.6, *scenarios.TABLE_32_33[1.6][:2], scenarios.TABLE_32_33[2.8][1]),
    ("section 5", 1.0, *scenarios.CH6_PULSES[1.0], scenarios.CH6_PULSES[3.0][1]),
    ("section 5", 1.6, *scenarios.CH6_PULSES[1.6], scenarios.CH6_PULSES[3.0][1]),
)
"""(source, pulse s, energy J, displacement mm, saturated stroke mm) of the measured
short pulses."""


def onset_bounds(params: UnitParams | None = None) -> list[OnsetBound]:
    """Energy balance of the measured short pulses (dissertation chapters 3 and 6)
    against the model.

    A wire that moved fraction f of its saturated stroke has turned f of its martensite to
    austenite and absorbed f rho V dH of latent heat; with no loss at all the rest of the
    pulse energy heats it to :func:`hems_ros.physics.heat.lossless_temperature_c`, an upper
    bound. The model's wire reaches the same fraction on its major heating branch (eq. 4.21)
    at the stress-shifted As, Af of the 50 N preload (eq. 4.25). Where the bound is below the
    branch temperature, no wire with the model's transformation temperatures and heat
    constants can move as early as the measured one did from ambient; ``start_c`` is how warm
    it must have been at the start instead (the same balance from a warmer wire).
    """
    p = params or load_params("sheathed_calibrated")
    rig = scenarios.characterization_rig(p, True)
    shift = (
        (scenarios.RIG_MASS_KG * 9.81 + scenarios.RIG_SPRING_PRETENSION_N)
        / p.wire.cross_section_m2
        / p.kinetics.ca_pa_per_c
    )
    pulses = sorted({fact[1] for fact in ONSET_FACTS})
    model = dict(zip(pulses, scenarios.pulse_responses([rig] * len(pulses), pulses, DT)))
    out = []
    for source, pulse, energy, x_mm, stroke_mm in ONSET_FACTS:
        f = x_mm / stroke_mm
        lossless = heat.lossless_temperature_c(
            energy, f, p.wire_heat_capacity_j_per_k, p.wire_latent_heat_j, p.ambient_temperature_c
        )
        branch = kinetics.heating_branch_temperature(
            f, p.kinetics.as0_c + shift, p.kinetics.af0_c + shift
        )
        out.append(
            OnsetBound(
                source,
                pulse,
                energy,
                x_mm,
                f,
                lossless,
                branch,
                kinetics.heating_branch_temperature(f, p.kinetics.as0_c, p.kinetics.af0_c),
                model[pulse].max_displacement_m * 1e3,
                branch - (lossless - p.ambient_temperature_c),
            )
        )
    return out


def earliest_onset(bounds: Sequence[OnsetBound], source: str) -> OnsetBound:
    """The shortest pulse of ``source`` among ``bounds``: the earliest the measured wire moved."""
    return min((b for b in bounds if b.source == source), key=lambda b: b.pulse_s)


# ------------------------------------------------------------------ closed form
@dataclass(frozen=True)
class ClosedForm:
    h_22_w_m2k: float  # h(22 degC) with Table 4.1's h0, h2
    churchill_chu_nusselt: float  # at the appendix 4.4 conditions
    churchill_chu_h_w_m2k: float
    sheath: SheathResistances  # Table 3.1, of the calibrated set's sheath
    capstan_ratio: float  # mu 0.04 over Theta pi


def closed_form(
    table41: UnitParams | None = None, calibrated: UnitParams | None = None
) -> ClosedForm:
    """The printed closed-form quantities from the model's functions: convection from Table 4.1,
    the sheath's resistances from the calibrated set."""
    t41 = table41 or load_params("table41")
    cal = calibrated or load_params("sheathed_calibrated")
    nusselt, h_cc = heat.appendix_free_convection()
    return ClosedForm(
        heat.convection_coefficient(22.0, t41.thermal.h0_w_m2_c, t41.thermal.h2_w_m2_c3),
        nusselt,
        h_cc,
        sheath_resistances(cal.sheath, cal.wire.length_m),
        capstan_ratio(0.04, math.pi),
    )
