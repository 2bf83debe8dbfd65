"""A Node whose publishers and subscriptions carry no QoS event handlers unless asked.

rclpy gives every publisher and subscription default handlers for QoS events; each is a
waitable that the executor re-adds to its wait set on every wake-up, in Python. The graph's
nodes wake a few hundred times a second, and these handlers were most of that cost.
"""

from __future__ import annotations

from rclpy.event_handler import PublisherEventCallbacks, SubscriptionEventCallbacks
from rclpy.node import Node


class LeanNode(Node):
    def create_publisher(self, *args, event_callbacks=None, **kwargs):
        return super().create_publisher(
            *args, event_callbacks=event_callbacks or PublisherEventCallbacks(use_default_callbacks=False), **kwargs)

    def create_subscription(self, *args, event_callbacks=None, **kwargs):
        return super().create_subscription(
            *args, event_callbacks=event_callbacks or SubscriptionEventCallbacks(use_default_callbacks=False),
            **kwargs)
