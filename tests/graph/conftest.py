"""A running HEMS graph (16 node processes) shared by the tests of a module."""

from __future__ import annotations

import pytest


@pytest.fixture(scope="module")
def graph(venv):
    from hems_ros.client.graph_client import GraphClient
    from hems_ros.graph import names
    from hems_ros.launcher import Graph, GraphOptions

    with (
        Graph(GraphOptions(composed=False, log_level="warn")) as running,
        GraphClient("hems_test") as client,
    ):
        # reset first: a start-up hiccup may have latched a fault
        ok, message = client.enable_when_ready(90, reset=True, retry_s=1.0)
        assert ok, f"graph did not become ready: {running.with_exits(message)}"
        client.call("disable")
        client.spin_for(10.0)  # let start-up load (imports, numba cache loads or compiles) pass
        client.call("reset")
        for finger in names.FINGERS:  # create every endpoint the tests use before they start
            client.send_setpoint(finger, "position", 0.0)
        client.spin_for(2.0)
        # a node left running by another test of this run shares the domain and would
        # answer the same samples (a second controller's duty wins every other period)
        seen = [
            f"{ns.rstrip('/')}/{name}" for name, ns in client.node.get_node_names_and_namespaces()
        ]
        assert not {
            n for n in seen if seen.count(n) > 1
        }, f"nodes twice in the test domain: {sorted(seen)}"
        yield running, client
