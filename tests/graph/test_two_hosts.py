"""The graph across two hosts: two network namespaces joined by a veth pair, created here and
removed afterwards. The index finger's actuation unit and shoulder module run in one, its
controller and the supervisor in the other; DDS discovery stays on loopback plus the one peer
address across the link (ROS_AUTOMATIC_DISCOVERY_RANGE=LOCALHOST, ROS_STATIC_PEERS), so no
traffic leaves the namespaces. A step and an e-stop pass across, and the unit's duty-command
latency is compared with the same graph inside one namespace: the difference is what the link
adds.
"""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import pytest
from netns import two_namespaces

from hems_ros.launcher import Graph, GraphOptions, warm_physics_cache
from hems_ros.processes import stop_processes
from hems_ros.rosenv import child_environment

pytestmark = [pytest.mark.slow]

CLIENT = Path(__file__).with_name("two_hosts_client.py")
SIDE_A = ("actuation_unit_index", "shoulder_module_index_middle")
ADDRESS = {"a": "10.231.0.1", "b": "10.231.0.2"}


@pytest.fixture
def namespaces():
    with two_namespaces("hems", ADDRESS) as ns:
        yield ns


def _run(ns: dict[str, str], split: bool) -> dict:
    """Start the index graph (split across the namespaces, or all in ``a``), run the client in
    the supervisor's namespace, stop everything; the client's JSON."""
    graph = Graph(GraphOptions(fingers=("index",), composed=False, log_level="error"))
    warm_physics_cache(child_environment())
    side_of = {name: ("a" if name in SIDE_A or not split else "b") for name in graph.commands()}
    processes = []
    try:
        for name, command in graph.commands().items():
            side = side_of[name]
            peer = ADDRESS["b" if side == "a" else "a"]
            env = child_environment({"ROS_STATIC_PEERS": peer if split else ""})
            processes.append(
                subprocess.Popen(
                    ["ip", "netns", "exec", ns[side], *command], env=env, process_group=0
                )
            )
        client_side = side_of["supervisor"]
        env = child_environment({"ROS_STATIC_PEERS": ADDRESS["a"] if split else ""})
        done = subprocess.run(
            ["ip", "netns", "exec", ns[client_side], sys.executable, str(CLIENT)],
            env=env,
            capture_output=True,
            text=True,
            timeout=180,
        )
        assert done.returncode == 0, done.stdout + done.stderr[-2000:]
        return json.loads(done.stdout.strip().splitlines()[-1])
    finally:
        stop_processes(processes, 5.0)


def test_step_and_estop_across_two_namespaces(namespaces):
    one = _run(namespaces, split=False)
    two = _run(namespaces, split=True)
    added_ms = 1e3 * (two["latency_p50_s"] - one["latency_p50_s"])
    print(
        f"duty-command latency p50: {1e3 * one['latency_p50_s']:.2f} ms in one namespace, "
        f"{1e3 * two['latency_p50_s']:.2f} ms across the link (added {added_ms:+.2f} ms); "
        f"p99 {1e3 * one['latency_p99_s']:.2f} / {1e3 * two['latency_p99_s']:.2f} ms; e-stop to "
        f"zero duty {1e3 * two['estop_zero_duty_s']:.0f} ms across"
    )
    for run in (one, two):
        assert run["setpoint_taken"] and run["reached_s"] is not None, run
        assert run["heated_before_estop"] and not run["heated_after"], run
        assert run["estop_zero_duty_s"] is not None and run["estop_zero_duty_s"] < 0.3, run
    # a veth link inside one host adds less than a control period
    assert added_ms < 10.0
