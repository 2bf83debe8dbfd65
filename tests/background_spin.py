"""A test's own node spun in a daemon thread, every wait bounded
(hems_ros.ros.lean_spin.spin_on_executor): ``executor.spin`` waits without a timeout, and a
lost wake-up would leave the test's teardown waiting on a node the thread still holds."""

from __future__ import annotations

import contextlib
import threading


class BackgroundSpin:
    def __init__(self, node) -> None:
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._spin, args=(node,), daemon=True)
        self._thread.start()

    def _spin(self, node) -> None:
        from rclpy.executors import ExternalShutdownException, SingleThreadedExecutor

        from hems_ros.ros import lean_spin

        with contextlib.suppress(ExternalShutdownException):
            lean_spin.spin_on_executor(
                [node],
                SingleThreadedExecutor(context=node.context),
                keep_going=lambda: not self._stop.is_set(),
            )

    def stop(self) -> None:
        """Ends the spinning within one wait; the executor is shut down with it."""
        self._stop.set()
        self._thread.join(timeout=5)
        if self._thread.is_alive():
            raise RuntimeError("the background spin did not end within 5 s of its stop")
