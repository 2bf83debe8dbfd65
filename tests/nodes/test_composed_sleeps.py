"""Nodes sharing one process sleep between their timers and messages: a unit and a
supervisor in one process (as `hems up --composed` runs them) wake about as often as their
timers ask, not tens of thousands of times a second (a QoS event status enabled on a reader
and never read keeps the wait set ready: a liveliness watch once held the composed graph at
a full core while idle)."""

from __future__ import annotations

import threading
import time


def test_unit_and_supervisor_in_one_process_wake_only_for_work(context):
    from rclpy.executors import ExternalShutdownException
    from rclpy.parameter import Parameter

    from hems_ros.nodes.actuation_unit import ActuationUnitNode
    from hems_ros.nodes.supervisor import SupervisorNode
    from hems_ros.ros import lean_spin

    nodes = [
        SupervisorNode(
            context=context,
            parameter_overrides=[Parameter("fingers", value=["index"])],
        ),
        ActuationUnitNode(context=context),
    ]
    waits = [0]
    original = lean_spin._WaitSet.wait

    def counted(self, timeout_ns):
        waits[0] += 1
        original(self, timeout_ns)

    lean_spin._WaitSet.wait = counted

    def spin():
        try:
            lean_spin.spin_nodes(nodes)
        except ExternalShutdownException:
            pass

    thread = threading.Thread(target=spin, daemon=True)
    try:
        thread.start()
        time.sleep(1.0)  # discovery of the two nodes' endpoints within the participant
        before, started = waits[0], time.monotonic()
        time.sleep(2.0)
        per_second = (waits[0] - before) / (time.monotonic() - started)
    finally:
        context.try_shutdown()
        thread.join(timeout=5)
        lean_spin._WaitSet.wait = original
        for node in nodes:
            node.destroy_node()
    # the unit's 100 Hz tick, the supervisor's 50 Hz check and the statuses between them:
    # a few hundred a second; a wait set that stays ready returns tens of thousands of times
    assert 50 < per_second < 600, per_second
