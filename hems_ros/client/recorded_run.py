"""The graph, a recorder of its topics and a client joined to it, started together and stopped
together: what a recorded run needs (`hems demo`, `hems step`, `hems soak`, the start-up
benchmark)."""

from __future__ import annotations

import os
import time
from collections.abc import Iterator
from contextlib import contextmanager
from dataclasses import dataclass

from hems_ros.bag.recording import RecorderProcess
from hems_ros.bag.selection import record_regex
from hems_ros.client.graph_client import GraphClient
from hems_ros.client.recording import wait_until_recording
from hems_ros.launcher import Graph, GraphOptions


@dataclass
class RecordedGraph:
    """A running graph with its recorder and the client joined to it."""

    graph: Graph
    recorder: RecorderProcess
    client: GraphClient
    stop_s: float = 0.0  # how long the graph took to stop, once it has


@contextmanager
def recorded_graph(
    options: GraphOptions, bag: str | os.PathLike, client_name: str, ready_timeout_s: float
) -> Iterator[RecordedGraph]:
    """Start the graph and a recorder of its topics, join it as ``client_name`` and wait until
    the recording holds every stream (TimeoutError, or the recorder's RuntimeError, after
    ``ready_timeout_s``). On leaving, whatever happened, the recorder finishes its bag while
    the graph still publishes (a caller that stopped it first gets the same bag), then the
    graph stops."""
    graph = Graph(options)
    graph.start()
    run = None
    try:
        with (
            RecorderProcess(bag, regex=record_regex(options.namespace)) as recorder,
            GraphClient(
                client_name, sim_time=options.sim_time, namespace=options.namespace
            ) as client,
        ):
            wait_until_recording(
                client, recorder, options.fingers, time.monotonic() + ready_timeout_s
            )
            run = RecordedGraph(graph, recorder, client)
            yield run
    finally:
        started = time.monotonic()
        graph.stop()
        if run is not None:
            run.stop_s = time.monotonic() - started
