"""On wall-clock time a unit takes its duty commands at its ticks, each at the time the
middleware received it: the command still takes effect from the encoder sample it answers,
and the latency in /diagnostics runs to the reception, not to the tick that took it."""

from __future__ import annotations

import time

import pytest

from hems_ros.ros.wire import stamp


def unit(context, use_sim_time: bool = False, require_supervisor: bool = False):
    """An index unit; with the supervisor required, its permission lasts a second after a
    status (the graph's supervisor renews it every 20 ms; these tests send one or two)."""
    from rclpy.parameter import Parameter

    from hems_ros.nodes.actuation_unit import ActuationUnitNode

    return ActuationUnitNode(
        context=context,
        parameter_overrides=[
            Parameter("require_supervisor", value=require_supervisor),
            Parameter("use_sim_time", value=use_sim_time),
            Parameter("supervisor_timeout_s", value=1.0),
        ],
    )


def tick_just_after_a_sample(node) -> float:
    """Tick the unit as its timer does, then once just after its next 10 ms sample falls due,
    so a command answering that sample arrives well before the one after (a tick a
    millisecond before the next sample made the command late); returns the sample time."""
    for _ in range(3):
        time.sleep(0.011)
        node.on_tick()
    next_sample_s = node.driver._sample_time_s + node.driver.sample_period_s
    time.sleep(max(0.0, next_sample_s + 0.0005 - time.time()))
    node.on_tick()
    sample_s = node.driver._sample_time_s
    assert sample_s == pytest.approx(next_sample_s, abs=1e-6)
    return sample_s


def test_duty_commands_and_statuses_wake_the_unit_only_on_sim_time(context):
    for use_sim_time in (False, True):
        node = unit(context, use_sim_time)
        try:
            assert (node.duty_sub in node.polled) is not use_sim_time
            assert (node.supervisor_sub in node.polled) is not use_sim_time
        finally:
            node.destroy_node()


def test_a_duty_taken_at_the_tick_counts_from_its_reception_and_acts_from_its_sample(
    context, matched_publisher
):
    import rclpy
    from builtin_interfaces.msg import Time
    from hems_msgs.msg import DutyCommand

    from hems_ros.ros import qos

    node = unit(context)
    helper = rclpy.create_node("duty_sender", context=context)
    try:
        publisher = matched_publisher(helper, DutyCommand, "/hems/index/duty", qos.COMMAND)
        sample_s = tick_just_after_a_sample(node)
        sec, nanosec = stamp(sample_s)
        publisher.publish(
            DutyCommand(
                finger="index", duty_percent=35.0, measurement_stamp=Time(sec=sec, nanosec=nanosec)
            )
        )
        sent_s = time.time()
        # the unit takes it at a tick that comes well after the command arrived
        time.sleep(0.006)
        assert node.driver.commands == 0
        node.on_tick()
        taken_s = time.time()
        assert node.driver.commands == 1 and node.driver.commanded_duty == 35.0
        # from the sample it answers, not from the tick that took it
        assert node.driver.last_command_s == pytest.approx(sample_s, abs=1e-9)
        assert node.driver.late_commands == 0 and node.driver.applied_duty == 35.0
        latency = node.driver.latencies_s[-1]
        assert sent_s - sample_s - 0.001 <= latency < taken_s - sample_s - 0.004
    finally:
        helper.destroy_node()
        node.destroy_node()


def test_units_tick_at_their_shoulder_modules_phase_on_wall_clock_time(context):
    from hems_ros.graph.cadence import tick_delay

    node = unit(context)
    try:
        # the physics grid (and so every encoder sample) follows the tick timer
        start = node.driver.start_time_s
        off = tick_delay("index", 0.01, start)
        assert min(off, 0.01 - off) <= 0.0005
    finally:
        node.destroy_node()


