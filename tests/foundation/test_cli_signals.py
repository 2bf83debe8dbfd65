"""A `hems` verb talking to the graph stops cleanly on Ctrl-C and SIGTERM.

rclpy's own handler shuts its context down on SIGTERM, after which the next spin call failed
in whatever rcl object it created (an RCLError traceback, exit code 1, e.g. from `hems demo`
in the middle of a grasp). Waiting for a controller that is not there keeps the verb spinning
without starting a graph.
"""

from __future__ import annotations

import select
import signal
import subprocess
import sys

import pytest

from hems_ros.rosenv import child_environment


@pytest.mark.parametrize(
    "signal_name, code, message",
    [
        ("SIGTERM", 143, "hems setpoint: stopped by SIGTERM"),
        ("SIGINT", 130, "hems setpoint: interrupted"),
    ],
)
def test_a_waiting_verb_stops_cleanly(
    ros_domain_id: int, signal_name: str, code: int, message: str
) -> None:
    verb = subprocess.Popen(
        [
            sys.executable,
            "-m",
            "hems_ros.cli.main",
            "setpoint",
            "index",
            "10",
            "--unit",
            "mm",
            "--timeout",
            "60",
        ],
        env=child_environment(),
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )
    try:
        # the progress line says it is spinning, waiting for a controller: the signal then
        # comes in the wait, however long the imports took on a busy host
        assert verb.stderr is not None
        ready, _, _ = select.select([verb.stderr], [], [], 60.0)
        first = verb.stderr.readline() if ready else ""
        assert first.startswith("setpoint: waiting for the graph"), first
        assert verb.poll() is None
        verb.send_signal(getattr(signal, signal_name))
        _, err = verb.communicate(timeout=20)
    finally:
        if verb.poll() is None:
            verb.kill()
    assert verb.returncode == code, err
    assert err.strip().splitlines()[-1] == message
    assert "Traceback" not in err


# a signal that shuts the context down while a verb's node is being made: rclpy's handler
# runs between two calls of Node's constructor, whose next call then fails on the dead context
MID_CONSTRUCTION = """
import rclpy
from rclpy.executors import ExternalShutdownException
from hems_ros.client import graph_client
from hems_ros.ros.lean_node import LeanNode

def node_cut_short(*args, **kwargs):
    rclpy.shutdown()
    return LeanNode(*args, **kwargs)

graph_client.LeanNode = node_cut_short
try:
    graph_client.GraphClient("hems_test_signal")
except ExternalShutdownException:
    print("stopped")
"""


def test_a_signal_while_a_verbs_node_is_made_is_a_stop_not_a_crash(ros_domain_id: int) -> None:
    done = subprocess.run(
        [sys.executable, "-c", MID_CONSTRUCTION],
        env=child_environment(),
        capture_output=True,
        text=True,
        timeout=60,
    )
    assert done.returncode == 0, done.stderr
    assert done.stdout.split() == ["stopped"], done.stdout + done.stderr
