"""The fault matrix's graph (tests/faults/faultrows.py has its rows and table).

One finger's graph (actuation unit, shoulder module, controller, supervisor; one process each,
as `ros2 run` of each node gives) stays up for the whole matrix; each row injects one fault
into a graph that is ENABLED and holding a setpoint, and restores it afterwards. With
HEMS_RELIABILITY_PAGE set (``make test-faults``) the run writes the matrix into that
Markdown file, between its fault-matrix markers.
"""

from __future__ import annotations

import os
import re
import subprocess
import sys
import time
from pathlib import Path

import pytest
from background_spin import BackgroundSpin
from faultrows import BEGIN, END, FINGER, ROWS, Observer, render

BUSY_LOOP = [sys.executable, "-c", "while True: pass"]  # as the benchmarks' --busy


@pytest.fixture(scope="module")
def matrix_graph(ros_domain_id):
    from hems_ros.rosenv import die_with_parent

    # A user's machine does other work: the matrix's timings count with one core taken
    busy = subprocess.Popen(BUSY_LOOP, preexec_fn=die_with_parent)
    try:
        yield from _matrix_graph()
    finally:
        busy.kill()
        busy.wait()


def _matrix_graph():
    import rclpy
    from hems_msgs.msg import ActuatorState, ControllerStatus, EncoderReading, SupervisorStatus
    from rcl_interfaces.msg import ParameterEvent
    from rclpy.qos import qos_profile_parameter_events

    from hems_ros.client.graph_client import GraphClient
    from hems_ros.graph import names
    from hems_ros.launcher import Graph, GraphOptions
    from hems_ros.ros import qos

    graph = Graph(GraphOptions(fingers=(FINGER,), composed=False, log_level="error"))
    graph.start()
    observer = Observer()
    try:
        with GraphClient("hems_fault_matrix") as client:
            context = rclpy.Context()
            rclpy.init(context=context)
            node = rclpy.create_node("fault_matrix_observer", context=context)
            now = time.monotonic

            def keep(target, item):
                with observer.lock:
                    target.append(item)

            node.create_subscription(
                EncoderReading,
                names.topic(FINGER, "encoder"),
                lambda m: keep(observer.drive, (now(), m.duty_percent)),
                qos.SENSOR,
            )
            node.create_subscription(
                ActuatorState,
                names.sim_topic(FINGER, "state"),
                lambda m: keep(observer.truth_c, (now(), m.wire_temperature_c)),
                qos.SENSOR,
            )
            node.create_subscription(
                SupervisorStatus,
                names.SUPERVISOR_STATUS_TOPIC,
                lambda m: keep(observer.supervisor, (now(), m.state_name, tuple(m.faults))),
                qos.STATUS,
            )
            node.create_subscription(
                ControllerStatus,
                names.topic(FINGER, "controller_status"),
                lambda m: keep(observer.status, (now(), m)),
                qos.CONTROLLER_STATUS,
            )
            node.create_subscription(
                ParameterEvent,
                "/parameter_events",
                lambda m: [
                    keep(observer.parameters, (now(), m.node, p.name, p.value.string_value))
                    for p in m.changed_parameters
                ],
                qos_profile_parameter_events,
            )
            spinner = BackgroundSpin(node)
            try:
                yield graph, client, observer
            finally:
                spinner.stop()
                node.destroy_node()
                rclpy.try_shutdown(context=context)
    finally:
        graph.stop()


def pytest_unconfigure() -> None:
    """Writes the fault table once the run is over (make test-faults sets the page)."""
    page = os.environ.get("HEMS_RELIABILITY_PAGE")
    if not page or not ROWS:
        return
    path = Path(page)
    text = path.read_text() if path.exists() else f"{BEGIN}\n{END}\n"
    table = render(ROWS)
    if BEGIN in text and END in text:
        text = re.sub(
            re.escape(BEGIN) + ".*?" + re.escape(END),
            lambda _: f"{BEGIN}\n{table}{END}",
            text,
            flags=re.S,
        )
    else:
        text += f"\n{BEGIN}\n{table}{END}\n"
    path.write_text(text)
