"""Batch API: many parameter sets over whole input time series, for analysis and fitting.

    res = simulate([p1, p2], dt=1e-3, current=np.array([...]))   # (n_steps,) or (n_sets, n_steps)
    simulate(p, dt=1e-2, temperature=ramp, start_temperature_c=ramp[0])  # imposed temperature, degC
    res.slider_position_m          # (n_sets, n_records) array; also res["wire_force_n"]
    res.time                       # (n_records,) s, time at the end of each recorded step

Parameter sets are packed into a (n_sets, N_P) float64 array and run in parallel by
block.run_batch, in blocks of sets whose step arithmetic is vectorised across the sets; a set
gives the same bits as the stepping API's kernel.step (to rounding when no energy channel is
recorded: the blocks then skip the energy accumulators, a tenth of their work).
``record_every`` keeps every k-th step; ``channels`` limits what is stored (memory for big
batches) and, for the energy channels, what is computed. Sensor channels (encoder, force
reading with the seeded noise of each set) are derived on first access from the recorded
truth, with the same functions and noise draws as the stepping API.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Iterable, Sequence

import numpy as np

from hems_ros.physics import block, jit, rows, sensors
from hems_ros.physics.electrical import DRIVE_NAMES, select_drive
from hems_ros.physics.params import UnitParams

CHANNELS = rows.STATE_NAMES + rows.OUT_NAMES
DERIVED = ("strain", "encoder_counts", "encoder_position_m", "force_reading_n", "force_saturated")


@dataclass
class SimResult:
    """Recorded channels, each an array shaped (n_sets, n_records).

    Sensor channels (``strain``, ``encoder_counts``, ``encoder_position_m``,
    ``force_reading_n``, ``force_saturated``) are computed on first access, so a fitting
    loop that reads only the truth does not pay for them.
    """

    params: list[UnitParams]
    dt: float
    record_every: int
    time: np.ndarray
    data: dict[str, np.ndarray] = field(default_factory=dict)
    n_steps: int = 0

    @property
    def n_sets(self) -> int:
        """Number of parameter sets simulated."""
        return len(self.params)

    def __getitem__(self, name: str) -> np.ndarray:
        """Return channel ``name``, (n_sets, n_records); sensor channels derive on first use."""
        if name in DERIVED and name not in self.data:
            _add_sensors(self.data, self.params, self.n_steps, self.record_every, self.time)
        if name not in self.data:
            raise KeyError(
                f"SimResult has no channel {name!r} (recorded: {', '.join(self.channels())})"
            )
        return self.data[name]

    def __getattr__(self, name: str) -> np.ndarray:
        """Return channel ``name`` as an attribute (``result.wire_force_n``)."""
        if name.startswith("__") or name not in CHANNELS + DERIVED:
            raise AttributeError(name)
        try:
            return self[name]
        except KeyError as exc:
            raise AttributeError(str(exc)) from None

    def channels(self) -> list[str]:
        """List the recorded channels and the sensor channels derivable from them."""
        derivable = []
        if "slider_position_m" in self.data:
            derivable += ["strain", "encoder_counts", "encoder_position_m"]
        if "wire_force_n" in self.data:
            derivable += ["force_reading_n", "force_saturated"]
        return list(dict.fromkeys(list(self.data) + derivable))


def _drive_array(kind: str, values, n_sets: int) -> np.ndarray:
    """(n_sets, n_steps), or (1, n_steps) when every set gets the same input."""
    arr = np.asarray(values, dtype=np.float64)
    if arr.ndim == 1:
        arr = arr[None, :]
    if arr.ndim != 2 or arr.shape[0] not in (1, n_sets):
        raise ValueError(
            f"{kind}: expected shape (n_steps,) or ({n_sets}, n_steps), got {np.shape(values)}"
        )
    if arr.shape[1] == 0:
        raise ValueError(f"{kind}: no steps")
    bad = ~np.isfinite(arr)
    if bad.any():
        i, k = np.argwhere(bad)[0]
        raise ValueError(f"{kind}[{i}, {k}] = {float(arr[i, k])!r}: drive input must be finite")
    if kind == "duty" and ((arr < 0).any() or (arr > 100).any()):
        i, k = np.argwhere((arr < 0) | (arr > 100))[0]
        raise ValueError(f"duty[{i}, {k}] = {float(arr[i, k])!r} %: must be within 0-100 %")
    return np.ascontiguousarray(arr)


def _load_segments(
    static_force_n, n_sets: int, n_steps: int, every: int
) -> list[tuple[int, int, np.ndarray | None]]:
    """Split the steps into runs under one load.

    Returns (first step, end step, static force of each set or None: its own) of each run.
    """
    if static_force_n is None:
        return [(0, n_steps, None)]
    force = np.asarray(static_force_n, dtype=np.float64)
    force = np.broadcast_to(force, (n_sets, n_steps)) if force.ndim == 1 else force
    if force.shape != (n_sets, n_steps):
        raise ValueError(
            f"static_force_n: expected shape ({n_steps},) or ({n_sets}, {n_steps}), "
            f"got {np.shape(static_force_n)}"
        )
    if not np.isfinite(force).all():
        i, k = np.argwhere(~np.isfinite(force))[0]
        raise ValueError(f"static_force_n[{i}, {k}] = {float(force[i, k])!r}: must be finite")
    changes = np.flatnonzero(np.any(np.diff(force, axis=1) != 0, axis=0)) + 1
    if (changes % every).any():
        k = int(changes[np.argmax(changes % every != 0)])
        raise ValueError(
            f"static_force_n changes at step {k}, inside a record of {every} steps: it may "
            f"change only where a record ends"
        )
    bounds = np.concatenate(([0], changes, [n_steps]))
    return [(int(a), int(b), force[:, a].copy()) for a, b in zip(bounds[:-1], bounds[1:])]


def _start_temperatures(start_temperature_c, n_sets: int) -> list:
    """One start temperature (degC, or None: the set's own start) per set."""
    if start_temperature_c is None or np.ndim(start_temperature_c) == 0:
        return [start_temperature_c] * n_sets
    starts = list(start_temperature_c)
    if len(starts) != n_sets:
        raise ValueError(
            f"start_temperature_c: expected one value per set ({n_sets}), got {len(starts)}"
        )
    return starts


def simulate(
    params: UnitParams | Sequence[UnitParams],
    dt: float = 1e-3,
    *,
    duty=None,
    current=None,
    voltage=None,
    temperature=None,
    record_every: int = 1,
    channels: Iterable[str] | None = None,
    start_temperature_c=None,
    static_force_n=None,
) -> SimResult:
    """Run one or many parameter sets from the initial state over one drive time series.

    Exactly one of ``duty`` (%), ``current`` (A), ``voltage`` (V), ``temperature`` (the wire
    temperature imposed at the end of each step, degC); arrays shaped (n_steps,) (same input
    for every set) or (n_sets, n_steps). ``start_temperature_c``: a start temperature for
    every set, or one per set (None: the set's own start, ambient plus ``params.start``),
    as rows.initial_state takes it. ``static_force_n``: the load's static force (N, load
    coordinates, in place of each set's m g + F_0) step by step, (n_steps,) or (n_sets,
    n_steps): a frame holding a stress that wanders, or moving the end of a stiff spring; it
    may change only where a record ends (a multiple of ``record_every`` steps), and the start
    state is the one under each set's own static force.
    """
    plist = [params] if isinstance(params, UnitParams) else list(params)
    if not plist or not all(isinstance(p, UnitParams) for p in plist):
        raise TypeError("params must be a UnitParams or a non-empty sequence of UnitParams")
    if not (np.isfinite(dt) and dt > 0):
        raise ValueError(f"dt = {dt!r}: must be a finite step > 0 s")
    kind, values = select_drive(duty, current, voltage, temperature)
    drives = _drive_array(kind, values, len(plist))
    if not (isinstance(record_every, (int, np.integer)) and record_every >= 1):
        raise ValueError(f"record_every = {record_every!r}: must be an integer >= 1")

    wanted = list(CHANNELS) if channels is None else list(channels)
    unknown = [c for c in wanted if c not in CHANNELS]
    if unknown:
        raise ValueError(f"unknown channel {unknown[0]!r} (known: {', '.join(CHANNELS)})")
    index = np.array([CHANNELS.index(c) for c in wanted], dtype=np.int64)

    n_sets, n_steps = len(plist), drives.shape[1]
    n_rec = n_steps // record_every
    imposed = kind == "temperature"
    packed = np.ascontiguousarray(
        np.stack([rows.pack(p, temperature_drive=imposed) for p in plist])
    )
    starts = _start_temperatures(start_temperature_c, n_sets)
    states = np.ascontiguousarray(
        np.stack([rows.initial_state(p, t) for p, t in zip(plist, starts)])
    )
    records = np.zeros((len(index), n_sets, n_rec))
    failed_at = np.zeros(n_sets, dtype=np.int64)
    for first, last, static in _load_segments(static_force_n, n_sets, n_steps, record_every):
        if static is not None:
            packed[:, rows.P_FSTAT] = static
        whole = (first, last) == (0, n_steps)
        part = records if whole else np.zeros((len(index), n_sets, (last - first) // record_every))
        jit.apply_thread_limit()
        block.run_batch(
            packed,
            states,
            DRIVE_NAMES[kind],
            np.ascontiguousarray(drives[:, first:last]),
            float(dt),
            int(record_every),
            index,
            part,
            failed_at,
        )
        if part is not records:
            records[:, :, first // record_every : last // record_every] = part
        if (failed_at >= 0).any():
            failed_at[failed_at >= 0] += first
            break
    if (failed_at >= 0).any():
        i = int(np.argmax(failed_at >= 0))
        raise FloatingPointError(
            f"parameter set {i} ({plist[i].name}): state became non-finite "
            f"at step {failed_at[i]} (t = {(failed_at[i] + 1) * dt:.6f} s)"
        )

    data = {name: records[j] for j, name in enumerate(wanted)}
    time = (np.arange(n_rec) + 1) * record_every * dt
    return SimResult(
        params=plist,
        dt=float(dt),
        record_every=int(record_every),
        time=time,
        data=data,
        n_steps=n_steps,
    )


def _add_sensors(
    data: dict[str, np.ndarray], plist: list[UnitParams], n_steps: int, every: int, time: np.ndarray
) -> None:
    """Add the sensor channels derived from the recorded truth to ``data``.

    The draws are the stepping API's; the force sensor's drift runs on the time of each record.
    """

    def column(values):
        return np.array(values, dtype=np.float64)[:, None]

    if "slider_position_m" in data:
        x = data["slider_position_m"]
        data["strain"] = x / column([p.wire.length_m for p in plist])
        resolution = column([p.encoder.resolution_m for p in plist])
        counts = sensors.encoder_counts_array(
            x, resolution, column([p.encoder.gain for p in plist])
        )
        data["encoder_counts"] = counts
        data["encoder_position_m"] = counts * resolution
    if "wire_force_n" in data:
        picks = np.arange(every - 1, (n_steps // every) * every, every)
        noise = np.stack(
            [
                sensors.noise_generator(p.force_sensor.seed).standard_normal(n_steps)[picks]
                if p.force_sensor.noise_std_n > 0
                else np.zeros(picks.size)
                for p in plist
            ]
        )
        fs = [p.force_sensor for p in plist]
        reading, saturated = sensors.force_reading_array(
            data["wire_force_n"],
            noise * column([f.noise_std_n for f in fs]),
            column([f.range_max_n for f in fs]),
            column([f.resolution_n for f in fs]),
            column([f.offset_n for f in fs]),
            column([f.drift_n_per_s for f in fs]),
            time,
        )
        data["force_reading_n"] = reading
        data["force_saturated"] = saturated
