"""Verbs that command a running graph: enable, disable, estop, reset, setpoint, status."""

from __future__ import annotations

import argparse
import json
import math
import sys

from hems_ros.cli.numbers import add_namespace_argument, positive
from hems_ros.cli.waiting import READY_TIMEOUT_S, WaitingLine
from hems_ros.client import DISCOVERY_S
from hems_ros.graph import names, transmission
from hems_ros.graph.setpoints import MODES, SetpointError, SetpointLimits, validate
from hems_ros.graph.supervisor_logic import (
    gap_report,
)

UNITS = {"mm": ("position", 1e-3), "m": ("position", 1.0), "N": ("force", 1.0)}


def register(subparsers) -> None:
    parser = subparsers.add_parser(
        "enable",
        help="allow heating: supervisor to ENABLED, once the graph is ready",
        description="Wait until the graph is ready (every finger's encoder, wire force, unit "
        "state and controller heartbeat present, and every unit getting its controller's "
        "commands; one progress line says what is missing), then switch the supervisor to "
        "ENABLED. Right after `hems up &` it waits for the graph to come up. Exit code 1 if "
        "the graph is not ready or the supervisor refuses within --timeout.",
    )
    parser.add_argument(
        "--timeout",
        type=positive,
        default=READY_TIMEOUT_S,
        help=f"seconds to wait for the graph and the supervisor (default {READY_TIMEOUT_S:g})",
    )
    add_namespace_argument(parser)
    parser.set_defaults(func=run_enable)
    for command, text in (
        ("disable", "stop heating: supervisor to DISABLED"),
        ("estop", "emergency stop: every duty to 0, latched until reset"),
        ("reset", "clear a latched FAULT or ESTOP (refused while a fault persists)"),
    ):
        parser = subparsers.add_parser(command, help=text, description=text + ".")
        parser.add_argument(
            "--timeout", type=positive, default=10.0, help="seconds to wait for the supervisor"
        )
        add_namespace_argument(parser)
        parser.set_defaults(func=lambda args, c=command: run_trigger(c, args))

    parser = subparsers.add_parser(
        "setpoint",
        help="send a finger setpoint (tendon side)",
        description="Publish hems_msgs/FingerSetpoint on <namespace>/<finger>/setpoint "
        "(/hems/index/setpoint). Values are tendon side: position in m (or mm with --unit mm), "
        "force in N. Checked here against the same limits the controller applies (tendon stroke "
        "0-54 mm, force 0-25 N). Then waits until the finger's controller status shows the "
        "setpoint, sending it again meanwhile (a controller that had not matched this new "
        "publisher yet drops the first one); exit code 1 if no controller took it or its status "
        "does not show it within --timeout, or if the supervisor is not ENABLED (nothing heats: "
        "its state and what to do are printed), 2 for a bad value.",
    )
    parser.add_argument(
        "finger", help="finger name, comma-separated names or 'all': " + ", ".join(names.FINGERS)
    )
    parser.add_argument("value", help="setpoint value in --unit")
    parser.add_argument(
        "--mode",
        choices=MODES,
        default=None,
        help="position or force (default: from --unit, position for m/mm, force for N)",
    )
    parser.add_argument(
        "--unit",
        choices=tuple(UNITS),
        default=None,
        help="unit of VALUE: mm, m (position) or N (force); default m or N by mode",
    )
    parser.add_argument(
        "--timeout",
        type=positive,
        default=DISCOVERY_S,
        help="seconds to wait for the controller to subscribe, for its status to show the "
        f"setpoint, and for the supervisor's status (default {DISCOVERY_S:g})",
    )
    add_namespace_argument(parser)
    parser.set_defaults(func=run_setpoint)

    parser = subparsers.add_parser(
        "status",
        help="one row per finger: mode, setpoint, position, force, duty, faults",
        description="Listen to the graph briefly and print one row per finger (tendon side: "
        "position in mm, force in N; duty in %) and the supervisor state.",
    )
    parser.add_argument(
        "--listen", type=positive, default=1.5, help="seconds to listen (default 1.5)"
    )
    parser.add_argument(
        "--json",
        action="store_true",
        help="print one JSON object instead of the table (SI units, named in the keys; the "
        "supervisor's stream-gap figures in ms; null where nothing was heard)",
    )
    add_namespace_argument(parser)
    parser.set_defaults(func=run_status)


