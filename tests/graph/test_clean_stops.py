"""Ctrl-C in a terminal (SIGINT to the whole process group) and SIGTERM stop `hems up` and
every node without a traceback, at any moment: while the nodes still load rclpy, while they
come up, and once the graph runs."""

from __future__ import annotations

import os
import signal
import subprocess
import time

import pytest

pytestmark = pytest.mark.slow


@pytest.mark.parametrize("after_s, group", [(1.0, True), (3.0, True), (12.0, True), (12.0, False)])
def test_a_signal_stops_hems_up_without_a_traceback(venv, after_s, group):
    up = subprocess.Popen(
        [str(venv / "bin" / "hems"), "up", "--separate", "--log-level", "warn"],
        stdout=subprocess.PIPE,
        stderr=subprocess.STDOUT,
        text=True,
        start_new_session=True,
    )
    try:
        time.sleep(after_s)
        if group:
            os.killpg(up.pid, signal.SIGINT)  # what a terminal's Ctrl-C sends
        else:
            up.send_signal(signal.SIGTERM)
        out, _ = up.communicate(timeout=60)
    finally:
        if up.poll() is None:
            os.killpg(up.pid, signal.SIGKILL)
            up.wait()
    assert "Traceback" not in out, out
    assert up.returncode in (0, 130, 143), out
    if after_s >= 12.0:
        assert "hems up: stopped 16 processes" in out, out
