"""Experiment protocols of the dissertation, run on the batch API (shared by the tests,
the calibration and ``hems validate``).

Definitions used throughout (dissertation chapter 3):
- characterization rig (chapter 3): straight sheathed actuator, 30 N hanging mass + bias
  spring pretensioned to 20 N (stiffness 754 N/m from Table 3.3: (70.70 - 50) N / 27.45 mm),
  4 A current pulses, each from rest at ambient temperature (wire and sheath cold);
- maximum displacement / force: maxima over the pulse and the following cooling;
- cooling time: from the end of the pulse until the slider is back to 0.5 % strain (4.5 mm);
- "same controlled displacement": 4 A until the slider reaches 20 mm, then off.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from hems_ros.physics.batch import simulate
from hems_ros.physics.params import UnitParams

RIG_MASS_KG = 30.0 / 9.81
RIG_SPRING_PRETENSION_N = 20.0
RIG_SPRING_STIFFNESS_N_PER_M = 754.0
PULSE_CURRENT_A = 4.0
COOLED_POSITION_M = 4.5e-3
CONTROLLED_DISPLACEMENT_M = 20e-3

# Tables 3.2 (1.0-2.2 s) and 3.3 (2.4-2.8 s): pulse s -> (energy J, max displacement mm,
# max force N, cooling time s)
TABLE_32_33 = {
    1.0: (66.75, 5.94, 51.82, 0.34),
    1.6: (106.8, 15.25, 57.06, 2.36),
    2.2: (146.85, 24.53, 63.70, 3.74),
    2.4: (160.2, 25.98, 69.09, 4.38),
    2.6: (173.55, 26.31, 69.67, 4.42),
    2.8: (186.9, 27.45, 70.70, 5.00),
}
# Dissertation chapter 6, the chapter 6 characterization of the HEMS unit (same 30 N + 20 N
# preload, 4 A pulses, wire resistance 3.6 ohm, so 57.6 W): pulse s -> (energy J, wire
# displacement mm). 1.6 s is printed (29 mm, 3.22 % strain); 1.0 and 3.0 s follow from the
# text, "1.0 -> 1.6 s adds about 5 mm, 1.6 -> 3 s only 1 mm more".
CH6_RESISTANCE_OHM = 3.6
CH6_PULSES = {
    1.0: (PULSE_CURRENT_A**2 * CH6_RESISTANCE_OHM * 1.0, 24.0),
    1.6: (PULSE_CURRENT_A**2 * CH6_RESISTANCE_OHM * 1.6, 29.0),
    3.0: (PULSE_CURRENT_A**2 * CH6_RESISTANCE_OHM * 3.0, 30.0),
}
CH6_COOLING_1_6_S = 4.5
COOLING_BARE_S = 4.83
COOLING_SHEATHED_S = 3.33


def characterization_rig(params: UnitParams, sheathed: bool) -> UnitParams:
    """The chapter 3 rig (30 N mass + 20 N spring, straight) with or without the sheath."""
    return params.replace(
        {
            "load.kind": "hanging_mass",
            "load.mass_kg": RIG_MASS_KG,
            "load.pretension_n": RIG_SPRING_PRETENSION_N,
            "load.stiffness_n_per_m": RIG_SPRING_STIFFNESS_N_PER_M,
            "load.pulley_ratio": 1.0,
            "sheath.enabled": sheathed,
            "capstan.enabled": False,
            "glove_friction.enabled": False,
        }
    )


def pulse_train(
    pulse_s: float, total_s: float, dt: float, amplitude: float = PULSE_CURRENT_A
) -> np.ndarray:
    """One pulse of ``pulse_s`` at t = 0, then zero up to ``total_s``."""
    n = int(round(total_s / dt))
    drive = np.zeros(n)
    drive[: int(round(pulse_s / dt))] = amplitude
    return drive


@dataclass(frozen=True)
class PulseResponse:
    pulse_s: float
    energy_j: float
    max_displacement_m: float
    max_force_n: float
    cooling_time_s: float  # NaN when the slider never passed 4.5 mm
    cooled_temperature_c: float  # wire temperature when it is back at 4.5 mm; NaN as above
    max_temperature_c: float
    min_martensite: float


def cooling_time(
    position: np.ndarray, end_index: int, dt: float, threshold: float = COOLED_POSITION_M
) -> float:
    """Seconds from sample ``end_index`` until ``position`` is back at or below ``threshold``."""
    if position.max() <= threshold:
        return float("nan")
    back = np.flatnonzero(position[end_index:] <= threshold)
    return float(back[0] * dt) if back.size else float("inf")


def pulse_responses(
    sets: list[UnitParams], pulses: list[float], dt: float = 1e-3, total_s: float = 16.0
) -> list[PulseResponse]:
    """4 A pulses, one per (set, pulse) pair, each from rest; maxima and cooling times."""
    drives = np.stack([pulse_train(p, total_s, dt) for p in pulses])
    res = simulate(
        sets,
        dt,
        current=drives,
        channels=[
            "slider_position_m",
            "wire_force_n",
            "wire_temperature_c",
            "martensite_fraction",
            "energy_joule_j",
        ],
    )
    out = []
    for i, pulse in enumerate(pulses):
        x = res.slider_position_m[i]
        end = int(round(pulse / dt)) - 1
        cooled = cooling_time(x, end, dt)
        out.append(
            PulseResponse(
                pulse_s=pulse,
                energy_j=float(res.energy_joule_j[i, -1]),
                max_displacement_m=float(x.max()),
                max_force_n=float(res.wire_force_n[i].max()),
                cooling_time_s=cooled,
                cooled_temperature_c=float(res.wire_temperature_c[i, end + int(round(cooled / dt))])
                if math.isfinite(cooled)
                else math.nan,
                max_temperature_c=float(res.wire_temperature_c[i].max()),
                min_martensite=float(res.martensite_fraction[i].min()),
            )
        )
    return out


def controlled_cooling_times(
    sets: list[UnitParams],
    target_m: float = CONTROLLED_DISPLACEMENT_M,
    dt: float = 1e-3,
    total_s: float = 25.0,
) -> list[float]:
    """Cooling time of each set after 4 A drove its slider to ``target_m`` (then off)."""
    heat = simulate(
        sets,
        dt,
        current=np.full(int(round(10.0 / dt)), PULSE_CURRENT_A),
        channels=["slider_position_m"],
    )
    cutoff = []
    for i, p in enumerate(sets):
        reached = np.flatnonzero(heat.slider_position_m[i] >= target_m)
        if not reached.size:
            raise ValueError(f"set {p.name}: 4 A for 10 s never reaches {target_m * 1e3:.1f} mm")
        cutoff.append((reached[0] + 1) * dt)
    resp = pulse_responses(sets, cutoff, dt, total_s)
    return [r.cooling_time_s for r in resp]
