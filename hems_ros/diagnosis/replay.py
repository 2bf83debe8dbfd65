"""Replay measured time series on the model: the measured input drives it open loop.

The recorded duty, current or voltage (held between samples, as the drive board holds it)
or the measured wire temperature (a thermal cycle, interpolated between samples) drives
many parameter sets at once through the batch API, and the model's outputs are read at the
measured sample instants. Sample 0 is the initial state: a wire at rest, martensite, at its
start temperature.

What a sensor error changes (``SENSOR_KEYS``: encoder gain, force offset and drift) is
applied to the simulated truth here, so sets that differ only in those share one
simulation.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from hems_ros.diagnosis.candidates import SENSOR_KEYS
from hems_ros.diagnosis.runs import DiagnosisInputError, TimeSeriesRun
from hems_ros.physics import rows
from hems_ros.physics.batch import simulate
from hems_ros.physics.params import UnitParams

#: Plant step of the replay of an electrically driven run: the graph's (1 kHz).
DEFAULT_DT = 1e-3
#: Thermal cycles are quasi-static; a coarser step keeps long paths cheap.
THERMAL_DT = 1e-2
#: Finest plant step of a replay (10 kHz sampling).
MIN_STEP = 1e-4
_GRAVITY = 9.81
_KERNEL_CHANNELS = {
    "position": "slider_position_m",
    "strain": "slider_position_m",
    "wire_force": "wire_force_n",
    "load_force": "tendon_force_n",
    "temperature": "wire_temperature_c",
}


#: A load frame's stiffness over the wire's own (austenite, E A / L): the wire's strain is
#: the frame's to a thousandth of its elastic part.
FRAME_STIFFNESS_RATIO = 1e3


def frame_rig(params: UnitParams, preload_pa: float) -> UnitParams:
    """A bare wire whose end a stiff load frame moves, preloaded to ``preload_pa``; the
    frame's load cell reads any force."""
    if not preload_pa > 0:
        raise DiagnosisInputError(
            f"prescribed strain: preload {preload_pa:g} Pa must be > 0 (a wire under load)"
        )
    wire = params.wire
    stiffness = (
        FRAME_STIFFNESS_RATIO
        * params.constitutive.e_austenite_pa
        * wire.cross_section_m2
        / wire.length_m
    )
    return params.replace(
        {
            "load.kind": "bias_spring",
            "load.mass_kg": 0.0,
            "load.damping_n_s_per_m": 0.0,
            "load.pretension_n": preload_pa * wire.cross_section_m2,
            "load.stiffness_n_per_m": stiffness,
            "load.cubic_stiffness_n_per_m3": 0.0,
            "load.pulley_ratio": 1.0,
            "capstan.enabled": False,
            "glove_friction.enabled": False,
            "force_sensor.range_max_n": 1e6,
        }
    )


def static_forces(sets: list[UnitParams], run: TimeSeriesRun, held: np.ndarray) -> np.ndarray:
    """(n_sets, n_steps) static load force of each rigged set under the run's held load: a
    thermal cycle's stress times the cross-section; a frame's preload plus its stiffness
    times the end displacement that imposes the strain."""
    if run.kind == "thermal_cycle":
        return np.stack([held * s.wire.cross_section_m2 for s in sets])
    return np.stack(
        [s.load.pretension_n + s.load.stiffness_n_per_m * s.wire.length_m * held for s in sets]
    )


def thermal_cycle_rig(params: UnitParams, stress_pa: float) -> UnitParams:
    """A bare wire under a dead weight that holds ``stress_pa`` (the lab's constant stress)."""
    mass = stress_pa * params.wire.cross_section_m2 / _GRAVITY
    if not mass > 0:
        raise DiagnosisInputError(
            f"thermal cycle: stress {stress_pa:g} Pa must be > 0 (a wire under load)"
        )
    return params.replace(
        {
            "load.kind": "hanging_mass",
            "load.mass_kg": mass,
            "load.pretension_n": 0.0,
            "load.stiffness_n_per_m": 0.0,
            "load.cubic_stiffness_n_per_m3": 0.0,
            "load.pulley_ratio": 1.0,
            "load.gravity_m_s2": _GRAVITY,
            "sheath.enabled": False,
            "capstan.enabled": False,
            "glove_friction.enabled": False,
        }
    )


@dataclass(frozen=True)
class ReplayPlan:
    """How one run is replayed: the per-step input and where its samples fall."""

    run: TimeSeriesRun
    dt: float
    drive: str  # keyword of batch.simulate
    values: np.ndarray  # per plant step
    record_every: int
    records: np.ndarray  # record index of samples 1..n-1 (sample 0 is the initial state)
    # per plant step, the load the rig holds: a thermal cycle's stress (Pa) when it wanders,
    # a prescribed-strain run's strain
    held_load: np.ndarray | None = None

    @property
    def thermal(self) -> bool:
        return self.drive == "temperature"


