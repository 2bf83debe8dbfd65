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
from pathlib import Path
from typing import TYPE_CHECKING

from hems_ros.cli.numbers import non_negative, positive, positive_int
from hems_ros.cli.up import add_graph_arguments, bag_folder, graph_options, print_bag
from hems_ros.client.step_figures import step_figures
from hems_ros.graph import transmission
from hems_ros.physics.params import load_params

if TYPE_CHECKING:
    from hems_ros.client.recorded_run import RecordedGraph

# A setpoint the controller status does not show within this long ends the run: the figures
# would otherwise describe a step the controller never took.
SETPOINT_CONFIRM_S = 2.0


def register(subparsers) -> None:
    parser = subparsers.add_parser(
        "step",
        help="one recorded tendon-position step on a graph it starts (chapter 5 step run)",
        description="Start the graph (default: index finger only), record it, enable it, step the "
        "tendon position 0 -> STEP -> 0 and print RMSE, overshoot and steady-state error from the "
        "bag. Chapter 5 rig: --physics-config ch5_straight_40n --pulley-ratio 1.",
    )
    add_graph_arguments(parser)
    parser.set_defaults(func=run, fingers="index")
    parser.add_argument(
        "--physics-config",
        default=None,
        help="physics parameter set of the actuation units (default: the params file's)",
    )
    parser.add_argument(
        "--pulley-ratio",
        type=positive,
        default=transmission.PULLEY_RATIO,
        help="tendon / wire ratio the controllers convert with; must match the physics set "
        f"(default {transmission.PULLEY_RATIO:g}; 1 for ch5_straight_40n)",
    )
    parser.add_argument(
        "--step-mm", type=positive, default=20.0, help="step height, tendon mm (default 20)"
    )
    parser.add_argument(
        "--before-s", type=non_negative, default=2.0, help="seconds at 0 before the step"
    )
    parser.add_argument("--step-s", type=positive, default=5.0, help="seconds at the step height")
    parser.add_argument(
        "--after-s", type=non_negative, default=8.0, help="seconds at 0 after the step (cooling)"
    )
    parser.add_argument(
        "--cycles",
        type=positive_int,
        default=1,
        help="record this many steps, each with its time at 0 before and after (a run for "
        "hems diagnose, which needs three); the printed figures are the last step's "
        "(default 1)",
    )
    parser.add_argument(
        "--record",
        type=Path,
        default=True,
        metavar="DIR",
        help="bag folder (default bags/step_<date>_<time>)",
    )
    parser.add_argument(
        "--ready-timeout", type=positive, default=60.0, help="seconds to wait for the graph"
    )


def run(args: argparse.Namespace) -> int:
    try:
        options = graph_options(args)
        if args.physics_config:
            load_params(
                args.physics_config
            )  # a bad name stops here, not in the unit after start-up
        record = bag_folder(args.record, "step")
    except ValueError as error:
        print(f"step: {error}", file=sys.stderr)
        return 2
    overrides = ["-p", f"pulley_ratio:={args.pulley_ratio!r}"]
    if args.physics_config:
        overrides += ["-p", f"physics_config:={args.physics_config}"]
    options.extra_ros_args = tuple(overrides)
    from hems_ros.client.recorded_run import recorded_graph

    try:
        with recorded_graph(options, record, "hems_step", args.ready_timeout) as graph_run:
            ran, state = _steps(graph_run, options.fingers, args)
            if not ran:
                return 1
            finished = graph_run.recorder.stop()
    except (TimeoutError, RuntimeError) as error:
        print(f"step: {error}", file=sys.stderr)
        return 1
    print_bag("step", finished)
    for finger in options.fingers:
        try:
            figures = step_figures(
                record, finger, args.pulley_ratio, step_s=args.step_s, namespace=options.namespace
            )
        except ValueError as error:
            print(f"step: {error}", file=sys.stderr)
            return 1
        print(f"step: {finger}: " + ", ".join(f"{k} {v:.3f}" for k, v in figures.items()))
    if state is None or state.state_name != "ENABLED":
        print(
            f"step: not a valid run: supervisor {state.state_name if state else 'silent'}"
            f"{': ' + '; '.join(state.faults) if state and state.faults else ''}",
            file=sys.stderr,
        )
        return 1
    return 0


def _steps(graph_run: RecordedGraph, fingers, args: argparse.Namespace):
    """Enable the graph and run the step cycles on every finger: (True, the supervisor's status
    at the end, None if silent), or (False, None) with why printed when the graph could not be
    enabled or a setpoint was not taken."""
    client = graph_run.client
    ok, message = client.enable_when_ready(args.ready_timeout)
    if not ok:
        print(
            f"step: could not enable the graph: {graph_run.graph.with_exits(message)}",
            file=sys.stderr,
        )
        return False, None
    cycle = ((0.0, args.before_s), (args.step_mm * 1e-3, args.step_s), (0.0, args.after_s))
    for value, seconds in cycle * args.cycles:
        print(f"step: position {value * 1e3:g} mm for {seconds:g} s", flush=True)
        in_force = []
        for finger in fingers:
            result = client.send_setpoint(finger, "position", value, confirm_s=SETPOINT_CONFIRM_S)
            if not result:
                print(
                    f"step: {finger}: position setpoint {value:g} m: {result.message}",
                    file=sys.stderr,
                )
                return False, None
            in_force.append(result.in_force_s)
        # each phase lasts its length from the sample its setpoint acted from
        known = [t for t in in_force if t is not None]
        since = max(known) if len(known) == len(in_force) else None
        client.spin_graph_time(seconds, since_s=since)
    state = client.snapshot(fingers, 0.3).supervisor
    client.call("disable")
    client.spin_for(0.3)
    return True, state
