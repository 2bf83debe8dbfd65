"""``hems grasp``: the scripted grasp on a running graph, with a summary and a plot."""

from __future__ import annotations

import argparse
import contextlib
import subprocess
import sys
from pathlib import Path

from hems_ros.cli.numbers import add_namespace_argument, finite, non_negative, positive
from hems_ros.cli.waiting import WaitingLine
from hems_ros.graph import names
from hems_ros.graph.grasp import (
    FingerTrace,
    GraspPlan,
    PhaseTracker,
    format_summary,
    plot,
    summarize,
    tracking_report,
)
from hems_ros.graph.setpoints import SetpointLimits, validate


def add_grasp_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument(
        "--force", type=finite, default=10.0, help="tendon force to hold, N (default 10)"
    )
    parser.add_argument(
        "--approach-mm", type=finite, default=20.0, help="tendon approach position, mm (default 20)"
    )
    parser.add_argument("--approach-s", type=non_negative, default=5.0, help="approach duration, s")
    parser.add_argument("--hold-s", type=non_negative, default=6.0, help="force hold duration, s")
    parser.add_argument("--release-s", type=non_negative, default=4.0, help="release duration, s")
    parser.add_argument(
        "--plot", type=Path, default=Path("results/grasp.png"), help="PNG plot path"
    )


def register(subparsers) -> None:
    parser = subparsers.add_parser(
        "grasp",
        help="scripted grasp (all six fingers, or --fingers): position approach, force "
        "hold, release",
        description="On a running graph (hems up), enabled (hems enable) or enabled by this tool "
        "after it has joined (--enable): every finger approaches a tendon position, holds a tendon "
        "force, then releases; prints a per-finger summary (tracking error, peak force, energy) "
        "and writes a PNG plot.",
    )
    add_grasp_arguments(parser)
    parser.add_argument(
        "--enable",
        action="store_true",
        help="enable the graph once this tool has joined it, and disable it after the grasp: "
        "a tool joining an ENABLED separate-process graph can hold its streams up past "
        "the supervisor's limits on a small host (README, Safety)",
    )
    parser.add_argument(
        "--enable-timeout",
        type=positive,
        default=30.0,
        help="with --enable: seconds to wait for the supervisor to accept enable (default 30)",
    )
    parser.add_argument(
        "--fingers",
        default="all",
        help="comma-separated fingers to grasp with, as the graph was brought up with "
        "(hems up --fingers; default all six)",
    )
    parser.add_argument(
        "--sim-time",
        action="store_true",
        help="the graph runs on /clock (hems up --sim-time): phase durations in simulated "
        "seconds, setpoints stamped with the graph's time",
    )
    add_namespace_argument(parser)
    parser.set_defaults(func=run)


def plan_from(args: argparse.Namespace) -> GraspPlan:
    """The grasp the options ask for, checked before anything runs (the plot's folder too)."""
    args.plot.parent.mkdir(parents=True, exist_ok=True)
    limits = SetpointLimits()
    validate("force", args.force, limits)
    validate("position", args.approach_mm * 1e-3, limits)
    return GraspPlan(
        force_n=args.force,
        approach_m=args.approach_mm * 1e-3,
        approach_s=args.approach_s,
        hold_s=args.hold_s,
        release_s=args.release_s,
    )


