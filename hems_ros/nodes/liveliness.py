"""Whether a subscription's writers are alive, polled (the lean spin loop serves no waitables,
so the QoS event handler rclpy would add is replaced by a read of the same status)."""

from __future__ import annotations

from rclpy.event_handler import QoSSubscriptionEventType
from rclpy.impl.implementation_singleton import rclpy_implementation as _rclpy


class LivelinessWatch:
    """Polls the liveliness of the writers a subscription matched (its QoS sets the lease)."""

    def __init__(self, subscription) -> None:
        with subscription.handle:
            self._event = _rclpy.EventHandle(
                subscription.handle, QoSSubscriptionEventType.RCL_SUBSCRIPTION_LIVELINESS_CHANGED)
        self._alive = False
        self.losses = 0       # alive -> not alive transitions seen

    def alive(self) -> bool:
        """At least one matched writer asserted its liveliness within the lease."""
        with self._event:
            status = self._event.take_event()
        if status is not None:
            alive = status.alive_count > 0
            self.losses += self._alive and not alive
            self._alive = alive
        return self._alive

    def destroy(self) -> None:
        self._event.destroy_when_not_in_use()
