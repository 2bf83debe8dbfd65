"""Bags recorded by the project as driven runs, one per finger, from what the hardware measures.

Only the hardware's own streams are read (:func:`measured_topics`): the duty commands, the
slider encoder, the wire-force sensor and the setpoints (for the phase labels). The
``/hems/sim/...`` topics are simulation truth no real unit provides; a diagnosis that read
them would not carry over to hardware bags, so they are never requested.

The time base is the encoder's header stamps (the unit's clock), from the first encoder
sample. A duty command answers the encoder sample whose stamp is its ``measurement_stamp``
and the unit applies it from that sample until the next command, or until its watchdog
forces 0 after more than three encoder periods without one; the run's ``drive_values`` model
exactly that on the encoder samples. The wire-force sensor stamps each reading with the
encoder sample it comes from, so the two streams are joined on equal stamps; a sample
missing from either is dropped (counted in the notes), leaving its gap in ``time``.

A measurement that is not a number (NaN or inf, a sensor's failure value) is dropped the same
way, named by topic and count in the notes; a run with more than ``runs.MAX_BAD_SHARE`` of
its samples dropped so is refused. A duty command outside 0-100 % or not a number is refused,
naming the topic and the message: the input is what the model is driven with, and a wrong
one would be fitted as physics.
"""

from __future__ import annotations

import os
from collections.abc import Iterable
from pathlib import Path

import numpy as np

from hems_ros.bag import Bag, BagFormatError, TopicData, load_bag
from hems_ros.diagnosis.csvload import require_span
from hems_ros.diagnosis.runs import DiagnosisInputError, TimeSeriesRun, non_finite_note
from hems_ros.graph import names

STREAMS = ("duty", "encoder", "wire_force", "setpoint")
REQUIRED = ("duty", "encoder")
WATCHDOG_PERIODS = 3
DEFAULT_FORCE_RESOLUTION_N = 0.01


def measured_topics(fingers: Iterable[str]) -> list[str]:
    """Every topic the loader requests for ``fingers``: the hardware's streams, no
    simulation truth."""
    return [names.topic(finger, stream) for finger in fingers for stream in STREAMS]


def _stamp_ns(data: TopicData, prefix: str = "header.stamp") -> np.ndarray:
    return data[f"{prefix}.sec"].astype(np.int64) * 1_000_000_000 + data[
        f"{prefix}.nanosec"
    ].astype(np.int64)


def _read(path: Path, fingers: tuple[str, ...]) -> Bag:
    try:
        return load_bag(path, topics=measured_topics(fingers))
    except (BagFormatError, OSError) as error:
        raise DiagnosisInputError(f"{path}: not a readable bag ({error})") from None


def load_bag_runs(
    path: str | os.PathLike, fingers: Iterable[str] | None = None
) -> list[TimeSeriesRun]:
    """One driven run (drive ``duty``) per finger of the bag at ``path`` (module docstring).

    ``fingers`` restricts the fingers (default: every finger with duty and encoder messages).
    """
    path = Path(path)
    try:
        requested = None if fingers is None else tuple(names.check_finger(f) for f in fingers)
    except ValueError as error:
        raise DiagnosisInputError(str(error)) from None
    if requested == ():
        raise DiagnosisInputError(f"{path}: no finger requested")
    bag = _read(path, requested or names.FINGERS)
    present = [f for f in names.FINGERS if all(names.topic(f, s) in bag for s in REQUIRED)]
    for finger in requested or ():
        missing = [names.topic(finger, s) for s in REQUIRED if names.topic(finger, s) not in bag]
        if missing:
            raise DiagnosisInputError(
                f"{path}: no {' or '.join(missing)} messages in the bag (fingers with "
                f"duty and encoder messages: {', '.join(present) or 'none'})"
            )
    if not present:
        raise DiagnosisInputError(
            f"{path}: no finger has duty and encoder messages in the bag "
            f"(read: {', '.join(sorted(bag.topics)) or 'nothing'})"
        )
    notes = [
        f"bag cut or unfinished, loaded as far as it goes: {r.describe()}"
        for r in bag.reports
        if not r.complete or r.skipped
    ]
    notes += bag.warnings
    label = path.stem if path.is_file() else path.name
    return [_finger_run(bag, path, label, finger, tuple(notes)) for finger in requested or present]


