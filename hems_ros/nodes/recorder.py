"""Records topics to an MCAP bag in the rosbag2 layout (``hems_ros.bag.BagWriter``).

Topics are found by querying the ROS graph every ``discovery_period`` seconds and taken if
named in ``topics`` or fully matching ``regex`` (default: every ``/hems`` topic,
``/diagnostics`` and ``/clock``). Each is subscribed raw: the serialized CDR bytes are
written as received, never decoded. The subscription QoS follows the publishers: reliable
only if every publisher is reliable (so best-effort sensor streams are matched), transient
local if every publisher is (so latched status is received on joining).

A topic in the graph with subscribers but no publisher yet (a controller's setpoint topic) is
subscribed at once, reliable and volatile as command writers are, so that the single message
of a short-lived publisher (``hems setpoint``, ``ros2 topic pub --once``) is recorded: such a
process has sent and gone before a recorder that waited to see its publisher would have
matched it. Its bag channel, with the publishers' offered QoS, is opened when a publisher or
the first message appears; a best-effort publisher turns the subscription best effort, a
latched one transient local unless messages already came.

Parameters: ``output`` (bag folder, must not exist or be empty; default
``hems_<date>_<time>``), ``topics`` (string array), ``regex`` (string), ``discovery_period``
(s, 0.2), ``flush_period`` (s, 0.5: the open chunk is closed and handed to the OS this often,
so a SIGKILL loses at most that much), ``chunk_size`` (bytes, 262144), ``compression``
(zstd | lz4 | none), ``queue_depth`` (1000), ``duration`` (s, 0 = until stopped).

Joining a running graph: while the recorder creates its ~40 subscriptions, the topics it
already records can miss samples, on every stream at once, for up to about half a second
(best-effort and reliable alike: the writers keep 10 samples). In 10 recordings of the full
graph here every loss fell before or within 0.2 s after the last subscription, none later
(tests/bag/test_graph_record.py opens its window 2 s after it). Start the recorder with the
graph (``hems up --record``) or give it two seconds before the part of a run that matters.

Messages are logged at the reception time the middleware stamped on them, with the
writer's source time as publish time (both nanoseconds since the epoch).

Each subscribed topic is logged as ``recording <topic> [<type>] ...``; on SIGINT or SIGTERM
(or after ``duration``) the bag is finished (summary, footer, ``metadata.yaml``) and its path
and message counts are logged.
"""

from __future__ import annotations

import time
from datetime import datetime
from typing import Any

from rclpy.node import Node
from rclpy.parameter import Parameter
from rclpy.qos import DurabilityPolicy, HistoryPolicy, QoSProfile, ReliabilityPolicy
from rclpy.subscription import Subscription

from hems_ros.bag import BagWriter, TopicSelection, offered_qos
from hems_ros.bag.selection import DEFAULT_RECORD_REGEX
from hems_ros.ros import lean_spin
from hems_ros.ros.wire import message_class

READY_PREFIX = "recording "
BATCH_S = 0.02  # recorder loop: pause after each round, so that rounds find batches
FINISHED_PREFIX = "bag finished: "
HEARD_PREFIX = "first message on "


def waiting_qos(depth: int) -> QoSProfile:
    """QoS for a topic that has no publisher yet: that of command writers (qos.COMMAND)."""
    return QoSProfile(
        history=HistoryPolicy.KEEP_LAST,
        depth=depth,
        reliability=ReliabilityPolicy.RELIABLE,
        durability=DurabilityPolicy.VOLATILE,
    )


def subscription_qos(publishers: list, depth: int) -> tuple[QoSProfile, list[dict]]:
    """A QoS that matches every publisher, and their offered profiles for the bag."""
    reliable = bool(publishers) and all(
        p.qos_profile.reliability == ReliabilityPolicy.RELIABLE for p in publishers
    )
    latched = bool(publishers) and all(
        p.qos_profile.durability == DurabilityPolicy.TRANSIENT_LOCAL for p in publishers
    )
    qos = QoSProfile(
        history=HistoryPolicy.KEEP_LAST,
        depth=depth,
        reliability=ReliabilityPolicy.RELIABLE if reliable else ReliabilityPolicy.BEST_EFFORT,
        durability=DurabilityPolicy.TRANSIENT_LOCAL if latched else DurabilityPolicy.VOLATILE,
    )
    offered = [
        offered_qos(
            p.qos_profile.reliability == ReliabilityPolicy.RELIABLE,
            p.qos_profile.durability == DurabilityPolicy.TRANSIENT_LOCAL,
            p.qos_profile.depth,
            p.qos_profile.liveliness_lease_duration.nanoseconds,
        )
        for p in publishers
    ]
    return qos, offered