def run_enable(args: argparse.Namespace) -> int:
    from hems_ros.client.graph_client import GraphClient

    line = WaitingLine("enable")
    with GraphClient(namespace=args.namespace) as client:
        ok, message = client.enable_when_ready(args.timeout, retry_s=0.5, progress=line)
    line.end()
    print(f"enable: {message}", file=sys.stdout if ok else sys.stderr)
    return 0 if ok else 1


def run_trigger(command: str, args: argparse.Namespace) -> int:
    from hems_ros.client.graph_client import GraphClient

    with GraphClient(namespace=args.namespace) as client:
        ok, message = client.call(command, args.timeout)
    print(f"{command}: {message}", file=sys.stdout if ok else sys.stderr)
    return 0 if ok else 1


def parse_setpoint(
    finger: str, value_text: str, mode: str | None, unit: str | None
) -> tuple[list[str], str, float]:
    """(fingers, mode, SI value) from the command line; ValueError with the reason."""
    fingers = list(names.parse_fingers(finger))
    if unit is not None:
        unit_mode, factor = UNITS[unit]
        if mode is not None and mode != unit_mode:
            raise ValueError(f"--unit {unit} is a {unit_mode} unit but --mode is {mode}")
        mode = unit_mode
    else:
        mode = mode or "position"
        factor = 1.0
    try:
        value = float(value_text) * factor
    except ValueError:
        raise ValueError(f"setpoint value {value_text!r} is not a number") from None
    if not math.isfinite(value):
        raise ValueError(f"setpoint value {value_text!r} is not finite")
    try:
        validate(mode, value, SetpointLimits())
    except SetpointError as error:
        raise ValueError(str(error)) from None
    return fingers, mode, value


def run_setpoint(args: argparse.Namespace) -> int:
    from hems_msgs.msg import SupervisorStatus

    try:
        fingers, mode, value = parse_setpoint(args.finger, args.value, args.mode, args.unit)
    except ValueError as error:
        print(f"setpoint rejected: {error}", file=sys.stderr)
        return 2
    from hems_ros.client.graph_client import GraphClient

    unit = "m" if mode == "position" else "N"
    waiting = WaitingLine("setpoint")
    with GraphClient(namespace=args.namespace) as client:
        client.watch_supervisor()
        # one wait for every controller: on a graph brought up with fewer fingers, "all" would
        # otherwise wait --timeout for each missing one in turn
        missing = client.fingers_without_readers(fingers, timeout=args.timeout, progress=waiting)
        waiting.end()
        results = {
            f: client.send_setpoint(
                f,
                mode,
                value,
                timeout=0.0 if f in missing else args.timeout,
                confirm_s=args.timeout,
            )
            for f in fingers
        }
        supervisor = client.supervisor_status(timeout=args.timeout)
    for finger, result in results.items():
        line = f"{finger}: {mode} setpoint {value:g} {unit}: {result.message}"
        print(line, file=sys.stdout if result else sys.stderr)
    heating = supervisor is not None and supervisor.state == SupervisorStatus.ENABLED
    if not heating:
        print(_not_heating(supervisor), file=sys.stderr)
    return 0 if all(results.values()) and heating else 1


def _not_heating(supervisor) -> str:
    """Why a setpoint in force moves nothing, and what to do."""
    from hems_msgs.msg import SupervisorStatus

    if supervisor is None:
        return (
            "no supervisor status: nothing heats without a supervisor in ENABLED (is the graph up?)"
        )
    faults = f" ({'; '.join(supervisor.faults)})" if supervisor.faults else ""
    hint = (
        "hems reset, then hems enable"
        if supervisor.state in (SupervisorStatus.FAULT, SupervisorStatus.ESTOP)
        else "hems enable"
    )
    return (
        f"the supervisor is {supervisor.state_name}{faults}: nothing heats until it is "
        f"ENABLED ({hint})"
    )