def plan(run: TimeSeriesRun, dt: float | None = None) -> ReplayPlan:
    """Steps, input and sample positions of ``run`` (the step shrinks for fast sampling)."""
    thermal = run.drive == "temperature"
    step = dt if dt is not None else (THERMAL_DT if thermal else DEFAULT_DT)
    gaps = np.diff(run.time)
    if gaps.size == 0:
        raise DiagnosisInputError(f"{run.name}: a run needs more than one sample")
    step = _grid_step(run.time, min(step, float(gaps.min())))
    if step < MIN_STEP * (1.0 - 1e-6):
        raise DiagnosisInputError(
            f"{run.name}: samples {gaps.min() * 1e3:.3g} ms apart; "
            "the replay needs them at least 0.1 ms apart"
        )
    index = np.rint(run.time / step).astype(np.int64)
    if np.any(np.diff(index) <= 0):
        raise DiagnosisInputError(
            f"{run.name}: sample instants do not fall on distinct {step * 1e3:g} ms steps"
        )
    every = int(np.gcd.reduce(index[1:]))
    if thermal:
        ends = (np.arange(index[-1]) + 1) * step
        values = np.interp(ends, run.time, run.drive_values)
    elif run.drive_steps is not None:
        # a change between steps takes effect at the next step, as a unit applies a command
        # at the step after it arrives
        times, levels = run.drive_steps
        starts = np.arange(index[-1]) * step
        last = np.searchsorted(times, starts + 1e-9, side="right") - 1
        values = np.where(last >= 0, levels[np.maximum(last, 0)], 0.0)
    else:
        values = np.repeat(run.drive_values[:-1], np.diff(index))
    return ReplayPlan(
        run, step, run.drive, values, every, index[1:] // every - 1, _held_load(run, index)
    )


def _held_load(run: TimeSeriesRun, index: np.ndarray) -> np.ndarray | None:
    """Between two samples the rig holds the mean of their loads."""
    load = run.strain_values if run.kind == "prescribed_strain" else run.stress_values
    if load is None:
        return None
    return np.repeat(0.5 * (load[:-1] + load[1:]), np.diff(index))


def _grid_step(time: np.ndarray, step: float) -> float:
    """The largest step at most ``step`` (a whole fraction of it) whose grid holds every sample
    instant to 1 % of a step, so the outputs are read at the measured instants; ``step`` when
    none of the first ten does (the samples are read at the nearest step)."""
    for divisor in range(1, 11):
        trial = step / divisor
        if trial < MIN_STEP * (1.0 - 1e-6):
            break
        if np.max(np.abs(time / trial - np.rint(time / trial))) <= 0.01:
            return trial
    return step


def rig(params: UnitParams, run: TimeSeriesRun) -> UnitParams:
    """The parameter set the run's conditions call for (a thermal cycle's dead weight, a
    prescribed-strain run's frame)."""
    if run.kind not in ("thermal_cycle", "prescribed_strain"):
        return params
    if run.stress_pa is None:
        raise DiagnosisInputError(f"{run.name}: a {run.kind} run needs the wire's stress")
    if run.kind == "thermal_cycle":
        return thermal_cycle_rig(params, run.stress_pa)
    return frame_rig(params, run.stress_pa)


def start_temperature(run: TimeSeriesRun) -> float | None:
    """A run driven by temperature starts at its first one; an electrically driven run at the
    model's ambient."""
    return float(run.drive_values[0]) if run.drive == "temperature" else None


def cannot_start(params: UnitParams, run: TimeSeriesRun) -> str | None:
    """Why ``params`` cannot replay ``run`` from a martensite wire, or None."""
    first = start_temperature(run)
    if first is not None and first >= params.kinetics.as0_c:
        return (
            f"{run.name}: the run starts at {first:g} degC, at or above As0 = "
            f"{params.kinetics.as0_c:g} degC of the model; it must start cold, with the "
            f"wire martensite"
        )
    return None


BEYOND_RANGE_SHARE = 0.01


def beyond_sensor(params: UnitParams, run: TimeSeriesRun) -> str | None:
    """Why the model's force sensor could not have read ``run``'s wire force, or None: a
    reading above its range shows that the lab's load cell is another one."""
    force = run.outputs.get("wire_force")
    top = rig(params, run).force_sensor.range_max_n  # a frame's load cell reads any force
    # a few noisy readings just past the range are the sensor's noise at its limit
    if force is None or not force.size or np.mean(force > top) <= BEYOND_RANGE_SHARE:
        return None
    return (
        f"{run.name}: the wire force reaches {float(np.max(force)):.4g} N "
        f"({np.mean(force > top):.0%} of the samples), above the model's "
        f"force sensor range of {top:g} N (force_sensor.range_max_n), where its readings stop; "
        "give the load cell's range in --conditions (force_sensor: {range_max_n: ...}) or "
        "with --set force_sensor.range_max_n=..."
    )