class GraspListener:
    """The subscriptions a grasp run reads (joint states, supervisor status, each finger's
    state and controller status), collecting from :meth:`start` on.

    Created before the graph is enabled, so that every process has matched these readers
    before anything heats: made right after the enable, while sixteen processes matched
    fourteen new readers on two cores and every unit began to heat, a stream stalled for
    50-100 ms about 0.8 s after ENABLED and the supervisor latched FAULT in two of five
    demos; made first, in none of six.
    """

    def __init__(self, client, fingers=names.FINGERS) -> None:
        from hems_msgs.msg import ActuatorState, ControllerStatus, SupervisorStatus
        from sensor_msgs.msg import JointState

        from hems_ros.ros import qos
        from hems_ros.ros.clock_time import from_msg

        self.seconds = from_msg
        self.node = client.node
        self.collecting = False
        self.traces = {f: FingerTrace.empty() for f in fingers}
        self.phases = {f: PhaseTracker() for f in fingers}
        self.statuses: list = []
        self.subs = [
            self.node.create_subscription(
                JointState, names.joint_states_topic(client.namespace), self._on_joints, qos.SENSOR
            ),
            self.node.create_subscription(
                SupervisorStatus,
                names.supervisor_status_topic(client.namespace),
                self._on_supervisor,
                qos.STATUS,
            ),
        ]
        for finger in fingers:
            self.subs.append(
                self.node.create_subscription(
                    ActuatorState,
                    names.sim_topic(finger, "state", client.namespace),
                    lambda m, f=finger: self._on_state(f, m),
                    qos.SENSOR,
                )
            )
            self.subs.append(
                self.node.create_subscription(
                    ControllerStatus,
                    names.topic(finger, "controller_status", client.namespace),
                    lambda m, f=finger: self._on_status(f, m),
                    qos.CONTROLLER_STATUS,
                )
            )

    def start(self) -> None:
        self.collecting = True

    def close(self) -> None:
        for sub in self.subs:
            self.node.destroy_subscription(sub)
        self.subs = []

    def _on_joints(self, message) -> None:
        if not self.collecting:
            return
        t = self.seconds(message.header.stamp)
        for name, x, f in zip(message.name, message.position, message.effort):
            if name in self.traces:
                self.traces[name].t.append(t)
                self.traces[name].position_m.append(x)
                self.traces[name].force_n.append(f)

    def _on_supervisor(self, message) -> None:
        if self.collecting:
            self.statuses.append(message)

    def _on_state(self, finger: str, message) -> None:
        trace = self.traces[finger]
        if not self.collecting:
            # the latest one before the grasp: the energy is read between samples that bracket it
            del trace.energy_t[:], trace.energy_j[:]
        trace.energy_t.append(self.seconds(message.header.stamp))
        trace.energy_j.append(message.electrical_energy)

    def _on_status(self, finger: str, message) -> None:
        if not self.collecting:
            return
        self.traces[finger].duty_t.append(self.seconds(message.header.stamp))
        self.traces[finger].duty_percent.append(message.duty_percent)
        self.phases[finger].feed(
            message.mode,
            message.setpoint,
            message.active,
            self.seconds(message.encoder_stamp),
            self.seconds(message.force_stamp),
        )


def require_controllers(client, fingers) -> None:
    """RuntimeError naming the fingers whose controller is not running, before any setpoint
    is sent: found only when its turn came, a missing controller would stop the grasp after
    one discovery wait per finger, while the fingers before it were already heating."""
    missing = client.fingers_without_readers(fingers)
    if missing:
        raise RuntimeError(
            f"no finger_controller for {', '.join(missing)} (a graph brought up with "
            "hems up --fingers needs the same --fingers here)"
        )


# the state messages come every 50 ms, a phase starts up to a control period after its setpoint
COLLECT_AFTER_S = 0.2


def run_grasp(
    client, plan: GraspPlan, fingers=names.FINGERS, listener: GraspListener | None = None
):
    """Drive the phases on ``fingers``; return (traces, phase starts per finger, supervisor
    statuses seen). Without a ``listener`` made beforehand, one is made here."""
    require_controllers(client, fingers)
    if listener is None:
        listener = GraspListener(client, fingers)
        client.spin_for(0.5)
    listener.start()
    try:
        for phase, mode, value, duration in plan.phases():
            print(
                f"grasp: {phase}: {mode} {value:g} {'m' if mode == 'position' else 'N'} for "
                f"{duration:g} s",
                flush=True,
            )
            missing = [f for f in fingers if not client.send_setpoint(f, mode, value)]
            if missing:
                raise RuntimeError(f"no finger_controller for {', '.join(missing)}")
            client.spin_graph_time(duration)
        # every stream's first sample past the last phase's end (which the graph's stamps set)
        client.spin_graph_time(COLLECT_AFTER_S)
    finally:
        listener.close()
    return (
        listener.traces,
        {f: tracker.starts for f, tracker in listener.phases.items()},
        listener.statuses,
    )


class EnableRefused(RuntimeError):
    """The supervisor would not enable the graph; the message is its answer."""


