"""The supervisor judges enable and reset on every controller report received before the
call, not only on what its last check took."""

from __future__ import annotations

import time


def test_enable_judges_the_reports_received_since_the_last_check(context, matched_publisher):
    import rclpy
    from hems_msgs.msg import ActuatorState, ControllerStatus
    from rclpy.duration import Duration
    from rclpy.parameter import Parameter
    from std_srvs.srv import Trigger

    from hems_ros.nodes.supervisor import SupervisorNode
    from hems_ros.ros import qos
    from hems_ros.ros.clock_time import to_msg

    supervisor = SupervisorNode(
        context=context, parameter_overrides=[Parameter("fingers", value=["index"])]
    )
    helper = rclpy.create_node("controller_reports", context=context)
    try:
        publisher = matched_publisher(
            helper, ControllerStatus, "/hems/index/controller_status", qos.CONTROLLER_STATUS
        )
        unit = matched_publisher(helper, ActuatorState, "/hems/sim/index/state", qos.SENSOR)
        # the unit's state and a controller's report with fresh readings, queued while no
        # check runs (the node is not spun, so its 20 ms check never takes them); each counts
        # from its reception, so the report comes last, as it would within 20 ms of enable
        state = ActuatorState(finger="index", watchdog_tripped=False)
        state.header.stamp = to_msg(time.time())
        for _ in range(3):  # best effort: nothing acknowledges it, so it goes more than once
            unit.publish(state)
            time.sleep(0.01)
        now = to_msg(time.time())
        publisher.publish(
            ControllerStatus(
                finger="index",
                mode="position",
                wire_position=0.001,
                wire_force=4.0,
                encoder_stamp=now,
                force_stamp=now,
            )
        )
        assert publisher.wait_for_all_acked(Duration(seconds=5))
        time.sleep(0.01)
        response = supervisor.on_command("enable", Trigger.Response())
        assert response.success, response.message
        assert supervisor.logic.state.name == "ENABLED"
    finally:
        helper.destroy_node()
        supervisor.destroy_node()


def test_the_check_runs_on_the_clock_grid_between_the_module_pairs_ticks(context):
    """Its status wakes every unit: the check sits SUPERVISOR_PHASE_S after the first pair's
    tick (hems_ros.graph.cadence.supervisor_check_delay), between two pairs' ticks."""
    from hems_ros.graph.cadence import SUPERVISOR_PHASE_S
    from hems_ros.nodes.supervisor import SupervisorNode

    supervisor = SupervisorNode(context=context)
    try:
        check = next(t for t in supervisor.timers if t.timer_period_ns == 20_000_000)
        due_s = time.time() + check.time_until_next_call() * 1e-9
        off = (due_s - SUPERVISOR_PHASE_S) % 0.02
        assert min(off, 0.02 - off) <= 0.0005
        assert 0.001 <= SUPERVISOR_PHASE_S <= 0.0033 - 0.001
    finally:
        supervisor.destroy_node()
