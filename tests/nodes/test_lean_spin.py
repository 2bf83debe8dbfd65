"""The nodes' spin loop (hems_ros/ros/lean_spin.py) against a regular rclpy node over DDS."""

from __future__ import annotations

import threading
import time
from contextlib import contextmanager

import pytest


@contextmanager
def spun(name: str, build):
    """A LeanNode ``name``, given its entities by ``build(node)``, spinning in lean_spin on a
    thread of its own context, and a peer node with an executor in another context.
    Yields (node, peer, executor, stopped); ``stopped`` gets True when the spin ends on the
    context's shutdown."""
    import rclpy
    from rclpy.context import Context
    from rclpy.executors import ExternalShutdownException, SingleThreadedExecutor
    from rclpy.node import Node

    from hems_ros.ros import lean_spin
    from hems_ros.ros.lean_node import LeanNode

    served, other = Context(), Context()
    rclpy.init(context=served)
    rclpy.init(context=other)
    node = LeanNode(name, context=served)
    build(node)
    assert lean_spin.can_spin(node)
    stopped = []

    def run() -> None:
        try:
            lean_spin.spin(node)
        except ExternalShutdownException:
            stopped.append(True)

    thread = threading.Thread(target=run)
    thread.start()
    peer = Node(name + "_peer", context=other)
    executor = SingleThreadedExecutor(context=other)
    executor.add_node(peer)
    try:
        yield node, peer, executor, stopped
    finally:
        rclpy.shutdown(context=served)
        thread.join(timeout=5)
        executor.shutdown()
        peer.destroy_node()
        node.destroy_node()
        rclpy.try_shutdown(context=other)
    assert not thread.is_alive()


def answer(executor, call):
    """The response to ``call()`` (a future), asked up to three times: a response sent before
    the service has matched the client's response reader is dropped by the middleware
    ("failed to send response (timeout)"), and wait_for_service sees only the request side."""
    for _ in range(3):
        future = call()
        executor.spin_until_future_complete(future, timeout_sec=5)
        if future.result() is not None:
            return future.result()
    return None


