"""An rclpy executor spun in a daemon thread for a test's own nodes, every wait bounded.

``executor.spin`` waits without a timeout, and now and then the wake-up that should end such
a wait is lost (hems_ros.ros.lean_spin.spin_on_executor): the test's teardown then waits on
a node that the spinning thread still holds. Waits of 50 ms let the thread see its stop."""

from __future__ import annotations

import threading

WAIT_S = 0.05


class BackgroundSpin:
    def __init__(self, executor) -> None:
        self.executor = executor
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._spin, daemon=True)
        self._thread.start()

    def _spin(self) -> None:
        while not self._stop.is_set() and self.executor.context.ok():
            self.executor.spin_once(timeout_sec=WAIT_S)

    def stop(self) -> None:
        """Ends the spinning (within one wait) and shuts the executor down."""
        self._stop.set()
        self._thread.join(timeout=5)
        self.executor.shutdown()