def _finger_run(
    bag: Bag, path: Path, label: str, finger: str, bag_notes: tuple[str, ...]
) -> TimeSeriesRun:
    notes = list(bag_notes)
    encoder = bag[names.topic(finger, "encoder")]
    stamps, first = np.unique(_stamp_ns(encoder), return_index=True)
    if stamps.size < len(encoder):
        notes.append(
            f"{len(encoder) - stamps.size} encoder samples repeat a stamp: the first of each kept"
        )
    if stamps.size < 2:
        raise DiagnosisInputError(
            f"{path}: {stamps.size} encoder sample(s) of {finger}: too few to compare"
        )
    period_ns = int(np.median(np.diff(stamps)))
    duty = bag[names.topic(finger, "duty")]
    _check_duty(path, duty, stamps[0])
    drive, duty_notes = _applied_duty(duty, stamps, period_ns)
    steps, step_notes = _duty_steps(duty, encoder.log_time_ns[first] - stamps, stamps, period_ns)
    notes += duty_notes + step_notes
    position = encoder["position"][first]
    keep = np.isfinite(position)
    notes += non_finite_note(str(path), f"{encoder.topic} position", keep)
    outputs_extra, resolution = {}, {"position": float(np.median(encoder["resolution"]))}
    force_topic = names.topic(finger, "wire_force")
    if force_topic in bag:
        force, at_force, force_notes = _force_on_encoder(path, bag[force_topic], stamps)
        notes += force_notes
        finite = np.isfinite(force) | ~at_force
        notes += non_finite_note(str(path), f"{force_topic} force", finite)
        keep &= at_force & finite
        outputs_extra["wire_force"] = force[keep]
        resolution["wire_force"] = _force_step(force[keep])
    else:
        notes.append(f"no {force_topic} messages: the run has no wire force")
    if steps is None and not keep.all():
        steps = stamps, drive  # a dropped sample's interval keeps its own duty
    stamps, position = stamps[keep], position[keep]
    time = (stamps - stamps[0]) * 1e-9
    source = f"{path}:{finger}"
    require_span(source, time, "driven")
    return TimeSeriesRun(
        name=f"{label}:{finger}",
        source=source,
        kind="driven",
        time=time,
        drive="duty",
        drive_values=drive[keep],
        outputs={"position": position - position[0], **outputs_extra},
        resolution=resolution,
        setpoints=_setpoints(bag, finger, encoder, stamps[0]),
        notes=tuple(notes),
        drive_steps=None if steps is None else ((steps[0] - stamps[0]) * 1e-9, steps[1]),
    )


def _check_duty(path: Path, duty: TopicData, t0_ns: int) -> None:
    """Every duty command a number within 0-100 %, or DiagnosisInputError naming the first
    that is not (its topic, message number and the sample it answers)."""
    values = duty["duty_percent"]
    bad = np.flatnonzero(~((values >= 0.0) & (values <= 100.0)))  # NaN fails both
    if bad.size:
        k = int(bad[0])
        at = (_stamp_ns(duty, "measurement_stamp")[k] - t0_ns) * 1e-9
        raise DiagnosisInputError(
            f"{path}: {duty.topic} message {k + 1} of {values.size} (answering the encoder "
            f"sample at {at:.3f} s) has duty_percent = {float(values[k])!r}: a duty is a number "
            f"within 0-100 %" + (f"; {bad.size - 1} more such messages" if bad.size > 1 else "")
        )