def enabled_grasp(client, plan: GraspPlan, fingers, enable_timeout: float, who: str):
    """Make the grasp's readers, enable the graph, run the grasp and disable it again; returns
    what :func:`run_grasp` returns.

    The readers come first so that every process has matched them before anything heats
    (:class:`GraspListener`). The disable follows a failed grasp too, since the heating this
    call started should end with it. After SIGINT or SIGTERM, which take this process's ROS
    context (rclpy's handler shuts it down), there is nothing left to call it with: the
    caller decides (:func:`disable_from_new_process`, or the demo stops the whole graph).
    Raises :class:`EnableRefused` when the supervisor does not take the enable.
    """
    from rclpy.executors import ExternalShutdownException

    listener = GraspListener(client, fingers)
    require_controllers(client, fingers)
    line = WaitingLine(who)
    ok, message = client.enable_when_ready(enable_timeout, progress=line)
    line.end()
    if not ok:
        raise EnableRefused(message)
    print(f"{who}: {message}", flush=True)
    try:
        result = run_grasp(client, plan, fingers, listener)
    except BaseException:
        # rclpy's handler shuts the context down on its own thread: a Ctrl-C can reach this
        # before or during the call, which then fails; the signal is what goes on
        with contextlib.suppress(ExternalShutdownException):
            _disable(client, who)
        raise
    _disable(client, who)
    return result


def _disable(client, who: str) -> None:
    ok, message = client.call("disable")
    print(f"{who}: {message}", file=sys.stdout if ok else sys.stderr, flush=True)
    client.spin_for(0.3)  # the DISABLED status and the cooling start reach a recorder


def disable_from_new_process() -> tuple[bool, str]:
    """`hems disable` in a process of its own, for a process whose ROS context a signal has
    shut down (a default context cannot be initialised again): otherwise an interrupted
    `hems grasp --enable` would leave the graph ENABLED, heating to its last setpoint."""
    try:
        done = subprocess.run(
            [sys.executable, "-m", "hems_ros.cli.main", "disable"],
            capture_output=True,
            text=True,
            timeout=30,
        )
    except subprocess.TimeoutExpired:
        return False, "hems disable did not finish within 30 s: run hems disable"
    answer = (done.stdout + done.stderr).strip().removeprefix("disable: ")
    return done.returncode == 0, answer or f"hems disable exited with {done.returncode}"


def fault_report(statuses) -> str | None:
    """Why the run is invalid (the supervisor left ENABLED), or None."""
    bad = [s for s in statuses if s.state_name != "ENABLED"]
    if not statuses:
        return "no supervisor status received"
    if bad:
        return f"supervisor {bad[0].state_name}: {'; '.join(bad[0].faults) or 'no fault text'}"
    return None


def report(traces, plan: GraspPlan, phase_starts: dict[str, list[float]], plot_path: Path) -> list:
    complete = [f for f in traces if len(phase_starts[f]) == len(plan.phases())]
    for finger in traces:
        if finger not in complete:
            print(
                f"grasp: {finger}: its controller never ran every phase (inactive?): no summary",
                file=sys.stderr,
            )
    rows = [summarize(f, traces[f], plan, phase_starts[f]) for f in complete]
    print(format_summary(rows, plan))
    if not complete:
        return rows
    plot(traces, plan, min(phase_starts[f][0] for f in complete), plot_path)
    print(f"grasp: plot written to {plot_path}")
    return rows


def run(args: argparse.Namespace) -> int:
    try:
        plan = plan_from(args)
        fingers = names.parse_fingers(args.fingers)
    except ValueError as error:
        print(f"grasp: {error}", file=sys.stderr)
        return 2
    from rclpy.executors import ExternalShutdownException

    from hems_ros.client.graph_client import GraphClient

    with GraphClient("hems_grasp", sim_time=args.sim_time, namespace=args.namespace) as client:
        try:
            if args.enable:
                traces, phase_starts, statuses = enabled_grasp(
                    client, plan, fingers, args.enable_timeout, "grasp"
                )
            else:
                traces, phase_starts, statuses = run_grasp(client, plan, fingers)
        except EnableRefused as error:
            print(f"grasp: could not enable the graph: {error}", file=sys.stderr)
            return 1
        except RuntimeError as error:
            print(f"grasp: {error}", file=sys.stderr)
            return 1
        except (KeyboardInterrupt, ExternalShutdownException):
            if args.enable:
                ok, message = disable_from_new_process()
                print(
                    f"grasp: stopped mid-grasp: {message}",
                    file=sys.stdout if ok else sys.stderr,
                    flush=True,
                )
            else:
                print(
                    "grasp: stopped mid-grasp; the fingers keep their last setpoint "
                    "(hems setpoint all 0 --unit mm releases them, hems disable stops all heating)",
                    file=sys.stderr,
                )
            raise
    rows = report(traces, plan, phase_starts, args.plot)
    problem = fault_report(statuses) or tracking_report(rows, plan, fingers)
    if problem:
        print(f"grasp: not a valid run: {problem}", file=sys.stderr)
        return 1
    return 0