def format_status(snap) -> str:
    rows = [
        f"{'finger':<16} {'mode':<9} {'setpoint':>10} {'position mm':>12} {'force N':>8} "
        f"{'duty %':>7}  faults"
    ]
    for finger in names.FINGERS:
        c = snap.controllers.get(finger)
        s = snap.states.get(finger)
        f = snap.forces.get(finger)
        if c is None:
            rows.append(
                f"{finger:<16} {'-':<9} {'-':>10} {'-':>12} {'-':>8} {'-':>7}  no controller status"
            )
            continue
        unit = "mm" if c.mode == "position" else "N"
        setpoint = 1e3 * c.setpoint if c.mode == "position" else c.setpoint
        position = f"{1e3 * s.tendon_position:>12.2f}" if s is not None else f"{'-':>12}"
        force = f"{transmission.tendon_force(f.force):>8.2f}" if f is not None else f"{'-':>8}"
        faults = finger_faults(snap, finger)
        rows.append(
            f"{finger:<16} {c.mode:<9} {setpoint:>7.2f} {unit:<2} {position} {force} "
            f"{c.duty_percent:>7.1f}  {', '.join(faults) or '-'}"
        )
    sup = snap.supervisor
    rows.append(
        f"supervisor: {sup.state_name if sup else 'not running'}"
        + (f" ({'; '.join(sup.faults)})" if sup and sup.faults else "")
    )
    if snap.diagnostics:
        rows.append(gap_line(snap))
    return "\n".join(rows)


def finger_faults(snap, finger: str) -> list[str]:
    """What is wrong with ``finger`` in the snapshot, in words (empty: nothing)."""
    c, s = snap.controllers[finger], snap.states.get(finger)
    faults = [c.fault] if c.fault else []
    if s is not None and s.watchdog_tripped:
        faults.append("watchdog")
    if snap.supervisor is not None and snap.supervisor.state_name == "ENABLED":
        if s is not None and not s.heating_allowed:
            faults.append("unit has no heating permission")
        if not c.active:
            faults.append("controller inactive")
    if c.rejected_setpoints:
        faults.append(f"{c.rejected_setpoints} rejected ({c.last_rejection})")
    return faults


def status_document(snap) -> dict:
    """The snapshot for scripts (`hems status --json`): SI units, named in the keys."""
    fingers: dict[str, dict | None] = {}
    for finger in names.FINGERS:
        c, s, f = (snap.controllers.get(finger), snap.states.get(finger), snap.forces.get(finger))
        fingers[finger] = (
            None
            if c is None
            else {
                "mode": c.mode,
                "setpoint": finite(c.setpoint),
                "setpoint_unit": "m" if c.mode == "position" else "N",
                "tendon_position_m": None if s is None else finite(s.tendon_position),
                "tendon_force_n": None if f is None else finite(transmission.tendon_force(f.force)),
                "duty_percent": finite(c.duty_percent),
                "faults": finger_faults(snap, finger),
            }
        )
    sup = snap.supervisor
    return {
        "supervisor": {
            "state": sup.state_name if sup else None,
            "faults": list(sup.faults) if sup else [],
        },
        "fingers": fingers,
        "stream_gaps": gap_report(snap.diagnostics) if snap.diagnostics else None,
    }


def finite(value: float) -> float | None:
    """``value``, or None for NaN and infinities, which JSON cannot carry."""
    return value if math.isfinite(value) else None


def gap_line(snap) -> str:
    """The supervisor's count of stream gaps and its loss limit, and the longest time a unit or
    controller took to take ENABLED against its grace, from the supervisor's /diagnostics."""
    if not snap.diagnostics:
        return "stream gaps: no supervisor diagnostics received"
    report = gap_report(snap.diagnostics)

    def ms(key: str) -> str:
        return "?" if report[key] is None else f"{report[key]:g}"

    gaps = (
        f"{report['gaps']} gaps, longest {ms('longest_gap_ms')} ms ({report['longest_gap_stream']})"
        if report["gaps"]
        else f"no gap over {ms('gap_floor_ms')} ms"
    )
    line = f"stream gaps while ENABLED: {gaps}; a stream silent for {ms('loss_limit_ms')} ms faults"
    if report["quiets"]:
        line += f"; supervisor quiets: {report['quiets']}, longest {ms('longest_quiet_ms')} ms"
    if report["enable_taken_ms"] is not None:
        line += (
            f"; ENABLED taken within {ms('enable_taken_ms')} ms ({report['enable_taken_by']}), "
            f"a node that has not taken it for {ms('enable_grace_ms')} ms faults"
        )
    return line


def run_status(args: argparse.Namespace) -> int:
    from hems_ros.client.graph_client import GraphClient

    with GraphClient(namespace=args.namespace) as client:
        snap = client.snapshot(seconds=args.listen)
    if args.json:
        print(json.dumps(status_document(snap), allow_nan=False))
    else:
        print(format_status(snap))
    return 0 if snap.supervisor is not None else 1