def test_lean_spin_runs_timers_subscriptions_and_services_and_stops_on_shutdown(
    ros_domain_id: int,
) -> None:
    from std_msgs.msg import Int32
    from std_srvs.srv import Trigger

    ticks, received = [], []

    def count(request, response):
        response.success, response.message = True, f"{len(received)} received"
        return response

    def build(node) -> None:
        node.create_timer(0.01, lambda: ticks.append(time.monotonic()))
        node.create_subscription(
            Int32, "/lean_spin_test/numbers", lambda m: received.append(m.data), 10
        )
        node.create_service(Trigger, "/lean_spin_test/count", count)

    with spun("lean_spin_test", build) as (node, peer, executor, stopped):
        publisher = peer.create_publisher(Int32, "/lean_spin_test/numbers", 10)
        client = peer.create_client(Trigger, "/lean_spin_test/count")
        assert client.wait_for_service(timeout_sec=10)
        deadline = time.monotonic() + 10
        while publisher.get_subscription_count() == 0 and time.monotonic() < deadline:
            time.sleep(0.01)
        for k in range(5):
            publisher.publish(Int32(data=k))
        deadline = time.monotonic() + 10
        while len(received) < 5 and time.monotonic() < deadline:
            time.sleep(0.01)
        response = answer(executor, lambda: client.call_async(Trigger.Request()))
        assert response is not None and response.message == "5 received"
        assert received == [0, 1, 2, 3, 4]
        deadline = time.monotonic() + 10
        while len(ticks) <= 10 and time.monotonic() < deadline:  # all of that can take under 30 ms
            time.sleep(0.01)
        spacing = sorted(b - a for a, b in zip(ticks, ticks[1:]))
        assert len(ticks) > 10 and 0.008 < spacing[len(spacing) // 2] < 0.012  # the 10 ms timer
    assert stopped == [True]


def test_nodes_with_clients_are_left_to_rclpy(ros_domain_id: int) -> None:
    import rclpy
    from rclpy.context import Context
    from std_srvs.srv import Trigger

    from hems_ros.ros import lean_spin
    from hems_ros.ros.lean_node import LeanNode

    context = Context()
    rclpy.init(context=context)
    node = LeanNode("lean_spin_client_test", context=context)
    try:
        node.create_client(Trigger, "/lean_spin_test/nothing")
        assert not lean_spin.can_spin(node)
        with pytest.raises(ValueError, match="use spin_on_executor"):
            lean_spin.spin(node)
    finally:
        node.destroy_node()
        rclpy.try_shutdown(context=context)


def test_lean_spin_serves_the_parameter_services(ros_domain_id: int) -> None:
    """They are served between wake-ups instead of from the wait set: `ros2 param` still works."""
    from rclpy.parameter import Parameter
    from rclpy.parameter_client import AsyncParameterClient

    def build(node) -> None:
        node.declare_parameter("gain", 0.5)
        node.create_timer(0.01, lambda: None)

    with spun("lean_param_test", build) as (node, peer, executor, _):
        client = AsyncParameterClient(peer, "lean_param_test")
        assert client.wait_for_services(timeout_sec=10)
        got = answer(executor, lambda: client.get_parameters(["gain"]))
        assert got is not None and got.values[0].double_value == 0.5
        done = answer(executor, lambda: client.set_parameters([Parameter("gain", value=0.8)]))
        assert done is not None and done.results[0].successful
        assert node.get_parameter("gain").value == 0.8


def test_a_queued_message_runs_before_a_timer_ready_at_the_same_wake_up(
    context, matched_publisher, one_round
) -> None:
    import rclpy
    from std_msgs.msg import Int32

    from hems_ros.ros.lean_node import LeanNode

    order = []
    node = LeanNode("lean_spin_order", context=context)
    helper = rclpy.create_node("lean_spin_order_sender", context=context)
    try:
        node.create_timer(0.05, lambda: order.append("timer"))
        node.create_subscription(
            Int32, "/lean_spin_order/numbers", lambda m: order.append(f"message {m.data}"), 10
        )
        publisher = matched_publisher(helper, Int32, "/lean_spin_order/numbers", 10)
        publisher.publish(Int32(data=1))
        time.sleep(0.2)  # the node is not spun: the timer expires while the message waits
        one_round(node)
        assert order == ["message 1", "timer"]
    finally:
        helper.destroy_node()
        node.destroy_node()


@pytest.mark.parametrize("bounded", [True, False], ids=["bounded", "unbounded"])
def test_a_node_on_an_executor_stops_even_if_the_shutdown_wake_up_is_lost(
    ros_domain_id: int, bounded: bool
) -> None:
    """The context is shut down beneath rclpy (through its handle), so neither the signal
    guard condition nor the executor's on-shutdown wake fires, as when rclpy loses that
    wake-up: spin_on_executor returns within a few wait timeouts; an unbounded wait does not."""
    import rclpy
    from rclpy.context import Context
    from rclpy.executors import ExternalShutdownException, SingleThreadedExecutor
    from rclpy.node import Node
    from std_msgs.msg import Empty

    from hems_ros.ros import lean_spin

    context = Context()
    rclpy.init(context=context)
    node = Node("executor_stop_test", context=context)
    node.create_subscription(Empty, "/executor_stop_test/in", lambda _: None, 1)
    executor = SingleThreadedExecutor(context=context)
    ended = threading.Event()

    def run() -> None:
        try:
            if bounded:
                lean_spin.spin_on_executor([node], executor)
            else:
                executor.add_node(node)
                executor.spin_once(timeout_sec=None)
        except ExternalShutdownException:
            ended.set()

    thread = threading.Thread(target=run, daemon=True)
    thread.start()
    time.sleep(0.5)
    shut = time.monotonic()
    context.handle.shutdown()
    try:
        if bounded:
            assert ended.wait(5.0)
            assert time.monotonic() - shut < 1.0
        else:
            assert not ended.wait(1.0)
            executor.wake()  # what rclpy's lost wake-up would have done
            assert ended.wait(5.0)
    finally:
        thread.join(5.0)
        executor.shutdown()
        node.destroy_node()
