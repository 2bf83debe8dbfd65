"""The composed graph's process runs every thread on the short scheduler slice; a node in a
process of its own keeps the kernel's default (hems_ros.ros.short_slice). On a kernel
without per-thread slices (before Linux 6.12) there is nothing to check."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import time

import pytest

from hems_ros.launcher import executable_path
from hems_ros.ros.short_slice import SLICE_S, current_slice_s
from hems_ros.rosenv import child_environment

DEFAULT_SLICE_S = current_slice_s()
pytestmark = pytest.mark.skipif(
    not DEFAULT_SLICE_S, reason="this kernel keeps no per-thread slice (Linux 6.12+)"
)


def thread_slices(pid: int) -> dict[int, float | None]:
    return {int(tid): current_slice_s(int(tid)) for tid in os.listdir(f"/proc/{pid}/task")}


def settled(process: subprocess.Popen, ready) -> dict[int, float | None]:
    """The process's threads' slices once ``ready(slices)`` holds (its middleware started)."""
    deadline = time.monotonic() + 30.0
    while True:
        assert process.poll() is None, process.stderr.read()
        slices = thread_slices(process.pid)
        if ready(slices):
            return slices
        assert time.monotonic() < deadline, f"thread slices after 30 s: {slices}"
        time.sleep(0.2)


def stop(process: subprocess.Popen) -> None:
    process.send_signal(signal.SIGINT)
    assert process.wait(timeout=10) == 0


def test_a_request_sets_the_slice_of_the_thread_and_its_children() -> None:
    code = (
        "import subprocess, sys; from hems_ros.ros import short_slice as s;"
        "assert s.request_short_slice();"
        "print(s.current_slice_s());"
        "subprocess.run([sys.executable, '-c', 'from hems_ros.ros import short_slice as s;"
        "print(s.current_slice_s())'], check=True)"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert [float(v) for v in out.stdout.split()] == pytest.approx([SLICE_S, SLICE_S])
    assert DEFAULT_SLICE_S > 5 * SLICE_S  # this process did not ask


def test_every_thread_of_the_composed_process_runs_on_the_short_slice(ros_domain_id) -> None:
    process = subprocess.Popen(
        [sys.executable, "-m", "hems_ros.nodes.composed", "supervisor:supervisor:fingers=[index]"]
        + ["--ros-args", "--log-level", "warn"],
        env=child_environment(),
        stderr=subprocess.PIPE,
        text=True,
    )
    try:
        slices = settled(process, lambda s: len(s) > 4)  # rclpy's and Fast DDS's threads
        assert list(slices.values()) == [pytest.approx(SLICE_S)] * len(slices), slices
    finally:
        stop(process)


def test_a_node_process_of_its_own_keeps_the_default_slice(ros_domain_id) -> None:
    process = subprocess.Popen(
        executable_path("shoulder_module") + ["--ros-args", "--log-level", "warn"],
        env=child_environment(),
        stderr=subprocess.PIPE,
        text=True,
    )
    try:
        slices = settled(process, lambda s: len(s) > 4)
        assert slices[process.pid] == pytest.approx(DEFAULT_SLICE_S)
    finally:
        stop(process)
