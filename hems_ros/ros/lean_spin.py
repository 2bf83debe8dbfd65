"""A lean spin loop for our nodes (and, draining in batches, the recorder).

rclpy's executors rebuild a wait set on every wake-up (a new rcl wait set, entity counts,
callback-group checks, a Task and a coroutine per callback); for our nodes, which wake a few
hundred times a second, that machinery cost more CPU than their own work. This loop
allocates one wait set, and on each wake-up re-adds the handles, waits, takes what is ready
and calls the callbacks directly, in the order rclpy uses (timers, subscriptions, services).

It serves nodes with timers, subscriptions and services only (no clients, guard conditions
or waitables such as QoS event handlers: see lean_node.py) and callbacks that are plain
functions (a timer callback gets no TimerInfo). :func:`spin` takes the entities as built;
:func:`loop` also follows entities added later. :func:`can_spin` tells; other nodes spin
on an rclpy executor (:func:`spin_on_executor`).
"""

from __future__ import annotations

import inspect
import time
from contextlib import ExitStack
from typing import Any

from rclpy.executors import ExternalShutdownException
from rclpy.impl.implementation_singleton import rclpy_implementation as _rclpy

WAIT_TIMEOUT_NS = 50_000_000  # how often the context is checked without work (Ctrl-C latency)
# How often the parameter and type-description services are served: checking the seven of a
# node costs about 150 us after a 10 ms sleep (23 us warm), and at 20 ms that was a few per
# cent of the separate graph's CPU; a `ros2 param` answer within 0.1 s goes unnoticed.
INTROSPECTION_POLL_S = 0.1
INTROSPECTION_PACKAGES = ("rcl_interfaces", "type_description_interfaces")
_polled_changes = 0  # bumped whenever a node changes the subscriptions it drains itself


def polled_changed() -> None:
    """A node (LeanNode.poll) changed which subscriptions it drains itself: the wait sets of
    the loops spinning it leave them out from the next round on."""
    global _polled_changes
    _polled_changes += 1


def can_spin(node) -> bool:
    """True if :func:`spin` handles every entity of ``node``."""
    from rclpy.subscription import Subscription

    return (
        not (list(node.clients) or list(node.guards) or list(node.waitables))
        and all(
            s._callback_type is Subscription.CallbackType.MessageOnly for s in node.subscriptions
        )
        and all(not inspect.signature(t.callback).parameters for t in node.timers)
    )


def spin(node) -> None:
    """Spin ``node`` until its context shuts down (then ExternalShutdownException, as
    rclpy.spin)."""
    spin_nodes([node])


def spin_nodes(nodes) -> None:
    """Spin several nodes of one context on one thread, one wait set for all of them.

    In one process (``hems up --composed``) this replaces a multi-threaded executor, whose
    threads only contend for the interpreter lock: the nodes' callbacks are short, and one
    thread running them in turn keeps each control period's chain (encoder, controller,
    duty) in order without a thread switch.
    """
    for node in nodes:
        if not can_spin(node):
            raise ValueError(
                f"node {node.get_name()} has clients, guard conditions or waitables: "
                "use spin_on_executor"
            )
    timers = [t for node in nodes for t in node.timers]
    services = [s for node in nodes for s in node.services]
    current: dict[str, Any] = {}

    def entities() -> tuple:
        if current.get("changes") != _polled_changes:
            current["changes"] = _polled_changes
            current["entities"] = (
                [
                    s
                    for node in nodes
                    for s in node.subscriptions
                    if s not in getattr(node, "polled", ())
                ],
                timers,
                services,
            )
        return current["entities"]

    loop(nodes[0].context, entities)
    raise ExternalShutdownException()


def spin_on_executor(nodes, executor, keep_going=None) -> None:
    """Spin nodes that :func:`spin_nodes` cannot serve on an rclpy ``executor`` until their
    context shuts down (then ExternalShutdownException) or ``keep_going()`` turns false (then
    it returns), every wait bounded; the executor is shut down either way.

    rclpy's executors wait without a timeout for the guard conditions that its signal thread
    triggers on Ctrl-C or SIGTERM. Now and then that wake-up is lost: a ping_responder on
    ``rclpy.spin``, stopped 60 times with one core busy, once slept on in ``rcl_wait`` after
    SIGTERM, every thread idle, until it was killed. A wait that returns after WAIT_TIMEOUT_NS
    lets the context be checked, as :func:`loop` does: 550 stops, none missed.
    """
    try:
        for node in nodes:
            executor.add_node(node)
        while nodes[0].context.ok():
            if keep_going is not None and not keep_going():
                return
            executor.spin_once(timeout_sec=WAIT_TIMEOUT_NS / 1e9)
    finally:
        executor.shutdown()
    raise ExternalShutdownException()


