"""Stopping child processes: the one place that signals, waits and, past the grace, kills."""

from __future__ import annotations

import signal
import subprocess
import time
from collections.abc import Iterable


def stop_processes(
    processes: Iterable[subprocess.Popen], grace_s: float = 2.5, signum: int = signal.SIGTERM
) -> list[subprocess.Popen]:
    """Send ``signum`` to every child still running, wait for all of them together for at most
    ``grace_s``, SIGKILL the rest; return the ones that had to be killed.

    SIGTERM by default, not SIGINT: a running node stops on either (rclpy's handler), but a
    process still loading Python ends on SIGTERM without an import traceback, and a background
    job of a non-interactive shell ignores SIGINT until rclpy installs its handler."""
    processes = list(processes)
    for process in processes:
        if process.poll() is None:
            process.send_signal(signum)
    deadline = time.monotonic() + grace_s
    killed = []
    for process in processes:
        try:
            process.wait(max(0.0, deadline - time.monotonic()))
        except subprocess.TimeoutExpired:
            process.kill()
            process.wait()
            killed.append(process)
    return killed


def stop_process(
    process: subprocess.Popen, grace_s: float = 5.0, signum: int = signal.SIGTERM
) -> int:
    """:func:`stop_processes` for one child; its exit code."""
    stop_processes([process], grace_s, signum)
    return process.returncode


def exit_description(code: int) -> str:
    """How a child ended, for a message: 'with code 2', or 'killed by SIGSEGV' for a negative
    return code (Popen's way of saying that signal ended it)."""
    if code >= 0:
        return f"with code {code}"
    try:
        return f"killed by {signal.Signals(-code).name}"
    except ValueError:
        return f"killed by signal {-code}"
