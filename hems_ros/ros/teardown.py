"""Leaving ROS within a bounded time.

Fast DDS 3.2 can wedge a process in the destruction of its participant: the destroying thread
busy-waits for the participant's discovery callback to return, and that callback (a reader
just discovered) waits on a mutex and never does. The process then spins a core for good,
holding the GIL, so no Python code of its own runs again (seen in a `hems wait` that
the launcher stopped: 3 minutes at 93 % of a core, its stack in
``DomainParticipant::set_listener`` under ``rmw_destroy_node``; Fast DDS's report
"DomainParticipantImpl::set_listener busy-spins with its default infinite timeout" describes the
busy wait). A timer signal with its default action ends such a process after
``TEARDOWN_S``, GIL or not. It leaves its Fast DDS files behind as a killed process does;
``hems up`` removes those at its next start (hems_ros/fastdds_files.py).
"""

from __future__ import annotations

import signal
import threading
from collections.abc import Iterable
from typing import Any

#: Longer than any teardown seen (well under a second with sixteen nodes in one process).
TEARDOWN_S = 5.0


def end_ros(nodes: Iterable[Any]) -> None:
    """Destroy ``nodes`` and shut rclpy down; a process still at it after ``TEARDOWN_S`` is
    ended by SIGALRM (exit status 142 in a shell)."""
    import rclpy  # imported by the caller already; not at module level, as in ros/runner.py

    armed = threading.current_thread() is threading.main_thread()
    if armed:  # only the main thread may set a signal's handler
        previous = signal.signal(signal.SIGALRM, signal.SIG_DFL)
        signal.setitimer(signal.ITIMER_REAL, TEARDOWN_S)
    try:
        for node in nodes:
            node.destroy_node()
        rclpy.try_shutdown()
    finally:
        if armed:
            signal.setitimer(signal.ITIMER_REAL, 0.0)
            if previous is not None:  # None: a handler set outside Python, left as it is
                signal.signal(signal.SIGALRM, previous)
