"""Recording topics in the test process while a graph runs."""

from __future__ import annotations

import threading
import time
from collections import defaultdict


class Recorder:
    """Collects messages of chosen topics in a background spin of the test's own node."""

    def __init__(self, client) -> None:
        self.client = client
        self.messages = defaultdict(list)  # topic -> [(receive wall time, message)]
        self.lock = threading.Lock()

    def listen(self, msg_type, topic: str, qos) -> None:
        def store(message, topic=topic):
            with self.lock:
                self.messages[topic].append((time.time(), message))

        self.client.node.create_subscription(msg_type, topic, store, qos)

    def since(self, topic: str, t0: float) -> list:
        with self.lock:
            return [(t, m) for t, m in self.messages[topic] if t >= t0]

    def spin(self, seconds: float) -> None:
        self.client.spin_for(seconds)
