"""A Node whose publishers and subscriptions carry no QoS event handlers unless asked,
which reads serialized messages without letting a malformed one stop it, and which can take
messages it does not need at once when it wakes for something else.

rclpy gives every publisher and subscription default handlers for QoS events; each is a
waitable that the executor re-adds to its wait set on every wake-up, in Python. The graph's
nodes wake a few hundred times a second, and these handlers were most of that cost.
"""

from __future__ import annotations

import functools
import time
from collections.abc import Callable
from typing import Any

from rcl_interfaces.msg import SetParametersResult
from rclpy.event_handler import PublisherEventCallbacks, SubscriptionEventCallbacks
from rclpy.node import Node

from hems_ros.codec.cdr import CdrError
from hems_ros.ros import lean_spin
from hems_ros.ros.wire import codec


class LeanNode(Node):
    def __init_subclass__(cls, **kwargs) -> None:
        """A node whose ``__init__`` raises (an invalid parameter) is destroyed before the
        error leaves it: left to the garbage collector, its handle was finalized at any later
        moment, once inside Fast DDS while another node's participant was busy, and hung."""
        super().__init_subclass__(**kwargs)
        init = cls.__init__

        @functools.wraps(init)
        def init_or_destroy(self, *args, **kwargs) -> None:
            try:
                init(self, *args, **kwargs)
            except BaseException:
                if getattr(self, "_LeanNode__created", False):
                    # the subclass's destroy_node expects what its __init__ did not get to
                    Node.destroy_node(self)
                    self.__created = False
                raise

        cls.__init__ = init_or_destroy  # type: ignore[method-assign]

    def __init__(self, *args, **kwargs) -> None:
        super().__init__(*args, **kwargs)
        self.__created = True
        self._unreadable_logged: dict[str, float] = {}
        self.polled: frozenset = frozenset()
        # on the system clock (not /clock): messages may count from their reception times
        self.wall_clock = not self.get_parameter("use_sim_time").value
        self.add_on_set_parameters_callback(self._keep_clock)

    def _keep_clock(self, parameters) -> SetParametersResult:
        """The clock is chosen at start-up: timers on the clock's grid, reception times and
        clock reads all follow it, so a change while running is refused, not half applied."""
        for parameter in parameters:
            if parameter.name == "use_sim_time" and parameter.value == self.wall_clock:
                return SetParametersResult(
                    successful=False,
                    reason="use_sim_time is read at start-up: restart the node with "
                    f"-p use_sim_time:={str(parameter.value).lower()} to change it",
                )
        return SetParametersResult(successful=True)

    def poll(self, *subscriptions) -> None:
        """Leave these subscriptions out of lean_spin's wait set from now on: the node drains
        them itself (:meth:`drain`). In separate processes each wake-up of a sleeping node
        costs far more CPU than the message it brings (benchmarks/bench_messages.py), so a
        stream the node only needs now and then should not wake it."""
        if frozenset(subscriptions) != self.polled:
            self.polled = frozenset(subscriptions)
            lean_spin.polled_changed()

    def drain(
        self,
        subscription,
        with_reception_time: bool = False,
        at: float | Callable[[Any], float] | None = None,
    ) -> None:
        """Run ``subscription``'s callback on every message queued for it, oldest first.

        ``with_reception_time``: the callback also gets the time the middleware received the
        message (s, system clock, the ROS clock without sim time): when the node took it, at
        its own convenience, says nothing about when it came. ``at``: the callback gets this
        time instead, or this function of the message (a lockstep clock says when a message
        counts as received)."""
        with subscription.handle:
            while (
                taken := subscription.handle.take_message(subscription.msg_type, subscription.raw)
            ) is not None:
                if callable(at):
                    subscription.callback(taken[0], at(taken[0]))
                elif at is not None:
                    subscription.callback(taken[0], at)
                elif with_reception_time:
                    subscription.callback(taken[0], taken[1]["received_timestamp"] * 1e-9)
                else:
                    subscription.callback(taken[0])

    def drain_in_order(self, *subscriptions) -> None:
        """:meth:`drain` of several subscriptions at once, every callback with the message's
        reception time (s, system clock), in the order the middleware received the messages:
        a node that takes what came since its last wake-up applies it as it came."""
        taken = []
        for rank, subscription in enumerate(subscriptions):
            with subscription.handle:
                while (
                    message := subscription.handle.take_message(
                        subscription.msg_type, subscription.raw
                    )
                ) is not None:
                    received_ns = message[1]["received_timestamp"]
                    taken.append((received_ns, rank, subscription.callback, message[0]))
        taken.sort(key=lambda entry: entry[:2])
        for received_ns, _, callback, message in taken:
            callback(message, received_ns * 1e-9)

    def create_publisher(self, *args, event_callbacks=None, **kwargs):
        return super().create_publisher(
            *args,
            event_callbacks=event_callbacks or PublisherEventCallbacks(use_default_callbacks=False),
            **kwargs,
        )

    def create_subscription(self, *args, event_callbacks=None, **kwargs):
        return super().create_subscription(
            *args,
            event_callbacks=event_callbacks
            or SubscriptionEventCallbacks(use_default_callbacks=False),
            **kwargs,
        )

    def subscribe_serialized(self, msg_type, topic: str, callback, qos_profile, on_unreadable=None):
        """Subscribe to ``topic`` taking serialized messages (hems_ros.ros.wire): ``callback``
        gets the message as the type's named tuple. A message that cannot be read (a raw
        publisher can send any bytes on a typed topic) is logged, at most once a second per
        topic so a bad stream neither floods the log nor hides another topic's, and dropped;
        ``on_unreadable()`` then runs if given. Arguments after the data (the reception time
        of :meth:`drain`) pass on to both."""
        decode = codec(msg_type).decode

        def on_data(data: bytes, *received) -> None:
            try:
                message = decode(data)
            except CdrError as error:
                now = time.monotonic()
                if now - self._unreadable_logged.get(topic, float("-inf")) >= 1.0:
                    self._unreadable_logged[topic] = now
                    self.get_logger().error(f"unreadable message on {topic} dropped: {error}")
                if on_unreadable is not None:
                    on_unreadable(*received)
                return
            callback(message, *received)

        return self.create_subscription(msg_type, topic, on_data, qos_profile, raw=True)