def test_duty_commands_that_came_before_a_supervisor_status_act_before_it(
    context, matched_publisher
):
    """An ESTOP stops the heating when it comes: a command that came earlier still heats from
    the sample it answers up to the ESTOP, not only until the unit's previous tick."""
    import rclpy
    from builtin_interfaces.msg import Time
    from hems_msgs.msg import DutyCommand, SupervisorStatus
    from rclpy.duration import Duration

    from hems_ros.ros import qos

    node = unit(context, require_supervisor=True)
    helper = rclpy.create_node("duty_sender", context=context)
    try:
        publisher = matched_publisher(helper, DutyCommand, "/hems/index/duty", qos.COMMAND)
        node.on_supervisor(SupervisorStatus(state=SupervisorStatus.ENABLED))
        sample_s = tick_just_after_a_sample(node)
        energy_at_sample = node.driver.last_result.energy_joule_j  # the tick stopped at the sample
        sec, nanosec = stamp(sample_s)
        publisher.publish(
            DutyCommand(
                finger="index", duty_percent=100.0, measurement_stamp=Time(sec=sec, nanosec=nanosec)
            )
        )
        # in the unit's queue before the ESTOP comes, however loaded the host
        assert publisher.wait_for_all_acked(Duration(seconds=5))
        time.sleep(max(0.0, sample_s + 0.004 - time.time()))
        node.on_supervisor(SupervisorStatus(state=SupervisorStatus.ESTOP))
        estop_s = node.driver.time_s
        assert node.driver.commands == 1 and node.driver.applied_duty == 0.0
        time.sleep(0.011)
        node.on_tick()
        heated = node.driver.last_result.energy_joule_j - energy_at_sample
        # 100 % duty is 4 A into about 4.2 ohm (dissertation chapter 3): about 67 W from the sample
        # to the ESTOP
        heating_s = estop_s - sample_s
        assert heating_s >= 0.003
        assert heated == pytest.approx(67.0 * heating_s, rel=0.25)
    finally:
        helper.destroy_node()
        node.destroy_node()


def test_a_command_and_an_estop_taken_at_one_tick_act_in_the_order_they_came(
    context, matched_publisher
):
    """Both came between two ticks: the command heats from the sample it answers until the
    ESTOP came, not until the tick that took them, and not at all if the ESTOP went first.
    The writers share the unit's participant, which hands it each message as it is sent."""
    import rclpy
    from builtin_interfaces.msg import Time
    from hems_msgs.msg import DutyCommand, SupervisorStatus

    from hems_ros.ros import qos

    node = unit(context, require_supervisor=True)
    helper = rclpy.create_node("command_sender", context=context)
    try:
        status_writer = matched_publisher(
            helper, SupervisorStatus, "/hems/supervisor/status", qos.STATUS
        )
        status_writer.publish(SupervisorStatus(state=SupervisorStatus.ENABLED))
        duty_writer = matched_publisher(helper, DutyCommand, "/hems/index/duty", qos.COMMAND)
        sample_s = tick_just_after_a_sample(node)
        assert node.driver.permitted(sample_s)
        energy_at_sample = node.driver.last_result.energy_joule_j
        sec, nanosec = stamp(sample_s)
        duty_writer.publish(
            DutyCommand(
                finger="index", duty_percent=100.0, measurement_stamp=Time(sec=sec, nanosec=nanosec)
            )
        )
        time.sleep(max(0.0, sample_s + 0.004 - time.time()))
        status_writer.publish(SupervisorStatus(state=SupervisorStatus.ESTOP))
        estop_s = time.time()  # a little after it came
        time.sleep(max(0.0, sample_s + 0.009 - time.time()))
        node.on_tick()
        assert node.driver.commands == 1 and not node.driver.permitted(node.driver.time_s)
        heated = node.driver.last_result.energy_joule_j - energy_at_sample
        # about 67 W (4 A into 4.2 ohm) from the sample to the ESTOP's arrival, none after
        assert 0.003 <= estop_s - sample_s < 0.009
        assert heated == pytest.approx(67.0 * (estop_s - sample_s), rel=0.3)
    finally:
        helper.destroy_node()
        node.destroy_node()


def test_a_repeated_enabled_status_only_moves_the_permission_on(context):
    """The supervisor's 10 Hz ENABLED wakes every unit at once: while heating is allowed it
    neither takes the queued commands nor integrates (the gates read the same for every step
    up to it), it only moves the lapse time on; a status after a lapse takes the full path."""
    from hems_msgs.msg import SupervisorStatus

    node = unit(context, require_supervisor=True)
    try:
        node.on_supervisor(SupervisorStatus(state=SupervisorStatus.ENABLED))
        granted_s = node.driver.permission_s
        time.sleep(0.025)
        node.on_tick()
        integrated_s = node.driver.time_s
        time.sleep(0.012)
        node.on_supervisor(SupervisorStatus(state=SupervisorStatus.ENABLED))
        assert node.driver.time_s == integrated_s
        assert node.driver.permission_s > granted_s + 0.03
        assert node.driver.permitted_since_s == pytest.approx(granted_s)
        node.driver.permission_s -= 1.0  # as if the heartbeats had stopped: lapsed
        node.on_supervisor(SupervisorStatus(state=SupervisorStatus.ENABLED))
        assert node.driver.time_s > integrated_s
        assert node.driver.permitted(node.driver.time_s)
    finally:
        node.destroy_node()