class Recorder(Node):
    def __init__(self, **node_kwargs) -> None:
        super().__init__("recorder", namespace="/hems", enable_rosout=False, **node_kwargs)
        output: str = self.declare_parameter("output", "").value or datetime.now().strftime(
            "hems_%Y%m%d_%H%M%S"
        )
        topics: list[str] = (
            self.declare_parameter("topics", Parameter.Type.STRING_ARRAY).value or []
        )
        regex: str = self.declare_parameter("regex", "").value
        self._selection = TopicSelection.of(
            topics, regex or (None if topics else DEFAULT_RECORD_REGEX)
        )
        discovery = self._positive("discovery_period", 0.2)
        flush = self._positive("flush_period", 0.5)
        chunk_size = int(self.declare_parameter("chunk_size", 262144).value)
        compression: str = self.declare_parameter("compression", "zstd").value
        self._depth = int(self.declare_parameter("queue_depth", 1000).value)
        duration = float(self.declare_parameter("duration", 0.0).value)
        if chunk_size <= 0 or self._depth <= 0 or duration < 0:
            raise ValueError("chunk_size and queue_depth must be positive, duration >= 0")
        self._writer = BagWriter(output, compression=compression, chunk_size=chunk_size)
        self._recorded: dict[str, Subscription[Any]] = {}
        self._heard_from: set[Subscription[Any]] = set()  # subscriptions that have taken a message
        self._channels: dict[
            Subscription[Any], tuple[int | None, type]
        ] = {}  # subscription -> (channel, class)
        self._types: dict[str, str] = {}
        self._waiting: set[str] = set()  # subscribed before the topic had a publisher
        self._skipped: set[str] = set()
        self._deadline = time.monotonic() + duration if duration > 0 else None
        self.get_logger().info(f"bag {self._writer.folder}: recording {self._selection.describe()}")
        try:
            self._discover()
            self.create_timer(discovery, self._discover)
            self.create_timer(flush, self._writer.flush)
        except BaseException:
            # a SIGTERM as soon as the first topics were reported subscribed shuts the context
            # down under the constructor, whose next rcl call then fails: the node never
            # exists to be destroyed, and the bag was left without its summary and footer
            self.finish()
            raise

    def _positive(self, name: str, default: float) -> float:
        value = float(self.declare_parameter(name, default).value)
        if value <= 0:
            raise ValueError(f"{name} must be positive, not {value}")
        return value

    @property
    def expired(self) -> bool:
        return self._deadline is not None and time.monotonic() >= self._deadline

    def _discover(self) -> None:
        for topic, types in self.get_topic_names_and_types():
            if topic in self._skipped or not self._selection.matches(topic):
                continue
            if topic in self._waiting:
                publishers = self.get_publishers_info_by_topic(topic)
                if publishers:
                    self._adopt(topic, publishers)
            elif topic not in self._recorded:
                self._subscribe(topic, types[0], self.get_publishers_info_by_topic(topic))

    def _subscribe(self, topic: str, type_name: str, publishers: list) -> None:
        try:
            cls = message_class(type_name)
            if publishers:
                qos, offered = subscription_qos(publishers, self._depth)
                channel = self._writer.add_topic(topic, type_name, offered)
            else:
                qos, channel = waiting_qos(self._depth), None
        except (ImportError, AttributeError, ValueError, OSError) as error:
            self._skipped.add(topic)
            self.get_logger().warning(f"not recording {topic} [{type_name}]: {error}")
            return
        self._types[topic] = type_name
        if channel is None:
            self._waiting.add(topic)
        self._listen(topic, cls, channel, qos)

    def _listen(self, topic: str, cls: type, channel: int | None, qos: QoSProfile) -> None:
        subscription = None

        # only for an executor that calls back per message; spin_until_expired drains instead
        def on_message(data: bytes) -> None:
            self._writer.write(self._channel(subscription), time.time_ns(), data)
            self._heard(subscription)

        subscription = self.create_subscription(cls, topic, on_message, qos, raw=True)
        self._recorded[topic] = subscription
        self._channels[subscription] = (channel, cls)
        self.get_logger().info(
            f"{READY_PREFIX}{topic} [{self._types[topic]}] "
            f"{qos.reliability.name.lower()}, {qos.durability.name.lower()}"
            f"{', before any publisher' if channel is None else ''}"
        )

    def _channel(self, subscription) -> int:
        """The bag channel of ``subscription``, opened now if its topic had no publisher before."""
        channel, cls = self._channels[subscription]
        if channel is None:
            topic = subscription.topic_name
            publishers = self.get_publishers_info_by_topic(topic)
            # A message can come before the graph cache lists its writer; it came to a reliable
            # reader, so from a reliable writer, taken as volatile (what command writers are).
            offered = (
                subscription_qos(publishers, self._depth)[1]
                if publishers
                else [offered_qos(True, False, 0)]
            )
            channel = self._writer.add_topic(topic, self._types[topic], offered)
            self._channels[subscription] = (channel, cls)
        return channel

    def _adopt(self, topic: str, publishers: list) -> None:
        """A waiting topic got publishers: open its channel with their offered QoS, and
        subscribe again where the waiting reader falls short (drained first, nothing queued is
        lost): a reliable reader never matches a best-effort writer, and a latched writer's
        sample sent before this reader matched it reaches only a transient-local reader. A
        waiting reader that has already taken messages is matched and stays."""
        self._waiting.discard(topic)
        subscription = self._recorded[topic]
        seen = self.drain(subscription) > 0 or self._channels[subscription][0] is not None
        channel, cls = self._channel(subscription), self._channels[subscription][1]
        qos = subscription_qos(publishers, self._depth)[0]
        if qos.reliability != ReliabilityPolicy.RELIABLE or (
            qos.durability == DurabilityPolicy.TRANSIENT_LOCAL and not seen
        ):
            del self._channels[subscription]
            self.destroy_subscription(subscription)
            self._listen(topic, cls, channel, qos)

    def drain(self, subscription) -> int:
        """Write every message waiting in ``subscription``'s queue; how many there were.

        Log time is the reception time the middleware stamped, publish time the writer's
        source time: both from the sample's message info, so a message waiting in the queue
        loses no timing accuracy.
        """
        channel, cls = self._channels[subscription]
        take, write = subscription.handle.take_message, self._writer.write
        count = 0
        while count < self._depth:
            taken = take(cls, True)
            if taken is None:
                break
            if channel is None:
                channel = self._channel(subscription)
            data, info = taken
            received = info["received_timestamp"] or time.time_ns()  # 0: the middleware gave none
            write(channel, received, data, info["source_timestamp"] or received)
            count += 1
        if count:
            self._heard(subscription)
        return count

    def _heard(self, subscription) -> None:
        # once per subscription (its topic's name asked then only): a tool that starts a run
        # waits for these lines, so that its bag holds each stream from before the run (a
        # reader subscribed is not yet matched)
        if subscription not in self._heard_from:
            self._heard_from.add(subscription)
            self.get_logger().info(f"{HEARD_PREFIX}{subscription.topic_name}")

    def finish(self) -> None:
        """Finish the bag (once; later calls do nothing)."""
        if not hasattr(self, "_writer"):  # construction failed before the bag was opened
            return
        if self._writer.finished:
            return
        summary = self._writer.finish()
        counts = ", ".join(f"{t} {n}" for t, n in sorted(summary.counts.items()))
        self.get_logger().info(
            f"{FINISHED_PREFIX}{summary.folder} ({summary.message_count} messages"
            f"{': ' + counts if counts else ''})"
        )

    def destroy_node(self) -> None:
        self.finish()
        super().destroy_node()


