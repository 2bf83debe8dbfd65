"""`hems up --composed`: the nodes in one process on one thread (lean_spin.spin_nodes) track a
position step as the separate processes do, and Ctrl-C ends the process within 3 s.

One finger (actuation unit, shoulder module, controller, supervisor) keeps it in the default
run; the full composed graph is measured by benchmarks/bench_graph.py.
"""

from __future__ import annotations

import signal
import time

import numpy as np
import pytest
from hems_msgs.msg import EncoderReading, SupervisorStatus
from recording import Recorder

from hems_ros.graph import names, transmission
from hems_ros.ros import qos
from hems_ros.ros.clock_time import from_msg

pytestmark = pytest.mark.slow

FINGER = "index"


def test_composed_graph_tracks_a_step_and_stops_on_ctrl_c(ros_domain_id: int) -> None:
    from hems_ros.client.graph_client import GraphClient
    from hems_ros.launcher import Graph, GraphOptions

    graph = Graph(GraphOptions(fingers=(FINGER,), log_level="warn"))
    graph.start()
    assert list(graph.processes) == ["composed"]
    try:
        with GraphClient("hems_test_composed") as client:
            rec = Recorder(client)
            rec.listen(EncoderReading, names.topic(FINGER, "encoder"), qos.SENSOR)
            rec.listen(SupervisorStatus, names.SUPERVISOR_STATUS_TOPIC, qos.STATUS)
            ok, message = client.enable_when_ready(60, reset=True, retry_s=0.5)
            assert ok, message
            t0 = time.time()
            assert client.send_setpoint(FINGER, "position", 0.020)
            rec.spin(4.5)
            samples = [
                (from_msg(m.header.stamp) - t0, transmission.tendon_position(m.position))
                for _, m in rec.since(names.topic(FINGER, "encoder"), t0)
            ]
            states = [m.state_name for _, m in rec.since(names.SUPERVISOR_STATUS_TOPIC, t0 - 10)]
        assert not graph.exited(), graph.exited()
        t = np.array([s[0] for s in samples])
        x = np.array([s[1] for s in samples])
        assert len(x) > 400, f"only {len(x)} encoder samples in 4.5 s (100 Hz expected)"
        assert "FAULT" not in states, states
        late = t >= 3.0
        assert np.all(
            np.abs(x[late] - 0.020) <= 1e-4
        ), f"{1e3 * x[late].min():.3f}-{1e3 * x[late].max():.3f} mm"
        assert x.max() <= 0.020 + 1e-4, f"overshoot to {1e3 * x.max():.3f} mm"

        process = graph.processes["composed"]
        started = time.monotonic()
        process.send_signal(signal.SIGINT)
        assert process.wait(10) == 0
        assert time.monotonic() - started <= 3.0
    finally:
        graph.stop()
