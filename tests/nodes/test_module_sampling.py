"""On wall-clock time a shoulder module samples at its own instants on the clock's grid,
``sample_delay_s`` after its units' tick, and turns every tension received since the last
instant into one reading; on sim time it reads each tension when it arrives."""

from __future__ import annotations

import time

import pytest


def module(context, use_sim_time: bool = False, **overrides):
    from rclpy.parameter import Parameter

    from hems_ros.nodes.shoulder_module import ShoulderModuleNode

    return ShoulderModuleNode(context=context, parameter_overrides=[
        Parameter("module", value="index_middle"), Parameter("use_sim_time", value=use_sim_time),
        Parameter("noise_std_n", value=0.0), *(Parameter(k, value=v) for k, v in overrides.items())])


def test_tensions_wake_the_module_only_on_sim_time(context):
    for use_sim_time in (False, True):
        node = module(context, use_sim_time)
        try:
            assert all((s in node.polled) is not use_sim_time for s in node.tension_subs)
            assert (node.sample_timer is None) is use_sim_time
        finally:
            node.destroy_node()


def test_the_sampling_instant_follows_the_units_tick_by_the_delay(context):
    from hems_ros.graph.cadence import grid_delay, module_phase_s

    node = module(context, sample_delay_s=0.003)
    try:
        next_call_s = time.time() + node.sample_timer.time_until_next_call() * 1e-9
        # index_middle's units tick a third of a period into the 10 ms grid
        off = grid_delay(module_phase_s("index_middle", 0.01) + 0.003, 0.01, next_call_s)
        assert module_phase_s("index_middle", 0.01) == pytest.approx(0.01 / 3)
        assert min(off, 0.01 - off) <= 0.0005
    finally:
        node.destroy_node()


def test_a_delay_of_a_whole_period_stops_start_up_naming_the_parameter(context):
    with pytest.raises(ValueError, match="sample_delay_s"):
        module(context, sample_delay_s=0.01)


def test_every_tension_received_between_instants_becomes_one_reading_at_the_instant(context):
    import rclpy
    from rclpy.duration import Duration

    from hems_msgs.msg import WireForce
    from hems_ros.nodes import qos

    node = module(context)
    helper = rclpy.create_node("tension_source", context=context)
    readings = []
    try:
        helper.create_subscription(WireForce, "/hems/index/wire_force", readings.append, qos.SENSOR)
        helper.create_subscription(WireForce, "/hems/middle/wire_force", readings.append, qos.SENSOR)
        publishers = {f: helper.create_publisher(WireForce, f"/hems/sim/{f}/wire_tension", qos.SENSOR)
                      for f in ("index", "middle")}
        deadline = time.monotonic() + 10.0
        while not all(p.get_subscription_count() for p in publishers.values()) or \
                helper.count_publishers("/hems/index/wire_force") < 1:
            assert time.monotonic() < deadline, "the module's topics were not discovered"
            time.sleep(0.05)
        sent = [("index", 4.0, 7), ("middle", 12.5, 8), ("index", 4.25, 9)]
        for finger, force, sec in sent:
            publishers[finger].publish(WireForce(finger=finger, force=force, sequence=sec))
            publishers[finger].wait_for_all_acked(Duration(seconds=1))
        time.sleep(0.05)
        executor = rclpy.executors.SingleThreadedExecutor(context=context)
        executor.add_node(helper)
        executor.spin_once(timeout_sec=0.05)
        assert readings == [], "a reading went out before the module's sampling instant"
        node.sample()
        deadline = time.monotonic() + 5.0
        while len(readings) < 3 and time.monotonic() < deadline:
            executor.spin_once(timeout_sec=0.05)
        got = sorted((r.finger, r.sequence, r.force) for r in readings)
        # resolution 0.01 N, no noise: the readings are the tensions, one each, numbered per sensor
        assert got == [("index", 1, 4.0), ("index", 2, 4.25), ("middle", 1, 12.5)]
    finally:
        helper.destroy_node()
        node.destroy_node()
