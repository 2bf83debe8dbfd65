"""Helpers of the graph bag tests: reference bags, node processes, the controller
replay, metrics."""

from __future__ import annotations

import dataclasses
import importlib
import math
import subprocess
import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from hems_ros.bag import iter_messages, load_bag
from hems_ros.graph import names, transmission
from hems_ros.graph.grasp import FingerTrace, GraspPlan, PhaseTracker, summarize
from hems_ros.launcher import GraphOptions, executable_path, ros_arguments
from hems_ros.processes import stop_process
from hems_ros.rosenv import child_environment

REPO = Path(__file__).resolve().parents[2]
BAGS = REPO / "bags"


@dataclass(frozen=True)
class Reference:
    path: Path
    finger: str
    pulley_ratio: float  # the controller's; the bag does not store node parameters


REFERENCES = {
    "demo_grasp_index": Reference(BAGS / "demo_grasp_index", "index", transmission.PULLEY_RATIO),
    "ch5_step_index": Reference(BAGS / "ch5_step_index", "index", 1.0),
}


def stamp_ns(data, prefix: str = "header.stamp") -> np.ndarray:
    return data[f"{prefix}.sec"].astype(np.int64) * 1_000_000_000 + data[f"{prefix}.nanosec"]


def start_node(
    executable: str, node: str, params: dict[str, str], extra: tuple[str, ...] = ()
) -> subprocess.Popen:
    options = GraphOptions(extra_ros_args=extra, log_level="warn")
    return subprocess.Popen(
        executable_path(executable) + ros_arguments(node, params, options), env=child_environment()
    )


class ControllerReplay:
    """Feeds a fresh finger_controller the recorded inputs of one finger in recorded order,
    one at a time: every feedback sample that triggers a control step is answered by a duty
    before the next input goes out, so the controller sees exactly the recorded sequence."""

    def __init__(self, finger: str) -> None:
        import rclpy
        from hems_msgs.msg import (
            ControllerStatus,
            DutyCommand,
            EncoderReading,
            FingerSetpoint,
            SupervisorStatus,
            WireForce,
        )
        from rclpy.executors import SingleThreadedExecutor

        from hems_ros.ros import qos

        self.finger = finger
        self.context = rclpy.Context()
        rclpy.init(context=self.context)
        self.node = rclpy.create_node("controller_replay", context=self.context)
        self.executor = SingleThreadedExecutor(context=self.context)
        self.executor.add_node(self.node)
        self.duties: list = []
        self.statuses: list = []
        self.node.create_subscription(
            DutyCommand, names.topic(finger, "duty"), self.duties.append, qos.DUTY
        )
        self.node.create_subscription(
            ControllerStatus,
            names.topic(finger, "controller_status"),
            self.statuses.append,
            qos.CONTROLLER_STATUS,
        )
        self.publishers = {
            names.topic(finger, "setpoint"): self.node.create_publisher(
                FingerSetpoint, names.topic(finger, "setpoint"), qos.COMMAND
            ),
            names.topic(finger, "encoder"): self.node.create_publisher(
                EncoderReading, names.topic(finger, "encoder"), qos.SENSOR
            ),
            names.topic(finger, "wire_force"): self.node.create_publisher(
                WireForce, names.topic(finger, "wire_force"), qos.SENSOR
            ),
        }
        self.status = self.node.create_publisher(
            SupervisorStatus, names.SUPERVISOR_STATUS_TOPIC, qos.STATUS
        )

    def spin_until(self, condition, timeout: float, what: str) -> None:
        deadline = time.monotonic() + timeout
        while not condition():
            if time.monotonic() > deadline:
                raise TimeoutError(f"controller replay: no {what} within {timeout:g} s")
            self.executor.spin_once(timeout_sec=0.005)

    def wait_for_controller(self, timeout: float = 60.0) -> None:
        self.spin_until(
            lambda: all(p.get_subscription_count() for p in self.publishers.values())
            and self.statuses,
            timeout,
            "controller",
        )

    def enable(self) -> None:
        from hems_msgs.msg import SupervisorStatus

        self.status.publish(SupervisorStatus(state=SupervisorStatus.ENABLED, state_name="ENABLED"))
        self.spin_until(lambda: self.statuses[-1].active, 5.0, "active controller status")

    def feed(self, topic: str, data: bytes, triggers: bool, stamp: int = 0) -> None:
        before = len(self.duties)
        self.publishers[topic].publish(data)
        if triggers:
            self.spin_until(
                lambda: len(self.duties) > before
                and stamp_ns_of(self.duties[-1].measurement_stamp) == stamp,
                5.0,
                f"duty for the sample stamped {stamp}",
            )
        else:
            # a setpoint or the other mode's feedback: no reply to wait for, but the
            # controller must have taken it before the next sample arrives
            end = time.monotonic() + 0.05
            while time.monotonic() < end:
                self.executor.spin_once(timeout_sec=0.005)

    def close(self) -> None:
        import rclpy

        self.executor.shutdown()
        self.node.destroy_node()
        rclpy.try_shutdown(context=self.context)