def loop(context, entities, on_ready=None, keep_going=None, pause_s: float = 0.0) -> None:
    """Wait on the entities and run what is ready until the context shuts down or
    ``keep_going()`` turns false.

    ``entities()`` gives (subscriptions, timers, services); the wait set is rebuilt when they
    change (the recorder subscribes as topics appear, a node takes a subscription out to
    drain it itself). ``on_ready(subscription)`` replaces taking one message for its
    callback; ``pause_s`` sleeps after each round.
    """
    # No signal guard condition: destroying one while rclpy's signal thread still triggers it
    # crashed the process now and then; Ctrl-C is seen within one wait timeout instead.
    last, built, waiting, introspection, next_poll = None, None, None, [], 0.0
    with ExitStack() as stack:
        # held for the loop, so its ok() is one call; Context.ok() takes a lock and enters the
        # handle each time (2.7 against 0.45 us), twice per wake-up of every node
        handle = context.handle
        stack.enter_context(handle)
        entered: set[int] = set()
        while handle.ok() and (keep_going is None or keep_going()):
            try:
                current = entities()
                if current is not last:
                    last = current
                    subscriptions, timers, services = current
                    key = tuple(tuple(map(id, kind)) for kind in current)
                if key != built:
                    built = key
                    for entity in (*subscriptions, *timers, *services):
                        if id(entity) not in entered:
                            stack.enter_context(entity.handle)
                            entered.add(id(entity))
                    # Every node has seven parameter and type-description services; in the
                    # wait set they are re-added and checked at every wake-up, almost always
                    # for nothing (the composed graph's 112 took a sixth of its CPU: 0.66 ->
                    # 0.55 cores), so they are served every INTROSPECTION_POLL_S instead,
                    # which `ros2 param` does not notice.
                    introspection = [s for s in services if _is_introspection(s)]
                    waiting = _WaitSet(
                        context,
                        subscriptions,
                        timers,
                        [s for s in services if s not in introspection],
                    )
                assert waiting is not None  # built in the first round
                waiting.wait(WAIT_TIMEOUT_NS)
                if not handle.ok():
                    break
                waiting.run_ready(on_ready)
                if introspection and (now := time.monotonic()) >= next_poll:
                    next_poll = now + INTROSPECTION_POLL_S
                    for service in introspection:
                        _serve(service)
                if pause_s:
                    time.sleep(pause_s)
            except RuntimeError:
                # Ctrl-C shuts the context down from rclpy's signal thread, possibly while a
                # wait or take is under way here, which then fails: not an error of the node
                time.sleep(0.05)
                if handle.ok():
                    raise
                break


def _is_introspection(service) -> bool:
    return service.srv_type.__module__.split(".", 1)[0] in INTROSPECTION_PACKAGES


def _serve(service) -> None:
    """Answer every request queued for ``service``."""
    while True:
        request, header = service.handle.service_take_request(service.srv_type.Request)
        if header is None:
            return
        service.send_response(service.callback(request, service.srv_type.Response()), header)


class _WaitSet:
    """One rcl wait set sized for the entities, with their handles looked up once.

    A composed graph has some seventy entities and wakes a thousand times a second: reading
    each handle and its pointer through pybind on every wake, and testing every entity for
    readiness, took a fifth of the process's time. Ready entities come back in the order they
    were added, so running them by pointer keeps rclpy's order (timers, subscriptions,
    services; each kind in creation order).
    """

    def __init__(self, context, subscriptions, timers, services) -> None:
        self.wait_set = _rclpy.WaitSet(
            len(subscriptions), 0, len(timers), 0, len(services), 0, context.handle
        )
        self.handles = (
            [s.handle for s in subscriptions],
            [t.handle for t in timers],
            [s.handle for s in services],
        )
        self.subscriptions = {s.handle.pointer: s for s in subscriptions}
        self.timers = {t.handle.pointer: t for t in timers}
        self.services = {s.handle.pointer: s for s in services}

    def wait(self, timeout_ns: int) -> None:
        wait_set = self.wait_set
        wait_set.clear_entities()
        subscriptions, timers, services = self.handles
        for handle in subscriptions:
            wait_set.add_subscription(handle)
        for handle in services:
            wait_set.add_service(handle)
        for handle in timers:
            wait_set.add_timer(handle)
        wait_set.wait(timeout_ns)

    def run_ready(self, on_ready=None) -> None:
        """Run the callbacks of the ready entities: subscriptions (one message each, or
        ``on_ready(subscription)``), then timers, then services.

        Messages before timers: the nodes' timers judge what has arrived (a controller's idle
        status reports its last readings, a unit's duty watchdog the last command, the
        supervisor's monitor the last reports). After the process was not scheduled for a
        while, both are ready at once; timers first reported the readings from before the
        pause while newer ones were queued (a controller's idle status with a 106 ms old
        encoder stamp latched a "stale encoder" FAULT just after enabling, one `make demo`
        in three), and each message's callback restarts the timer it makes unnecessary.
        """
        wait_set = self.wait_set
        # a kind the set does not hold is not asked for (a module has neither timers nor
        # services in it)
        for pointer in wait_set.get_ready_entities("subscription") if self.subscriptions else ():
            subscription = self.subscriptions[pointer]
            if on_ready is not None:
                on_ready(subscription)
                continue
            taken = subscription.handle.take_message(subscription.msg_type, subscription.raw)
            if taken is not None:
                subscription.callback(taken[0])
        for pointer in wait_set.get_ready_entities("timer") if self.timers else ():
            timer = self.timers[pointer]
            if timer.handle.is_timer_ready():
                timer.handle.call_timer()
                timer.callback()
        for pointer in wait_set.get_ready_entities("service") if self.services else ():
            _serve(self.services[pointer])
