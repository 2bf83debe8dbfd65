"""``hems step``: one recorded tendon-position step on a graph it starts (the chapter 5 step run).

Starts the graph (one finger by default) with an optional physics set and pulley ratio,
records it, enables it, holds position 0 for ``--before-s``, steps to ``--step-mm`` for
``--step-s``, returns to 0 for ``--after-s`` (``--cycles`` times), disables, and prints the
last step's figures from the bag (tendon position from the encoder, times from the message
stamps).
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np

from hems_ros.cli.numbers import non_negative, positive, positive_int
from hems_ros.cli.up import add_graph_arguments, bag_folder, graph_options, stop_recorder, wait_until_recording
from hems_ros.graph import names, transmission
from hems_ros.physics.params import load_params

# A setpoint the controller status does not show within this long ends the run: the figures
# would otherwise describe a step the controller never took.
SETPOINT_CONFIRM_S = 2.0


def register(subparsers) -> None:
    parser = subparsers.add_parser(
        "step", help="one recorded tendon-position step on a graph it starts (chapter 5 step run)",
        description="Start the graph (default: index finger only), record it, enable it, step the tendon "
                    "position 0 -> STEP -> 0 and print RMSE, overshoot and steady-state error from the bag. "
                    "Chapter 5 rig: --physics-config ch5_straight_40n --pulley-ratio 1.")
    add_graph_arguments(parser)
    parser.set_defaults(func=run, fingers="index")
    parser.add_argument("--physics-config", default=None,
                        help="physics parameter set of the actuation units (default: the params file's)")
    parser.add_argument("--pulley-ratio", type=positive, default=transmission.PULLEY_RATIO,
                        help="tendon / wire ratio the controllers convert with; must match the physics set "
                             f"(default {transmission.PULLEY_RATIO:g}; 1 for ch5_straight_40n)")
    parser.add_argument("--step-mm", type=positive, default=20.0, help="step height, tendon mm (default 20)")
    parser.add_argument("--before-s", type=non_negative, default=2.0, help="seconds at 0 before the step")
    parser.add_argument("--step-s", type=positive, default=5.0, help="seconds at the step height")
    parser.add_argument("--after-s", type=non_negative, default=8.0, help="seconds at 0 after the step (cooling)")
    parser.add_argument("--cycles", type=positive_int, default=1,
                        help="record this many steps, each with its time at 0 before and after (a run for "
                             "hems diagnose, which needs three); the printed figures are the last step's "
                             "(default 1)")
    parser.add_argument("--record", type=Path, default=True, metavar="DIR",
                        help="bag folder (default bags/step_<date>_<time>)")
    parser.add_argument("--ready-timeout", type=positive, default=60.0, help="seconds to wait for the graph")


def step_span(values: np.ndarray) -> tuple[int, int]:
    """Indices of the setpoint messages that start and end the last step in ``values``: the
    first of the last run of equal non-zero values (a setpoint sent again repeats it) and the
    next message after that run. ValueError when the messages hold no such step."""
    values = np.asarray(values, dtype=float)
    raised = np.flatnonzero(values != 0.0)
    if raised.size == 0 or raised[-1] == values.size - 1:
        raise ValueError(f"{values.size} setpoint messages ({', '.join(f'{v:g}' for v in values)} m) "
                         "hold no step up and back to 0")
    last = raised[-1]
    first = last
    while first > 0 and values[first - 1] == values[last]:
        first -= 1
    return int(first), int(last + 1)


def _taken_at(bag, finger: str, value: float, sent_s: float) -> float:
    """When the finger's controller took the setpoint ``value`` sent at ``sent_s``: the stamp
    of its first accepted /commands record of that value from then on (the graph's clock, so on
    sim time the sample it acted from), or ``sent_s`` for a bag without the records."""
    topic = names.topic(finger, "commands")
    records = bag[topic] if topic in bag else None
    if records is None or len(records) == 0:
        return sent_s
    stamp = records.stamp
    taken = np.flatnonzero(records["accepted"] & (records["value"] == value) & (stamp >= sent_s - 1e-3))
    return float(stamp[taken[0]]) if taken.size else sent_s


def step_figures(bag_path: Path, finger: str, ratio: float, settle_s: float = 1.0,
                 step_s: float | None = None) -> dict[str, float]:
    """RMSE (whole step), overshoot (first peak, :func:`hems_ros.control.metrics.overshoot`) and
    steady-state error (mean over its last ``settle_s``), tendon mm.

    The step runs from the moment the controller took its setpoint (:func:`_taken_at`) for
    ``step_s`` (default: until the controller took the next one): a tool that sends the setpoints
    late, or a clock that ran on meanwhile, then changes neither the start nor the length the
    figures cover. ValueError when the bag does not hold the step's setpoints (:func:`step_span`)."""
    from hems_ros.bag import load_bag
    from hems_ros.control import metrics

    topics = [names.topic(finger, s) for s in ("encoder", "setpoint", "commands")]
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
    start = _taken_at(bag, finger, values[rise], setpoint.stamp[rise])
    end = _taken_at(bag, finger, values[fall], setpoint.stamp[fall])
    if step_s is not None:
        end = min(end, start + step_s)
    height = 1e3 * values[rise]
    during = (t >= start) & (t < end)
    settled = (t >= end - settle_s) & (t < end)
    return {"rmse_mm": metrics.rmse(y[during], np.full(int(during.sum()), height)),
            "overshoot_mm": metrics.overshoot(y[during], metrics.StepSegment(0, int(during.sum()), 0.0, height)),
            "steady_state_error_mm": float(np.mean(height - y[settled]))}


