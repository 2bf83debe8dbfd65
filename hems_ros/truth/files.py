"""A truth run as a lab hands it over: a CSV log and a YAML note of the rig's conditions.

The log has what a bench records (the commanded current, or a PWM drive's duty; the
encoder's contraction, the load cell's wire force), each output through its
:class:`~hems_ros.truth.measurement.Sensor`; the conditions name the rig in the layout of
``config/physics/*.yaml`` (load, ambient, a PWM drive's nominal supply), as a user writes
them for ``hems diagnose --conditions``. Nothing about the material or the supply's losses
goes there: finding them is the diagnosis's job.
"""

from __future__ import annotations

import csv
from collections.abc import Mapping
from pathlib import Path

import numpy as np
import yaml

from hems_ros.truth.drive import Supply
from hems_ros.truth.measurement import Sensor, measure
from hems_ros.truth.rig import RigRun, WireRig

#: ``hems diagnose --columns`` for the log :func:`write_run` writes of a current-driven run
COLUMNS = "time=time_s:s,current=current_a:A,displacement=contraction_mm:mm,wire_force=force_n:N"
#: the same for a PWM-driven run
DUTY_COLUMNS = COLUMNS.replace("current=current_a:A", "duty=duty_pct:%")

#: the bench's load cell reads 0-200 N (the project's own force sensor stops at 50 N)
LOAD_CELL_RANGE_N = 200.0

#: channel -> (column, scale from the run's SI unit to the column's)
CHANNELS = {"contraction": ("contraction_mm", 1e3), "wire_force": ("force_n", 1.0)}


def conditions(rig: WireRig, supply: Supply | None = None) -> dict:
    """The rig's conditions in the project's physics-config layout; a PWM drive's nominal
    supply voltage and current limit when ``supply`` drove it."""
    drive = (
        {}
        if supply is None
        else {
            "drive": {
                "supply_voltage_v": supply.voltage_v,
                "current_limit_a": supply.current_limit_a,
            }
        }
    )
    return drive | {
        "ambient_temperature_c": rig.ambient_c,
        "wire": {"diameter_m": rig.diameter_m, "length_m": rig.length_m},
        "load": {
            "kind": "hanging_mass",
            "mass_kg": rig.mass_kg,
            "gravity_m_s2": rig.gravity_m_s2,
            "damping_n_s_per_m": rig.damping_n_s_m,
            "stiffness_n_per_m": rig.spring_n_m,
            "pretension_n": rig.preload_n,
            "pulley_ratio": 1.0,
        },
        "force_sensor": {"range_max_n": LOAD_CELL_RANGE_N},
    }


def write_run(
    run: RigRun,
    rig: WireRig,
    folder: Path,
    name: str,
    sensors: Mapping[str, Sensor],
    rng: np.random.Generator,
    supply: Supply | None = None,
) -> tuple[Path, Path]:
    """Write ``<name>.csv`` and ``<name>_conditions.yaml`` into ``folder``; their paths.

    ``sensors``: a :class:`Sensor` per channel of :data:`CHANNELS`, in its column's unit (mm,
    N); a channel left out is recorded exactly. A PWM-driven run (``supply``) logs its duty
    instead of the current (:data:`DUTY_COLUMNS`)."""
    unknown = set(sensors) - set(CHANNELS)
    if unknown:
        raise ValueError(
            f"no channel {', '.join(sorted(unknown))}; channels: {', '.join(CHANNELS)}"
        )
    folder.mkdir(parents=True, exist_ok=True)
    sample_s = float(np.median(np.diff(run.time_s)))
    true = {"contraction": run.contraction_m, "wire_force": run.wire_force_n}
    if (supply is None) != (run.duty_percent is None):
        raise ValueError("a PWM-driven run needs its supply, a current-driven one none")
    drive = (
        {"current_a": run.current_a} if run.duty_percent is None else {"duty_pct": run.duty_percent}
    )
    columns = {"time_s": run.time_s, **drive}
    for channel, (column, scale) in CHANNELS.items():
        values = true[channel] * scale
        sensor = sensors.get(channel)
        columns[column] = values if sensor is None else measure(values, sample_s, sensor, rng)
    log = folder / f"{name}.csv"
    with log.open("w", newline="") as handle:
        writer = csv.writer(handle)
        writer.writerow(columns)
        writer.writerows(zip(*(np.round(v, 9) for v in columns.values())))
    note = folder / f"{name}_conditions.yaml"
    note.write_text(yaml.safe_dump(conditions(rig, supply), sort_keys=False))
    return log, note
