"""A short-lived rclpy node the command-line verbs use to talk to a running graph."""

from __future__ import annotations

import functools
import math
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

import rclpy
from diagnostic_msgs.msg import DiagnosticArray
from hems_msgs.msg import (
    ActuatorState,
    ControllerStatus,
    FingerSetpoint,
    SupervisorStatus,
    WireForce,
)
from rclpy.executors import ExternalShutdownException
from rclpy.parameter import Parameter
from rclpy.type_description_service import START_TYPE_DESCRIPTION_SERVICE_PARAM
from std_srvs.srv import Trigger

from hems_ros.client import DISCOVERY_S
from hems_ros.graph import names
from hems_ros.graph.supervisor_logic import HEARD_KEY
from hems_ros.ros import qos
from hems_ros.ros.clock_time import from_msg
from hems_ros.ros.lean_node import LeanNode
from hems_ros.ros.teardown import end_ros

RETRY_S = 2.0  # a service call unanswered this long is sent again
# a wait for the controllers' setpoint readers shows its progress once it lasts this long, s
PROGRESS_AFTER_S = 1.0
CLOCK_STALL_S = 5.0  # /clock standing still this long (wall) means the graph's clock is gone
MATCH_ALL_S = (
    1.0  # a subscription that never matches (incompatible QoS) delays a setpoint this long at most
)
RESEND_S = 0.3  # a setpoint the controller status does not show yet is sent again after this long
# A snapshot takes each stream's newest message this often instead of every message as it
# comes: `hems status` heard some 900 messages a second through rclpy's executor and spent
# about 0.7 s of CPU doing so, on a host whose graph needs the CPU at that moment.
SNAPSHOT_POLL_S = 0.05


def checked(call, *args, **kwargs):
    """``call(...)`` (rclpy.spin_once, spin_until_future_complete, a service call) that raises
    ExternalShutdownException once SIGINT or SIGTERM has shut rclpy's context down: the call
    itself then fails in whatever rcl object it uses next, with an RCLError or RuntimeError
    that says nothing of the signal."""
    if not rclpy.ok():
        raise ExternalShutdownException()
    try:
        return call(*args, **kwargs)
    except Exception:
        if rclpy.ok():
            raise
        raise ExternalShutdownException() from None


@dataclass
class SetpointResult:
    """What became of a setpoint: ``sent`` to a subscribed controller, ``confirmed`` by its
    status (None when not checked), and a line for the user. True when sent and not refuted.
    ``in_force_s``: graph time (s) from which the setpoint acts: the later of the status's
    feedback sample and its own stamp (a status published on the change, as the controller
    took the setpoint, still carries the sample before)."""

    sent: bool
    confirmed: bool | None
    message: str
    in_force_s: float | None = None

    def __bool__(self) -> bool:
        return self.sent and self.confirmed is not False


@dataclass
class Snapshot:
    """The latest message of each kind per finger, gathered over a short listen."""

    controllers: dict[str, ControllerStatus] = field(default_factory=dict)
    states: dict[str, ActuatorState] = field(default_factory=dict)
    forces: dict[str, WireForce] = field(default_factory=dict)
    supervisor: SupervisorStatus | None = None
    # the supervisor's latest /diagnostics key-value pairs (1 Hz: empty if none came)
    diagnostics: list[tuple[str, str]] = field(default_factory=list)
    # the fingers listened to: those of them the supervisor hears must report here too
    fingers: tuple[str, ...] = ()

    def incomplete(self) -> bool:
        """The supervisor not heard yet (its status, or its once-a-second diagnostics), a
        finger listened to whose controller the supervisor hears but this snapshot has not (a
        new process discovers the graph's writers one by one), or a finger whose controller
        reported without its unit's state or its wire force."""
        heard = dict(self.diagnostics).get(HEARD_KEY, "").split(",")
        return (
            self.supervisor is None
            or not self.diagnostics
            or any(f in heard and f not in self.controllers for f in self.fingers)
            or any(f not in self.states or f not in self.forces for f in self.controllers)
        )