def spin_until_expired(node: Recorder) -> None:
    """Spin the recorder in batches until shutdown or until ``duration`` has passed.

    An executor wakes the process and calls Python once per message, ~3000 times a second on
    the full graph; this loop (lean_spin.loop) waits on all subscriptions at once, drains
    every queue that has messages (Recorder.drain), runs the due timers and services (topic
    discovery, flushing, parameters), then sleeps BATCH_S so that the next wake-up finds a
    batch. The subscription queues (``queue_depth``) hold far more than BATCH_S of any stream.
    """
    from rclpy.executors import ExternalShutdownException

    try:
        lean_spin.loop(
            node.context,
            lambda: (list(node.subscriptions), list(node.timers), list(node.services)),
            on_ready=node.drain,
            keep_going=lambda: not node.expired,
            pause_s=BATCH_S,
        )
    finally:
        # the bag is finished here, before the teardown, whose timer must not cut a long
        # bag's summary short (ros/teardown.py)
        node.finish()
    if not node.expired:
        raise ExternalShutdownException()


def main(argv: list[str] | None = None) -> int:
    from hems_ros.ros.runner import run_node

    return run_node(Recorder, argv, spin=spin_until_expired, config_errors=(ValueError, OSError))


if __name__ == "__main__":
    raise SystemExit(main())
