"""The figures of a recorded tendon-position step (what `hems step` prints), read back from its
bag: RMSE, overshoot and steady-state error, tendon mm."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from hems_ros.graph import names, transmission


def step_span(values: np.ndarray) -> tuple[int, int]:
    """Indices of the setpoint messages that start and end the last step in ``values``: the
    first of the last run of equal non-zero values (a setpoint sent again repeats it) and the
    next message after that run. ValueError when the messages hold no such step."""
    values = np.asarray(values, dtype=float)
    raised = np.flatnonzero(values != 0.0)
    if raised.size == 0 or raised[-1] == values.size - 1:
        raise ValueError(
            f"{values.size} setpoint messages ({', '.join(f'{v:g}' for v in values)} m) "
            "hold no step up and back to 0"
        )
    last = raised[-1]
    first = last
    while first > 0 and values[first - 1] == values[last]:
        first -= 1
    return int(first), int(last + 1)


def _taken_at(
    bag, finger: str, value: float, sent_s: float, namespace: str = names.NAMESPACE
) -> float:
    """When the finger's controller took the setpoint ``value`` sent at ``sent_s``: the stamp
    of its first accepted /commands record of that value from then on (the graph's clock, so on
    sim time the sample it acted from), or ``sent_s`` for a bag without the records."""
    topic = names.topic(finger, "commands", namespace)
    records = bag[topic] if topic in bag else None
    if records is None or len(records) == 0:
        return sent_s
    stamp = records.stamp
    taken = np.flatnonzero(
        records["accepted"] & (records["value"] == value) & (stamp >= sent_s - 1e-3)
    )
    return float(stamp[taken[0]]) if taken.size else sent_s


def step_figures(
    bag_path: Path,
    finger: str,
    ratio: float,
    settle_s: float = 1.0,
    step_s: float | None = None,
    namespace: str = names.NAMESPACE,
) -> dict[str, float]:
    """RMSE (whole step), overshoot (first peak, :func:`hems_ros.control.metrics.overshoot`) and
    steady-state error (mean over its last ``settle_s``), tendon mm.

    The step runs from the moment the controller took its setpoint (:func:`_taken_at`) for
    ``step_s`` (default: until the controller took the next one): a tool that sends the setpoints
    late, or a clock that ran on meanwhile, then changes neither the start nor the length the
    figures cover. ValueError when the bag does not hold the step's setpoints
    (:func:`step_span`)."""
    from hems_ros.bag import load_bag
    from hems_ros.control import metrics

    topics = [names.topic(finger, s, namespace) for s in ("encoder", "setpoint", "commands")]
    bag = load_bag(bag_path, topics=topics)
    if topics[0] not in bag or topics[1] not in bag:
        raise ValueError(f"{finger}: bag {bag_path} holds no {topics[0]} or {topics[1]}")
    encoder, setpoint = bag[topics[0]], bag[topics[1]]
    t, y = encoder.stamp, 1e3 * transmission.tendon_position(encoder["position"], ratio)
    try:
        rise, fall = step_span(setpoint["value"])
    except ValueError as error:
        raise ValueError(f"{finger}: bag {bag_path}: {error}") from None
    values = setpoint["value"]
    start = _taken_at(bag, finger, values[rise], setpoint.stamp[rise], namespace)
    end = _taken_at(bag, finger, values[fall], setpoint.stamp[fall], namespace)
    if step_s is not None:
        end = min(end, start + step_s)
    height = 1e3 * values[rise]
    during = (t >= start) & (t < end)
    settled = (t >= end - settle_s) & (t < end)
    return {
        "rmse_mm": metrics.rmse(y[during], np.full(int(during.sum()), height)),
        "overshoot_mm": metrics.overshoot(
            y[during], metrics.StepSegment(0, int(during.sum()), 0.0, height)
        ),
        "steady_state_error_mm": float(np.mean(height - y[settled])),
    }