class GraphClient:
    def __init__(
        self, name: str = "hems_cli", sim_time: bool = False, namespace: str = names.NAMESPACE
    ) -> None:
        """``sim_time``: the graph runs on /clock (``hems up --sim-time``); the client then
        stamps its setpoints with the graph's time and :meth:`spin_graph_time` counts it.
        ``namespace``: the graph's (``hems up --namespace``)."""
        if not rclpy.ok():
            rclpy.init(args=[])
        self.sim_time = sim_time
        self.namespace = namespace
        try:
            # No parameter or type-description services, no /rosout and (LeanNode) no QoS
            # event handlers: the client serves no parameters and logs nothing, each endpoint
            # is announced to every node of the graph as a command-line tool starts, and each
            # handler is another entity for every wait of rclpy's executor.
            self.node = LeanNode(
                f"{name}_{int(time.time() * 1e3) % 100000}",
                namespace=namespace,
                start_parameter_services=False,
                enable_rosout=False,
                parameter_overrides=[
                    Parameter(START_TYPE_DESCRIPTION_SERVICE_PARAM, value=False),
                    *([Parameter("use_sim_time", value=True)] if sim_time else []),
                ],
            )
        except Exception as error:
            # a SIGINT or SIGTERM while the node was being made shut the context down under
            # it (its next rcl call fails): a stop, as the verbs know it, not a crash
            if not rclpy.ok():
                raise ExternalShutdownException() from error
            raise
        self._setpoint_pubs: dict[str, object] = {}
        # Endpoints are kept for the client's life: every new endpoint is announced to all
        # sixteen nodes, which costs them CPU at the moment they should be controlling.
        self._service_clients: dict[str, object] = {}
        self._status_subs: dict[str, object] = {}
        self._statuses: dict[str, ControllerStatus] = {}
        self._supervisor_sub: object | None = None
        self._supervisor: SupervisorStatus | None = None

    def close(self) -> None:
        end_ros([self.node])

    def __enter__(self) -> "GraphClient":
        return self

    def __exit__(self, *exc) -> None:
        self.close()

    def spin_for(self, seconds: float) -> None:
        deadline = time.monotonic() + seconds
        while time.monotonic() < deadline:
            checked(
                rclpy.spin_once,
                self.node,
                timeout_sec=max(0.0, min(0.05, deadline - time.monotonic())),
            )

    def spin_graph_time(
        self, seconds: float, stall_s: float = CLOCK_STALL_S, since_s: float | None = None
    ) -> None:
        """Spin for ``seconds`` of the graph's time: wall seconds, or on sim time seconds of
        /clock (with ``--rate R`` a phase of a run lasts what it says in simulated time),
        counted from ``since_s`` (graph time, s) when given: this client's /clock can lag the
        sample a controller took a setpoint at. RuntimeError when /clock stands still for
        ``stall_s`` wall seconds."""
        if not self.sim_time:
            self.spin_for(seconds)
            return
        clock = self.node.get_clock()
        start = None if since_s is None else round(since_s * 1e9)
        last, moved = clock.now().nanoseconds, time.monotonic()
        while True:
            now = clock.now().nanoseconds
            if now != last:
                last, moved = now, time.monotonic()
            elif time.monotonic() - moved > stall_s:
                raise RuntimeError(f"the graph's /clock has not moved for {stall_s:g} s")
            if now > 0:  # 0 until the first /clock message
                start = now if start is None else start
                if now - start >= seconds * 1e9:
                    return
            checked(rclpy.spin_once, self.node, timeout_sec=0.01)

    def _service_client(self, command: str):
        client = self._service_clients.get(command)
        if client is None:
            client = self._service_clients[command] = self.node.create_client(
                Trigger, names.service(command, self.namespace)
            )
        return client

    def call(self, command: str, timeout: float = 10.0) -> tuple[bool, str]:
        """Call a supervisor Trigger service; (success, message).
        ExternalShutdownException once a signal has shut the context down (see :func:`checked`).
        """
        return checked(self._call, command, timeout)

    def _call(self, command: str, timeout: float) -> tuple[bool, str]:
        """:meth:`call` without the signal check.

        Enabling also makes the estop client, so that it is matched by the time it is needed:
        the supervisor takes a request only from a client it has discovered, and the first
        estop from a new client waited for that (about 70 ms) where a matched one stops every
        unit within a few milliseconds."""
        client = self._service_client(command)
        if command == "enable":
            self._service_client("estop")
        if not client.wait_for_service(timeout_sec=timeout):
            return (
                False,
                f"no supervisor answers {names.service(command, self.namespace)} (is "
                f"the graph up?)",
            )
        # The middleware drops a response sent before the service has matched this client's
        # response reader (wait_for_service sees only the request side), which a new process
        # meets now and then: ask again. The four commands give the same answer when repeated.
        deadline = time.monotonic() + timeout
        while True:
            future = client.call_async(Trigger.Request())
            checked(
                rclpy.spin_until_future_complete,
                self.node,
                future,
                timeout_sec=max(0.0, min(RETRY_S, deadline - time.monotonic())),
            )
            if future.result() is not None:
                return future.result().success, future.result().message
            client.remove_pending_request(future)
            if time.monotonic() >= deadline:
                return (
                    False,
                    f"{names.service(command, self.namespace)} did not answer within {timeout:g} s",
                )

    def wait_until_ready(
        self, timeout: float, progress: Callable[[list[str] | None], None] | None = None
    ) -> list[str] | None:
        """Wait until the supervisor reports the graph ready on /diagnostics (every stream
        that ``enable`` needs is present) or ``timeout`` s have passed; returns what is still
        missing ([] once ready), or None when no supervisor reported at all.

        ``progress(missing)`` is called whenever what is missing changes (None: no supervisor
        heard yet). The client's own discovery of the graph comes first: a new process can
        take seconds to match the supervisor's writer (:data:`DISCOVERY_S`)."""
        name = names.diagnostic_name(self.namespace, "supervisor")
        latest: dict[str, list[str]] = {}

        def on_diagnostics(array: DiagnosticArray) -> None:
            for status in array.status:
                if status.name == name:
                    latest["missing"] = [kv.value for kv in status.values if kv.key == "not ready"]

        subscription = self.node.create_subscription(
            DiagnosticArray, names.DIAGNOSTICS_TOPIC, on_diagnostics, 10
        )
        deadline = time.monotonic() + timeout
        shown: list[str] | None | bool = False  # nothing shown yet
        try:
            while True:
                missing = latest.get("missing")
                if progress is not None and missing != shown:
                    progress(missing)
                    shown = missing
                if missing == [] or time.monotonic() >= deadline:
                    return missing
                checked(rclpy.spin_once, self.node, timeout_sec=0.05)
        finally:
            self.node.destroy_subscription(subscription)

    def enable_when_ready(
        self,
        timeout: float,
        reset: bool = False,
        retry_s: float = 2.0,
        progress: Callable[[list[str] | None], None] | None = None,
    ) -> tuple[bool, str]:
        """Wait until the graph is ready (:meth:`wait_until_ready`, ``progress`` as there),
        then call ``enable`` until the supervisor accepts it (a stream can lapse between the
        two) or ``timeout`` s have passed in all; (success, last message).

        ``reset`` unlatches a fault first on every try (a start-up hiccup may have latched one).
        """
        deadline = time.monotonic() + timeout
        missing = self.wait_until_ready(timeout, progress)
        if missing is None:
            return False, (
                f"no supervisor reported within {timeout:g} s "
                f"(is the graph up in {self.namespace}?)"
            )
        if missing:
            return False, f"the graph was not ready after {timeout:g} s: " + "; ".join(missing)
        ok, message = False, "no answer"
        while time.monotonic() < deadline:
            if reset:
                self.call("reset", timeout=max(1.0, min(5.0, deadline - time.monotonic())))
            ok, message = self.call(
                "enable", timeout=max(1.0, min(5.0, deadline - time.monotonic()))
            )
            if ok:
                break
            self.spin_for(retry_s)
        return ok, message

    def send_setpoint(
        self,
        finger: str,
        mode: str,
        value: float,
        timeout: float = DISCOVERY_S,
        confirm_s: float | None = None,
    ) -> SetpointResult:
        """Publish one setpoint once the finger's controller is subscribed (``timeout`` s).

        It also waits, up to MATCH_ALL_S more, until every other subscription this process
        already knows on the topic (a recorder, ``ros2 topic echo``) has matched: the setpoint
        is sent once and not latched.

        ``confirm_s``: then watch the finger's controller status until it shows the setpoint,
        sending it again every RESEND_S, for up to ``confirm_s`` s. A reader that has not yet
        matched this new writer drops the sample, and the reliable repair waits for the
        writer's heartbeat (every 3 s), which a process that exits at once never sends:
        without the check, one `hems setpoint` of 60 against a one-finger graph here left the
        controller on its old setpoint."""
        topic = names.topic(finger, "setpoint", self.namespace)
        if confirm_s is not None:
            self._watch_status(finger)  # discovered while the setpoint writer is being matched
        publisher = self._setpoint_publisher(finger)
        if self.fingers_without_readers([finger], 1, timeout):
            return SetpointResult(False, None, f"no finger_controller subscribed to {topic}")
        until = time.monotonic() + MATCH_ALL_S
        while (
            publisher.get_subscription_count() < self.node.count_subscribers(topic)
            and time.monotonic() < until
        ):
            checked(rclpy.spin_once, self.node, timeout_sec=0.02)
        before = self._statuses.get(finger)
        self._publish_setpoint(publisher, mode, value)
        if confirm_s is None:
            return SetpointResult(True, None, "sent")
        rejected = None if before is None else before.rejected_setpoints
        deadline = time.monotonic() + confirm_s
        resend = time.monotonic() + RESEND_S
        while time.monotonic() < deadline:
            checked(rclpy.spin_once, self.node, timeout_sec=0.01)
            status = self._statuses.get(finger)
            # only a status received after the publish: the one before may come from a
            # controller since restarted, which never took this setpoint
            if status is not None and status is not before:
                if status.mode == mode and math.isclose(
                    status.setpoint, value, rel_tol=1e-9, abs_tol=1e-12
                ):
                    feedback = status.encoder_stamp if mode == "position" else status.force_stamp
                    # the status sent at once on the change carries the sample before it
                    acted_from = max(from_msg(feedback), from_msg(status.header.stamp))
                    return SetpointResult(True, True, "in force (controller status)", acted_from)
                if rejected is None:
                    rejected = status.rejected_setpoints
                elif status.rejected_setpoints > rejected:
                    return SetpointResult(
                        True, False, f"rejected by the controller: {status.last_rejection}"
                    )
            if time.monotonic() >= resend:
                self._publish_setpoint(publisher, mode, value)
                resend = time.monotonic() + RESEND_S
        status = self._statuses.get(finger)
        seen = (
            "no controller status received"
            if status is None or status is before
            else f"the controller status shows {status.mode} {status.setpoint:g}"
        )
        return SetpointResult(True, False, f"sent, but not in force after {confirm_s:g} s ({seen})")

    def watch_supervisor(self) -> None:
        """Start listening to the supervisor's status now, so that discovery runs while the
        client does other work; :meth:`supervisor_status` then rarely waits."""
        if self._supervisor_sub is None:
            self._supervisor_sub = self.node.create_subscription(
                SupervisorStatus,
                names.supervisor_status_topic(self.namespace),
                lambda m: setattr(self, "_supervisor", m),
                qos.STATUS,
            )

    def supervisor_status(self, timeout: float = DISCOVERY_S) -> SupervisorStatus | None:
        """The supervisor's latest status (transient local: the last one comes at once to a
        new reader), or None when none has come within ``timeout`` s. The reader stays for
        the client's life; a new one is matched only after DDS discovery, which on a busy
        host can take seconds."""
        self.watch_supervisor()
        deadline = time.monotonic() + timeout
        while self._supervisor is None and time.monotonic() < deadline:
            checked(rclpy.spin_once, self.node, timeout_sec=0.02)
        return self._supervisor

    def _setpoint_publisher(self, finger: str):
        publisher = self._setpoint_pubs.get(finger)
        if publisher is None:
            publisher = self.node.create_publisher(
                FingerSetpoint, names.topic(finger, "setpoint", self.namespace), qos.COMMAND
            )
            self._setpoint_pubs[finger] = publisher
        return publisher

    def fingers_without_readers(
        self,
        fingers,
        readers: int = 1,
        timeout: float = DISCOVERY_S,
        progress: Callable[[list[str] | None], None] | None = None,
    ) -> list[str]:
        """The ``fingers`` whose setpoint writer in this client has matched fewer than
        ``readers`` readers (the finger's controller, a recorder) after ``timeout`` s, all
        waited for at once, so that a run needing them all says so before anything heats. Only
        a matched reader gets the next setpoint: the writer keeps none for latecomers.

        ``progress(topics)`` is called with the setpoint topics still unmatched whenever they
        change, once the wait has lasted PROGRESS_AFTER_S (a match usually comes sooner)."""
        publishers = {f: self._setpoint_publisher(f) for f in fingers}
        started = time.monotonic()
        shown: list[str] | None = None
        while True:
            missing = [f for f, pub in publishers.items() if pub.get_subscription_count() < readers]
            waited = time.monotonic() - started
            if not missing or waited > timeout:
                return missing
            topics = [f"{pub.topic_name} reader" for f, pub in publishers.items() if f in missing]
            if progress is not None and waited >= PROGRESS_AFTER_S and topics != shown:
                progress(topics)
                shown = topics
            checked(rclpy.spin_once, self.node, timeout_sec=0.02)

    def _publish_setpoint(self, publisher, mode: str, value: float) -> None:
        message = FingerSetpoint(mode=mode, value=float(value))
        message.header.stamp = self.node.get_clock().now().to_msg()
        publisher.publish(message)

    def _watch_status(self, finger: str) -> None:
        if finger not in self._status_subs:
            self._status_subs[finger] = self.node.create_subscription(
                ControllerStatus,
                names.topic(finger, "controller_status", self.namespace),
                lambda m, f=finger: self._statuses.__setitem__(f, m),
                qos.CONTROLLER_STATUS,
            )

    def snapshot(
        self, fingers=names.FINGERS, seconds: float = 0.5, supervisor_wait_s: float = DISCOVERY_S
    ) -> Snapshot:
        """Listen for ``seconds`` (taking each stream's newest message every
        :data:`SNAPSHOT_POLL_S`), and up to ``supervisor_wait_s`` longer while the snapshot is
        :meth:`Snapshot.incomplete`: DDS discovery between a new process and the graph now and
        then waits for a periodic announcement, seconds later, and `hems status` reported a
        running supervisor as not running, or a finger's position and force as missing."""
        snap = Snapshot(fingers=tuple(fingers))
        supervisor = names.diagnostic_name(self.namespace, "supervisor")

        def on_diagnostics(array: DiagnosticArray) -> None:
            for status in array.status:
                if status.name == supervisor:
                    snap.diagnostics = [(kv.key, kv.value) for kv in status.values]

        streams: list[tuple[type, str, Callable[[Any], None]]] = [
            (
                SupervisorStatus,
                names.supervisor_status_topic(self.namespace),
                lambda m: setattr(snap, "supervisor", m),
            ),
        ]
        for finger in fingers:
            streams += [
                (
                    ControllerStatus,
                    names.topic(finger, "controller_status", self.namespace),
                    functools.partial(snap.controllers.__setitem__, finger),
                ),
                (
                    ActuatorState,
                    names.sim_topic(finger, "state", self.namespace),
                    functools.partial(snap.states.__setitem__, finger),
                ),
                (
                    WireForce,
                    names.topic(finger, "wire_force", self.namespace),
                    functools.partial(snap.forces.__setitem__, finger),
                ),
            ]
        subs = [self.node.create_subscription(*stream, qos.LATEST) for stream in streams]
        # every node's array comes on /diagnostics once a second: the supervisor's is one of them
        subs.append(
            self.node.create_subscription(
                DiagnosticArray, names.DIAGNOSTICS_TOPIC, on_diagnostics, 10
            )
        )
        listened = time.monotonic() + seconds
        deadline = listened + supervisor_wait_s
        while True:
            time.sleep(SNAPSHOT_POLL_S)
            for sub in subs:
                checked(self.node.drain, sub)
            now = time.monotonic()
            if now >= deadline or (now >= listened and not snap.incomplete()):
                break
        for sub in subs:
            self.node.destroy_subscription(sub)
        return snap
