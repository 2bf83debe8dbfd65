"""A node process runs Fast DDS's listener and event threads under SCHED_BATCH (they do not
preempt the sender of the message they wake for) and its own main thread under the default
policy (hems_ros.ros.middleware_threads)."""

from __future__ import annotations

import os
import signal
import subprocess
import time

from hems_ros.launcher import executable_path
from hems_ros.ros.middleware_threads import THREAD_PREFIXES
from hems_ros.rosenv import child_environment


def thread_policies(pid: int) -> dict[str, int]:
    policies = {}
    for tid in os.listdir(f"/proc/{pid}/task"):
        try:
            with open(f"/proc/{pid}/task/{tid}/comm") as comm:
                name = "main" if int(tid) == pid else comm.read().strip()
            policies[f"{name}/{tid}"] = os.sched_getscheduler(int(tid))
        except OSError:
            continue
    return policies


def test_a_node_process_defers_its_middleware_threads_only(ros_domain_id):
    process = subprocess.Popen(
        executable_path("shoulder_module") + ["--ros-args", "--log-level", "warn"],
        env=child_environment(),
        stderr=subprocess.PIPE,
        text=True,
    )
    try:
        deadline = time.monotonic() + 30.0
        while True:
            assert process.poll() is None, process.stderr.read()
            policies = thread_policies(process.pid)
            middleware = {k: v for k, v in policies.items() if k.startswith(THREAD_PREFIXES)}
            if middleware and all(v == os.SCHED_BATCH for v in middleware.values()):
                break
            assert time.monotonic() < deadline, f"thread policies after 30 s: {policies}"
            time.sleep(0.2)
        assert any(k.startswith("dds.shm.") for k in middleware) and any(
            k.startswith("dds.ev.") for k in middleware
        )
        assert policies[f"main/{process.pid}"] == os.SCHED_OTHER
    finally:
        process.send_signal(signal.SIGINT)
        assert process.wait(timeout=10) == 0