def run(args: argparse.Namespace) -> int:
    from hems_ros.bag.recording import RecorderProcess
    from hems_ros.cli.up import print_bag

    try:
        options = graph_options(args)
        if args.physics_config:
            load_params(args.physics_config)   # a bad name stops here, not in the unit after start-up
        record = bag_folder(args.record, "step")
    except ValueError as error:
        print(f"step: {error}", file=sys.stderr)
        return 2
    overrides = ["-p", f"pulley_ratio:={args.pulley_ratio!r}"]
    if args.physics_config:
        overrides += ["-p", f"physics_config:={args.physics_config}"]
    options.extra_ros_args = tuple(overrides)
    from hems_ros.cli.graph_client import GraphClient
    from hems_ros.launcher import Graph

    graph = Graph(options)
    graph.start()
    recorder = RecorderProcess(record)
    finished = None
    try:
        with GraphClient("hems_step", sim_time=options.sim_time) as client:
            wait_until_recording(client, recorder, options.fingers, time.monotonic() + args.ready_timeout)
            ok, message = client.enable_when_ready(args.ready_timeout)
            if not ok:
                print(f"step: could not enable the graph: {graph.with_exits(message)}", file=sys.stderr)
                return 1
            cycle = ((0.0, args.before_s), (args.step_mm * 1e-3, args.step_s), (0.0, args.after_s))
            for value, seconds in cycle * args.cycles:
                print(f"step: position {value * 1e3:g} mm for {seconds:g} s", flush=True)
                for finger in options.fingers:
                    result = client.send_setpoint(finger, "position", value, confirm_s=SETPOINT_CONFIRM_S)
                    if not result:
                        print(f"step: {finger}: position setpoint {value:g} m: {result.message}", file=sys.stderr)
                        return 1
                client.spin_graph_time(seconds)
            state = client.snapshot(options.fingers, 0.3).supervisor
            client.call("disable")
            client.spin_for(0.3)
        finished = recorder.stop()
    except (TimeoutError, RuntimeError) as error:
        print(f"step: {error}", file=sys.stderr)
        return 1
    finally:
        if finished is None:
            stop_recorder("step", recorder)
        graph.stop()
    print_bag("step", finished)
    for finger in options.fingers:
        try:
            figures = step_figures(record, finger, args.pulley_ratio, step_s=args.step_s)
        except ValueError as error:
            print(f"step: {error}", file=sys.stderr)
            return 1
        print(f"step: {finger}: " + ", ".join(f"{k} {v:.3f}" for k, v in figures.items()))
    if state is None or state.state_name != "ENABLED":
        print(f"step: not a valid run: supervisor {state.state_name if state else 'silent'}"
              f"{': ' + '; '.join(state.faults) if state and state.faults else ''}", file=sys.stderr)
        return 1
    return 0