def physics_key(params: UnitParams) -> UnitParams:
    """``params`` with the sensor errors at their defaults: what the simulation depends on."""
    return params.replace({key: (1.0 if key == "encoder.gain" else 0.0) for key in SENSOR_KEYS})


def replay(p: ReplayPlan, sets: list[UnitParams]) -> dict[str, np.ndarray]:
    """Each measured output of the run as the model gives it: (n_sets, n_samples) arrays."""
    run = p.run
    rigged = [rig(s, run) for s in sets]  # the rig's sensors read too
    keys = [physics_key(r) for r in rigged]
    unique: dict[UnitParams, int] = {}
    for key in keys:
        if cannot_start(key, run) is None:
            unique.setdefault(key, len(unique))
    out = {name: np.full((len(sets), run.n_samples), np.nan) for name in run.outputs}
    if not unique:
        return out
    physics = list(unique)
    wanted = sorted({_KERNEL_CHANNELS[name] for name in run.outputs})
    start = start_temperature(run)
    delays = [key.drive.input_delay_s for key in physics]
    values = np.stack([delayed(p.values, d / p.dt) for d in delays]) if any(delays) else p.values
    res = simulate(
        physics,
        p.dt,
        record_every=p.record_every,
        channels=wanted,
        start_temperature_c=start,
        static_force_n=None if p.held_load is None else static_forces(physics, run, p.held_load),
        **{p.drive: values},
    )
    initial = _initial_outputs(physics, start)
    live = np.array([k in unique for k in keys])
    picked = np.array([unique[k] for k in keys if k in unique])
    chosen = [r for r, ok in zip(rigged, live) if ok]
    for name in run.outputs:
        channel = _KERNEL_CHANNELS[name]
        series = np.concatenate([initial[channel][:, None], res[channel][:, p.records]], axis=1)[
            picked
        ]
        out[name][live] = _sensor(name, series, chosen, run.time)
    return out


def delayed(values: np.ndarray, steps: float) -> np.ndarray:
    """The per-step input as the wire receives it ``steps`` plant steps (any real number)
    after its record: each step takes the record at its own index minus ``steps``, between
    two steps in proportion (so a fit sees a smooth cost), the first or last record beyond
    the ends. The delay is the same for every step, so this is two shifted copies blended
    by one share (five times quicker than indexing each step: a fit of the timing
    candidates calls it thousands of times)."""
    lower = math.floor(-steps)  # the earlier record's offset from each step's own index
    share = -steps - lower
    earlier = _shifted(values, lower)
    # in this form a step between two equal records is that record exactly, and no step lies
    # outside its two records (a duty between 100 and 100 % stays 100 %)
    return earlier + share * (_shifted(values, lower + 1) - earlier)


def _shifted(values: np.ndarray, offset: int) -> np.ndarray:
    """``values[clip(i + offset, 0, n - 1)]`` for every index ``i``."""
    n = values.size
    out = np.empty_like(values)
    if n == 0:
        return out
    if offset >= 0:
        kept = max(n - offset, 0)
        out[:kept] = values[offset : offset + kept]
        out[kept:] = values[-1]
    else:
        held = min(-offset, n)
        out[:held] = values[0]
        out[held:] = values[: n - held]
    return out


def _initial_outputs(sets: list[UnitParams], start: float | None) -> dict[str, np.ndarray]:
    """The kernel channels at t = 0 (the batch records only after steps)."""
    states = [rows.initial_state(p, start) for p in sets]
    force = np.array([p.wire.cross_section_m2 * s[rows.S_SIG] for p, s in zip(sets, states)])
    return {
        "slider_position_m": np.array([s[rows.S_X] for s in states]),
        "wire_force_n": force,
        "tendon_force_n": np.array([p.load.static_force_n() for p in sets]),
        "wire_temperature_c": np.array([s[rows.S_T] for s in states]),
    }


def _sensor(name: str, truth: np.ndarray, sets: list[UnitParams], time: np.ndarray) -> np.ndarray:
    """What the measuring chain of each set reads of the simulated ``truth``."""
    if name == "position":
        return truth * np.array([s.encoder.gain for s in sets])[:, None]
    if name == "strain":
        return -truth / np.array([s.wire.length_m for s in sets])[:, None]
    if name == "wire_force":
        offset = np.array([s.force_sensor.offset_n for s in sets])[:, None]
        drift = np.array([s.force_sensor.drift_n_per_s for s in sets])[:, None]
        top = np.array([s.force_sensor.range_max_n for s in sets])[:, None]
        # the sensor reads within 0..range (sensors.force_reading); a slack wire reads 0
        return np.clip(truth + offset + drift * time[None, :], 0.0, top)
    return truth