def stamp_ns_of(message) -> int:
    return message.sec * 1_000_000_000 + message.nanosec


def as_installed(raw) -> bytes:
    """A recorded message re-encoded with the installed definition of its type. The reference
    bags' encoder readings predate the drive board's measurement in the same packet: those
    fields come as NaN, which the thermal guard takes as no heating."""
    from hems_ros.codec import cdr, msgdefs
    from hems_ros.ros.wire import codec

    if raw.definition.strip() == msgdefs.full_definition(raw.type).strip():
        return raw.data
    recorded = cdr.build_decoder(raw.type, msgdefs.parse_full_definition(raw.type, raw.definition))
    values = dict(
        zip((c.name.replace(".", "_") for c in recorded.columns), recorded.decode(raw.data))
    )
    package, _, name = raw.type.partition("/msg/")
    installed = codec(getattr(importlib.import_module(f"{package}.msg"), name))
    missing = set(installed.fields._fields) - set(values)
    if not missing <= DRIVE_FIELDS:
        raise ValueError(f"{raw.type}: recorded without {sorted(missing)}")
    return installed.encode(installed.fields(**{**dict.fromkeys(missing, math.nan), **values}))


DRIVE_FIELDS = {"duty_percent", "on_current", "on_voltage"}


def controller_inputs(bag_path: Path, finger: str):
    """The recorded controller inputs in the order the controller took them (see below).

    Returns (inputs, first_enabled_index): inputs are (topic, raw bytes, decoded message, time
    taken) of the setpoint, encoder and wire-force streams and the supervisor status.
    """
    from hems_msgs.msg import EncoderReading, FingerSetpoint, SupervisorStatus, WireForce
    from rclpy.serialization import deserialize_message

    types = {
        names.topic(finger, "setpoint"): FingerSetpoint,
        names.topic(finger, "encoder"): EncoderReading,
        names.topic(finger, "wire_force"): WireForce,
        names.SUPERVISOR_STATUS_TOPIC: SupervisorStatus,
    }
    duty = load_bag(bag_path, topics=[names.topic(finger, "duty")])[names.topic(finger, "duty")]
    computed = dict(
        zip(stamp_ns(duty, "measurement_stamp")[::-1].tolist(), stamp_ns(duty)[::-1].tolist())
    )
    decoded = []
    for m in iter_messages(bag_path, topics=list(types)):
        m = dataclasses.replace(m, data=as_installed(m))
        msg = deserialize_message(m.data, types[m.topic])
        # Ordered by when the original controller most likely took each message; the
        # recorder's receive time can lag that by a few ms. A feedback sample was taken no
        # later than the duty computed from its sample time was stamped; a setpoint or a
        # status is stamped just before it is sent.
        if m.topic in (names.topic(finger, "encoder"), names.topic(finger, "wire_force")):
            taken = min(m.log_time_ns, computed.get(stamp_ns_of(msg.header.stamp), m.log_time_ns))
        else:
            taken = min(m.log_time_ns, stamp_ns_of(msg.header.stamp))
        decoded.append((m.topic, m.data, msg, taken))
    # The controller takes the supervisor's status only at its status steps (it does not wake
    # for it, hems_ros/nodes/finger_controller.py), so ENABLED counts from the step whose
    # status first reports the controller active: just before that step's feedback sample
    # (every ENABLED sent before then, the status being republished, waits until then).
    first_active = _first_active_measurement(bag_path, finger)
    feedback = (names.topic(finger, "encoder"), names.topic(finger, "wire_force"))
    enable_at = min(
        (
            taken
            for topic, _, msg, taken in decoded
            if topic in feedback and stamp_ns_of(msg.header.stamp) == first_active
        ),
        default=None,
    )
    if enable_at is not None:
        decoded = [
            (topic, data, msg, max(taken, enable_at - 1))
            if topic == names.SUPERVISOR_STATUS_TOPIC and msg.state == SupervisorStatus.ENABLED
            else (topic, data, msg, taken)
            for topic, data, msg, taken in decoded
        ]
    decoded.sort(key=lambda entry: entry[3])
    enabled = next(
        i
        for i, (topic, _, msg, _) in enumerate(decoded)
        if topic == names.SUPERVISOR_STATUS_TOPIC and msg.state == SupervisorStatus.ENABLED
    )
    return decoded, enabled


def _first_active_measurement(bag_path: Path, finger: str) -> int | None:
    """Measurement stamp (ns) of the first duty the controller computed while active.

    A control step sends its duty, then its status (within a millisecond); an idle status
    (no feedback for 0.1 s) comes without a duty, and the next duty is the first active one.
    """
    topics = [names.topic(finger, "controller_status"), names.topic(finger, "duty")]
    bag = load_bag(bag_path, topics=topics)
    status, duty = bag[topics[0]], bag[topics[1]]
    active = np.flatnonzero(status["active"])
    if active.size == 0:
        return None
    reported, sent = stamp_ns(status)[active[0]], stamp_ns(duty)
    same_step = np.flatnonzero((sent <= reported) & (sent > reported - 1_000_000))
    later = np.flatnonzero(sent > reported)
    first = same_step[-1] if same_step.size else (later[0] if later.size else None)
    return None if first is None else int(stamp_ns(duty, "measurement_stamp")[first])