def _duty_steps(
    duty: TopicData, encoder_lag_ns: np.ndarray, stamps: np.ndarray, period_ns: int
) -> tuple[tuple[np.ndarray, np.ndarray] | None, list[str]]:
    """The duty as the unit applies it, as a step function (stamp-clock ns, duty %).

    A command that reaches the unit before the sample after the one it answers applies from
    that sample; a later one from its arrival; no command for three periods is 0 (the
    watchdog; unit_driver). The bag does not hold the unit's arrival times: the recorder's log
    time, moved onto the stamp clock by the encoder samples' median log-minus-stamp delay,
    stands in for them. When log times do not follow the stamps (a graph on /clock at another
    rate), there is no arrival time to use: None, and the commands apply at their samples.
    """
    low, lag, high = np.percentile(encoder_lag_ns, [5, 50, 95])
    if high - low > 5 * period_ns:
        return None, [
            "log times do not follow the stamps (a graph on /clock?): duty commands applied "
            "from the samples they answer"
        ]
    arrival = duty.log_time_ns - int(lag)
    answered = _stamp_ns(duty, "measurement_stamp")
    order = np.argsort(arrival, kind="stable")
    arrival, answered, values = arrival[order], answered[order], duty["duty_percent"][order]
    index = np.clip(np.searchsorted(stamps, answered - period_ns // 2), 0, stamps.size - 1)
    matched = np.abs(stamps[index] - answered) <= period_ns // 2
    following = np.where(
        index + 1 < stamps.size,
        stamps[np.minimum(index + 1, stamps.size - 1)],
        np.iinfo(np.int64).max,
    )
    on_time = matched & (arrival < following)
    start = np.where(on_time, stamps[index], arrival)
    timeout = WATCHDOG_PERIODS * period_ns
    step_times, step_levels = [], []
    for k in range(start.size):
        step_times.append(start[k])
        step_levels.append(values[k])
        if k + 1 < start.size and start[k + 1] > start[k] + timeout:
            step_times.append(start[k] + timeout)
            step_levels.append(0.0)
    times, levels = np.array(step_times, dtype=np.int64), np.array(step_levels, dtype=float)
    sort = np.argsort(times, kind="stable")
    late = int(np.count_nonzero(matched & ~on_time))
    notes = (
        [
            f"{late} duty commands reached the unit after the next sample (recorder log times): "
            f"applied from their arrival, as the unit applies them"
        ]
        if late
        else []
    )
    return (times[sort], levels[sort]), notes


def _applied_duty(
    duty: TopicData, stamps: np.ndarray, period_ns: int
) -> tuple[np.ndarray, list[str]]:
    """The duty the unit applies over the interval starting at each encoder sample."""
    answered = _stamp_ns(duty, "measurement_stamp")
    order = np.argsort(answered, kind="stable")  # two answers to one sample: the later one wins
    answered, values = answered[order], duty["duty_percent"][order]
    # a command answers its sample exactly; half a period covers a clock that rounds stamps
    latest = np.searchsorted(answered, stamps + period_ns // 2, side="right") - 1
    drive = np.where(latest >= 0, values[np.maximum(latest, 0)], 0.0)
    # the watchdog trips when the last command is more than three periods old: the whole
    # interval after a sample three periods (or more) after it is at 0
    silent = (latest >= 0) & (
        stamps - answered[np.maximum(latest, 0)] > (WATCHDOG_PERIODS - 0.5) * period_ns
    )
    drive[silent] = 0.0
    notes = []
    nearest = np.clip(np.searchsorted(stamps, answered), 1, stamps.size - 1)
    offset = np.minimum(np.abs(answered - stamps[nearest - 1]), np.abs(answered - stamps[nearest]))
    near, far = (offset > 0) & (offset <= period_ns // 2), offset > period_ns // 2
    if np.any(near):
        notes.append(
            f"{int(np.count_nonzero(near))} duty commands answer no encoder stamp exactly: "
            f"applied from the nearest sample within half a period"
        )
    if np.any(far):
        notes.append(
            f"{int(np.count_nonzero(far))} duty commands answer no encoder sample of the bag "
            f"(before the first, after the last or in a gap)"
        )
    if np.any(silent):
        notes.append(
            f"watchdog: {int(np.count_nonzero(silent))} samples more than {WATCHDOG_PERIODS} "
            f"periods after the last duty command, at 0 %"
        )
    return drive, notes


def _force_on_encoder(
    path: Path, force: TopicData, stamps: np.ndarray
) -> tuple[np.ndarray, np.ndarray, list[str]]:
    """Wire force at each encoder sample (NaN-free where ``keep``) and the samples kept."""
    force_stamps, first = np.unique(_stamp_ns(force), return_index=True)
    values = np.zeros(stamps.size)
    _, at_encoder, at_force = np.intersect1d(
        stamps, force_stamps, assume_unique=True, return_indices=True
    )
    values[at_encoder] = force["force"][first][at_force]
    keep = np.zeros(stamps.size, dtype=bool)
    keep[at_encoder] = True
    notes = []
    if not keep.all():
        notes.append(
            f"{stamps.size - at_encoder.size} encoder samples without a wire force at their stamp "
            f"dropped"
        )
    if force_stamps.size > at_force.size:
        notes.append(
            f"{force_stamps.size - at_force.size} wire forces without an encoder sample at their "
            f"stamp dropped"
        )
    if not keep.any():
        raise DiagnosisInputError(
            f"{path}: {force.topic} and the encoder share no stamp: the wire force "
            f"cannot be put on the encoder's time base"
        )
    return values, keep, notes


def _force_step(force: np.ndarray) -> float:
    """The smallest nonzero step between force readings (the sensor's quantisation)."""
    steps = np.diff(np.unique(force))
    steps = steps[steps > 1e-12]
    return round(float(steps.min()), 9) if steps.size else DEFAULT_FORCE_RESOLUTION_N


def _setpoints(
    bag: Bag, finger: str, encoder: TopicData, t0_ns: int
) -> tuple[tuple[float, str, float], ...]:
    """(time on the run's base, mode, value): the header stamp, else the log time moved onto
    the unit's clock by the median lag between the encoder's stamps and its log times."""
    topic = names.topic(finger, "setpoint")
    if topic not in bag:
        return ()
    setpoint = bag[topic]
    stamped = _stamp_ns(setpoint)
    lag = int(np.median(encoder.log_time_ns - _stamp_ns(encoder)))
    at = np.where(stamped > 0, stamped, setpoint.log_time_ns - lag)
    return tuple(
        (float((t - t0_ns) * 1e-9), str(mode), float(value))
        for t, mode, value in zip(at, setpoint["mode"], setpoint["value"])
    )
