"""Fixtures of the node tests."""

from __future__ import annotations

import pytest


@pytest.fixture
def context(ros_domain_id):
    """An rclpy context of its own for in-process nodes, shut down after the test."""
    import rclpy
    from rclpy.context import Context

    context = Context()
    rclpy.init(context=context)
    yield context
    rclpy.try_shutdown(
        context=context
    )  # a test that spins on a thread shuts it down to stop the loop


@pytest.fixture
def matched_publisher():
    """publisher(node, msg_type, topic, qos): a publisher whose subscriber under test is
    discovered, so a message published next is not lost to discovery."""
    import time

    def make(node, msg_type, topic: str, qos_profile):
        publisher = node.create_publisher(msg_type, topic, qos_profile)
        deadline = time.monotonic() + 10.0
        while publisher.get_subscription_count() < 1:
            assert time.monotonic() < deadline, f"no subscription to {topic} was discovered"
            time.sleep(0.05)
        return publisher

    return make


@pytest.fixture
def one_round(context):
    """one_round(node): wait once on ``node``'s subscriptions and timers in the nodes' spin
    loop (hems_ros.ros.lean_spin) and run what is ready, as a node process does."""
    from hems_ros.ros import lean_spin

    def run(node) -> None:
        rounds = iter([True])
        lean_spin.loop(
            context,
            lambda: (list(node.subscriptions), list(node.timers), []),
            keep_going=lambda: next(rounds, False),
        )

    return run
