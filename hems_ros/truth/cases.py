"""The blind suite's truths: wire rigs with one effect in a form of its own, at several
sizes, read through sensors at three noise levels, written as a lab hands runs over.

Every truth is a :class:`~hems_ros.truth.rig.WireRig` of one of two families (``FAMILIES``):
Brinson's material, another SMA model family than the project's, so that the starting model
never equals it; or the dissertation's own law written again (``duhem``), where only the
effect's form and the solver differ from the model. Each is driven by current pulses: a
training run and a held-out run with other pulse lengths and currents, each with its own
noise draw. A supply's truth is driven instead through a PWM board by a position loop run on
the rig (``drive``), stepping through other contraction targets in each run. The supply,
warm-start and sensor forms beyond the drift are truths of the independent form only
(``Effect.families``).
``expected`` names the library candidates that count as naming the effect; the null truth
expects nothing named, an effect outside the library an ``unexplained`` or ``partial``
verdict. Nothing here knows the library: the names are what the diagnosis should say.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, replace
from pathlib import Path

import numpy as np

from hems_ros.truth.drive import Supply, simulate_closed_loop
from hems_ros.truth.duhem import DuhemMaterial
from hems_ros.truth.files import COLUMNS, DUTY_COLUMNS, write_run
from hems_ros.truth.measurement import Sensor
from hems_ros.truth.rig import WireRig, simulate
from hems_ros.truth.sheath import Sheath, Shell

PERIOD_S = 20.0  # a pulse every 20 s: the wire cools back to martensite in between
TRAIN_PULSES = ((1.2, 4.0), (1.6, 4.0), (2.0, 4.0), (1.4, 4.5), (1.8, 4.5), (1.0, 5.0))
HELDOUT_PULSES = ((1.5, 4.0), (1.9, 4.0), (1.3, 4.5), (1.2, 5.0))
SAMPLE_S = 0.01
#: contraction targets (mm) a position loop steps through, HOLD_S each, the wire cooling for
#: COOL_S after each train of steps: the closed-loop runs' training and held-out plans
TRAIN_STEPS_MM = ((6.0, 12.0, 18.0), (15.0, 9.0), (10.0, 20.0))
HELDOUT_STEPS_MM = ((8.0, 16.0), (13.0, 5.0))
HOLD_S = 5.0
COOL_S = 20.0
#: (contraction sensor in mm, force sensor in N) per noise level: coloured noise, latency,
#: spikes and the encoder's 1 um and the load cell's 0.01 N resolution
NOISE = {
    "low": (
        Sensor(noise_sd=0.002, rho=0.3, quantum=0.001),
        Sensor(noise_sd=0.02, rho=0.3, quantum=0.01),
    ),
    "mid": (
        Sensor(noise_sd=0.02, rho=0.6, latency_samples=1, quantum=0.001),
        Sensor(noise_sd=0.1, rho=0.6, latency_samples=1, quantum=0.01),
    ),
    "high": (
        Sensor(
            noise_sd=0.1,
            rho=0.9,
            latency_samples=2,
            spike_share=0.001,
            spike_size=0.5,
            quantum=0.001,
        ),
        Sensor(noise_sd=0.4, rho=0.9, latency_samples=2, quantum=0.01),
    ),
}


#: family -> the bare rig every effect of that family is added to
FAMILIES = {
    "dissertation": WireRig(material=DuhemMaterial(), convection_h0_h2=(37.67, 0.01)),
    "brinson": WireRig(),
}


@dataclass(frozen=True)
class Effect:
    """A truth family: what it changes at a size, and what the diagnosis should say."""

    name: str
    kind: str  # "effect", "null" or "outside"
    expected: tuple[str, ...]  # candidates that name it (an effect); empty otherwise
    sizes: tuple[float, ...]
    unit: str  # of the sizes
    rig: Callable[[WireRig, float], WireRig]  # (a family's bare rig, size)
    sensors: Callable[[float, tuple[Sensor, Sensor]], tuple[Sensor, Sensor]] = (
        lambda size, sensors: sensors
    )
    description: str = ""
    # a PWM drive's supply at a size: the runs are then driven by a position loop on the
    # truth (:mod:`~hems_ros.truth.drive`) instead of current pulses
    supply: Callable[[float], Supply] | None = None
    families: tuple[str, ...] = tuple(FAMILIES)  # the families it is a truth of


def _sheathed(bare: WireRig, scale: float) -> WireRig:
    base = Sheath()

    def scaled(shell: Shell) -> Shell:
        return replace(shell, heat_capacity_j_m3_k=shell.heat_capacity_j_m3_k * scale)

    return replace(bare, sheath=replace(base, liner=scaled(base.liner), helix=scaled(base.helix)))


def sheath_capacity_j_k(scale: float) -> float:
    """The sheath's heat capacity at a capacity ``scale`` of the dissertation's sheath."""
    rig = _sheathed(WireRig(), scale)
    network = rig.network()
    assert network is not None
    return float(network.capacities.sum())


def _stiffening(rig: WireRig, share: float) -> WireRig:
    k = rig.spring_n_m
    # the rate grows by ``share`` over 30 mm of extension, from the rest position on
    points = np.linspace(-0.01, 0.04, 11)
    force = [k * e * (1.0 + share * max(e, 0.0) / 0.03 / 2.0) for e in points]
    return replace(rig, spring_table=tuple(zip(points.tolist(), force)))


def _sagging(series_ohm: float) -> Supply:
    # the series resistance shared by the source, the leads and the switch, with a
    # polarisation that sags a further half of it over a few seconds
    return Supply(
        source_ohm=0.5 * series_ohm,
        cable_ohm=0.25 * series_ohm,
        switch_ohm=0.25 * series_ohm,
        droop_ohm=0.5 * series_ohm,
        droop_s=3.0,
    )


def _warming_cell(offset_n: float, sensors: tuple[Sensor, Sensor]) -> tuple[Sensor, Sensor]:
    contraction, force = sensors
    return contraction, replace(force, warmup=offset_n, warmup_s=40.0)


def _lagging(lag_s: float, sensors: tuple[Sensor, Sensor]) -> tuple[Sensor, Sensor]:
    contraction, force = sensors
    return replace(contraction, lag_s=lag_s), force


def _drifting(drift_um_s: float, sensors: tuple[Sensor, Sensor]) -> tuple[Sensor, Sensor]:
    contraction, force = sensors
    return replace(contraction, drift_per_s=drift_um_s * 1e-3), force


EFFECTS = (
    Effect(
        "none",
        "null",
        (),
        (0.0,),
        "-",
        lambda bare, size: bare,
        description="the rig as it is",
    ),
    Effect(
        "bowden_sheath",
        "effect",
        ("sheath_heat_sink",),
        (0.25, 0.5, 1.0),
        f"x the {sheath_capacity_j_k(1.0):.1f} J/K sheath",
        _sheathed,
        description="radial conduction through PTFE liner and steel helix sub-shells",
    ),
    Effect(
        "dahl_friction",
        "effect",
        ("tendon_friction", "capstan_friction"),
        (0.5, 1.0, 2.0, 4.0),
        "N",
        lambda bare, size: replace(bare, friction_n=size),
        description="dry friction with pre-sliding (Dahl) on the mass's guide",
    ),
    Effect(
        "stiffening_spring",
        "effect",
        ("spring_stiffening",),
        (0.1, 0.25, 0.5),
        "rate rise",
        _stiffening,
        description="bias spring from a force-extension table, stiffening with extension",
    ),
    Effect(
        "encoder_drift",
        "outside",
        (),
        (2.0, 5.0, 10.0),
        "um/s",
        lambda bare, size: bare,
        sensors=_drifting,
        description="the contraction sensor's zero creeping (no candidate has it)",
    ),
    Effect(
        "supply_droop",
        "effect",
        ("supply_sag",),
        (1.0, 1.5),
        "ohm in series",
        lambda bare, size: bare,
        description="a 20 V supply behind source, lead and switch resistances and a sagging "
        "polarisation, PWM-driven by a position loop run on the rig",
        supply=_sagging,
        families=("dissertation",),
    ),
    Effect(
        "load_cell_warmup",
        "effect",
        ("force_sensor_drift",),
        (0.5, 2.0),
        "N",
        lambda bare, size: bare,
        sensors=_warming_cell,
        description="the load cell's offset settling exponentially (40 s) as it warms up",
        families=("dissertation",),
    ),
    Effect(
        "warm_wire",
        "effect",
        ("warm_start",),
        (10.0, 25.0),
        "K above the room",
        lambda bare, size: replace(bare, start_c=bare.ambient_c + size),
        description="the wire still warm from a run before when the log starts",
        families=("dissertation",),
    ),
    Effect(
        "encoder_lag",
        "outside",
        (),
        (0.03, 0.1),
        "s",
        lambda bare, size: bare,
        sensors=_lagging,
        description="the contraction sensor behind a first-order filter (no candidate lags "
        "one channel alone)",
        families=("dissertation",),
    ),
)
BY_NAME = {e.name: e for e in EFFECTS}


def pulses(plan: tuple[tuple[float, float], ...]) -> list[tuple[float, float, float]]:
    return [(1.0 + PERIOD_S * k, 1.0 + PERIOD_S * k + s, a) for k, (s, a) in enumerate(plan)]


def steps(plan: tuple[tuple[float, ...], ...]) -> tuple[list[tuple[float, float, float]], float]:
    """(targets as (start s, end s, contraction m), duration s) of a closed-loop plan."""
    targets, t = [], 1.0
    for train in plan:
        for level in train:
            targets.append((t, t + HOLD_S, level * 1e-3))
            t += HOLD_S
        t += COOL_S
    return targets, t


def columns(effect: Effect) -> str:
    """``hems diagnose --columns`` for the logs of ``effect``'s runs."""
    return COLUMNS if effect.supply is None else DUTY_COLUMNS


def write_case(
    family: str, effect: Effect, size: float, noise: str, seed: int, folder: Path
) -> dict:
    """The training and held-out runs of one truth in ``folder``: their CSV and conditions."""
    if family not in effect.families:
        raise ValueError(f"{effect.name} is a truth of {', '.join(effect.families)}, not {family}")
    rig = effect.rig(FAMILIES[family], size)
    contraction, force = effect.sensors(size, NOISE[noise])
    sensors = {"contraction": contraction, "wire_force": force}
    rng = np.random.default_rng([seed, int(1000 * size), len(effect.name)])
    supply = None if effect.supply is None else effect.supply(size)
    out = {}
    for role, plan, loop_plan in (
        ("train", TRAIN_PULSES, TRAIN_STEPS_MM),
        ("heldout", HELDOUT_PULSES, HELDOUT_STEPS_MM),
    ):
        if supply is None:
            run = simulate(rig, pulses(plan), PERIOD_S * len(plan), SAMPLE_S)
        else:
            run = simulate_closed_loop(rig, supply, *steps(loop_plan))
        out[role] = write_run(run, rig, folder, role, sensors, rng, supply)
    return out
