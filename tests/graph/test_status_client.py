"""`hems status` hears a running supervisor even when discovery is slower than its listen."""

from __future__ import annotations

import subprocess
import time


def test_snapshot_waits_for_the_supervisor_beyond_its_listen_time(venv, ros_domain_id):
    from hems_ros.cli.graph_client import GraphClient

    supervisor = subprocess.Popen([str(venv / "bin" / "python"), "-m", "hems_ros.nodes.supervisor"],
                                  stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    try:
        with GraphClient("hems_status_test") as client:
            start = time.monotonic()
            # no listen at all: only the wait for the supervisor can find it
            snap = client.snapshot(fingers=("index",), seconds=0.0, supervisor_wait_s=30.0)
            elapsed = time.monotonic() - start
        assert snap.supervisor is not None and snap.supervisor.state_name == "IDLE"
        assert elapsed < 30.0
        assert snap.controllers == {}
    finally:
        supervisor.terminate()
        supervisor.wait(timeout=10)