OTHER_FEEDBACK_NS = 40_000_000


def replay_into_controller(
    reference: Reference,
) -> tuple[list[tuple[int, float]], list[tuple[int, float]]]:
    """Replay ``reference`` into a fresh controller; (replayed, recorded) duties as (measurement
    stamp, duty)."""
    finger = reference.finger
    inputs, enabled = controller_inputs(reference.path, finger)
    encoder, wire_force, setpoint = (
        names.topic(finger, s) for s in ("encoder", "wire_force", "setpoint")
    )
    # the reference runs' controllers judged the other sensor's lag at 100 ms
    controller = start_node(
        "finger_controller",
        f"finger_controller_{finger}",
        {"finger": finger, "feedback_lag_s": "0.1"},
        ("-p", f"pulley_ratio:={reference.pulley_ratio!r}"),
    )
    replay = ControllerReplay(finger)
    try:
        replay.wait_for_controller()
        mode = "position"
        # Before ENABLED the controller computes nothing: the latest feedback of each stream
        # is enough. After it, the other mode's feedback goes in too, every OTHER_FEEDBACK_NS
        # of its stamps: its freshness gates the duty (feedback_lag_s, 100 ms), and each feed
        # waits for the controller to take it.
        held = {}
        for topic, data, msg, _ in inputs[:enabled]:
            if topic == setpoint:
                mode = msg.mode
                replay.feed(topic, data, False)
            elif topic in (encoder, wire_force):
                held[topic] = data
        for topic, data in held.items():
            replay.feed(topic, data, False)
        replay.enable()
        first_duty = len(replay.duties)
        held, other_fed = {}, 0
        for topic, data, msg, _ in inputs[enabled + 1 :]:
            if topic == names.SUPERVISOR_STATUS_TOPIC:
                if msg.state_name != "ENABLED":
                    break  # the run ends at the first state change after ENABLED
                continue
            if topic == setpoint:
                if held:  # the value a mode switch starts from: the latest reading
                    replay.feed(*held.popitem(), False)
                mode = msg.mode
                replay.feed(topic, data, False)
            elif (topic == encoder) == (mode == "position"):
                replay.feed(topic, data, True, stamp_ns_of(msg.header.stamp))
            elif stamp_ns_of(msg.header.stamp) - other_fed >= OTHER_FEEDBACK_NS:
                replay.feed(topic, data, False)
                other_fed = stamp_ns_of(msg.header.stamp)
                held.clear()
            else:
                held = {topic: data}
        replayed = [
            (stamp_ns_of(d.measurement_stamp), d.duty_percent) for d in replay.duties[first_duty:]
        ]
    finally:
        replay.close()
        stop_process(controller, 10.0)
    duty = load_bag(reference.path, topics=[names.topic(finger, "duty")])[
        names.topic(finger, "duty")
    ]
    recorded = list(
        zip(stamp_ns(duty, "measurement_stamp").tolist(), duty["duty_percent"].tolist())
    )
    start = next(i for i, (stamp, _) in enumerate(recorded) if stamp == replayed[0][0])
    return replayed, recorded[start : start + len(replayed)]


def grasp_metrics(bag_path: Path, finger: str, plan: GraspPlan, phase_starts: list[float]):
    """The demo's per-finger summary computed from a bag: tendon position and force from the
    encoder and wire-force streams (matched by stamp), power from the actuator state."""
    bag = load_bag(
        bag_path,
        topics=[
            names.topic(finger, "encoder"),
            names.topic(finger, "wire_force"),
            names.sim_topic(finger, "state"),
            names.topic(finger, "duty"),
        ],
    )
    encoder, force = bag[names.topic(finger, "encoder")], bag[names.topic(finger, "wire_force")]
    state, duty = bag[names.sim_topic(finger, "state")], bag[names.topic(finger, "duty")]
    common, ei, fi = np.intersect1d(stamp_ns(encoder), stamp_ns(force), return_indices=True)
    trace = FingerTrace(
        list(common * 1e-9),
        list(transmission.tendon_position(encoder["position"][ei])),
        list(transmission.tendon_force(force["force"][fi])),
        list(state.stamp),
        list(state["electrical_energy"]),
        list(duty.stamp),
        list(duty["duty_percent"]),
    )
    return summarize(finger, trace, plan, phase_starts)


def phase_stamps(bag_path: Path, finger: str) -> list[float]:
    """When each phase of the recorded grasp began (:class:`hems_ros.graph.grasp.PhaseTracker`)."""
    topic = names.topic(finger, "controller_status")
    status = load_bag(bag_path, topics=[topic])[topic]
    tracker = PhaseTracker()
    encoder, force = (
        stamp_ns(status, "encoder_stamp") * 1e-9,
        stamp_ns(status, "force_stamp") * 1e-9,
    )
    for i in range(len(status.stamp)):
        tracker.feed(
            status["mode"][i],
            status["setpoint"][i],
            bool(status["active"][i]),
            encoder[i],
            force[i],
        )
    return tracker.starts
