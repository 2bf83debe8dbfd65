"""Whether a subscription's writers are alive, polled (the lean spin loop serves no waitables,
so the QoS event handler rclpy would add is replaced by a read of the same status)."""

from __future__ import annotations

from rclpy.event_handler import QoSSubscriptionEventType
from rclpy.impl.implementation_singleton import rclpy_implementation as _rclpy


class LivelinessWatch:
    """Polls the liveliness of the writers a subscription matched (its QoS sets the lease).

    Lost means: no matched writer alive, after one was (or while the middleware counts one not
    alive). On a loaded host Fast DDS now and then never reports a matched writer's liveliness
    at all, though its data arrive (about one reader in ten over graph starts here); such a
    writer is not judged (:attr:`established` stays False), and the data's own timeouts are
    then the only watch.
    """

    def __init__(self, subscription) -> None:
        with subscription.handle:
            self._event = _rclpy.EventHandle(
                subscription.handle, QoSSubscriptionEventType.RCL_SUBSCRIPTION_LIVELINESS_CHANGED
            )
        self._alive = True
        self.established = False  # a matched writer has been reported alive
        self.losses = 0  # alive -> lost transitions seen

    def alive(self) -> bool:
        """Not lost (see the class documentation)."""
        with self._event:
            status = self._event.take_event()
        if status is not None:
            self.established = self.established or status.alive_count > 0
            alive = status.alive_count > 0 or (not self.established and status.not_alive_count == 0)
            self.losses += self._alive and not alive
            self._alive = alive
        return self._alive

    @property
    def state(self) -> str:
        """For /diagnostics: alive, lost, or not reported (not judged)."""
        if not self._alive:
            return "lost"
        return "alive" if self.established else "not reported"

    def destroy(self) -> None:
        self._event.destroy_when_not_in_use()
