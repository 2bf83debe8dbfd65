"""Waiting until a recorder holds what a run needs, before the run starts."""

from __future__ import annotations

import time

from hems_ros.graph import names


def graph_topics(fingers, namespace: str = names.NAMESPACE) -> list[str]:
    """Topics a recording of the graph must hold before the run starts (setpoints included:
    their publisher is reliable but not latched, so a recorder joining late misses one)."""
    topics = [names.supervisor_status_topic(namespace)]
    for finger in fingers:
        topics += [
            names.topic(finger, s, namespace) for s in ("encoder", "wire_force", "duty", "setpoint")
        ]
    return topics


def periodic_topics(fingers, namespace: str = names.NAMESPACE) -> list[str]:
    """The streams the graph publishes whether enabled or not, one message of each to be in
    the bag before a run starts."""
    topics = [names.supervisor_status_topic(namespace)]
    for finger in fingers:
        topics += [
            names.topic(finger, "encoder", namespace),
            names.topic(finger, "controller_status", namespace),
            names.sim_topic(finger, "state", namespace),
        ]
    return topics


def wait_until_recording(client, recorder, fingers, deadline: float) -> None:
    """Send every finger's controller its start setpoint (position 0), which creates the
    client's setpoint publishers, wait until ``recorder`` holds :func:`graph_topics`, setpoints
    included, then until its setpoint readers have matched the client's writers, so that the
    run's first real setpoint is recorded (a subscribed reader not matched yet loses it: once
    here a step's bag held one of its four setpoints), and until a message of each of
    :func:`periodic_topics` has reached the bag. ``deadline`` is a time.monotonic()
    value; TimeoutError when it passes, the recorder's RuntimeError passes through."""
    for finger in fingers:
        while not client.send_setpoint(finger, "position", 0.0) and time.monotonic() < deadline:
            pass
    recorder.wait_for_topics(
        graph_topics(fingers, client.namespace), timeout=max(1.0, deadline - time.monotonic())
    )
    # two readers per setpoint writer: the controller's and the recorder's
    unmatched = client.fingers_without_readers(fingers, 2, max(1.0, deadline - time.monotonic()))
    if unmatched:
        raise TimeoutError(
            "the recorder's setpoint readers did not match this tool's writers in time: "
            + ", ".join(names.topic(f, "setpoint", client.namespace) for f in unmatched)
        )
    # a subscribed reader need not have matched the streams' writers yet: on a slow host a
    # demo's bag began its states and statuses after the approach had started
    recorder.wait_for_messages(
        periodic_topics(fingers, client.namespace), timeout=max(1.0, deadline - time.monotonic())
    )
