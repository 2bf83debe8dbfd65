"""A bad parameter stops a node at start-up with a message naming it and exit code 2.

Each node runs as the installed executable would (``python -m hems_ros.nodes.<node>``) in
the test run's ROS domain; none gets as far as spinning.
"""

from __future__ import annotations

import subprocess

import pytest


@pytest.mark.parametrize(
    "executable, override, message",
    [
        ("actuation_unit", "finger:=pinky", "parameter 'finger' = 'pinky': must be one of"),
        (
            "actuation_unit",
            "physics_dt_s:=-0.001",
            "parameter 'physics_dt_s' = -0.001: must be a finite number > 0",
        ),
        ("actuation_unit", "physics_dt_s:=1", "parameter 'physics_dt_s': wrong type"),
        (
            "actuation_unit",
            "physics_config:=no_such_set",
            "parameter 'physics_config' = 'no_such_set'",
        ),
        ("finger_controller", "strategy:=fuzzy", "parameter 'strategy' = 'fuzzy': must be one of"),
        ("shoulder_module", "module:=foot", "parameter 'module' = 'foot': must be one of"),
        ("supervisor", "stale_s:=0.0", "parameter 'stale_s' = 0.0"),
    ],
)
def test_bad_parameter_stops_the_node_naming_it(venv, ros_domain_id, executable, override, message):
    result = subprocess.run(
        [
            str(venv / "bin" / "python"),
            "-m",
            f"hems_ros.nodes.{executable}",
            "--ros-args",
            "-p",
            override,
        ],
        capture_output=True,
        text=True,
        timeout=60,
    )
    assert result.returncode == 2, result.stderr[-2000:]
    assert message in result.stderr
    assert "Traceback" not in result.stderr


def test_a_parameter_changed_at_run_time_reaches_the_node_and_a_bad_one_does_not(context):
    """The values declare() returns follow every accepted change, which the nodes read
    instead of get_parameter; a rejected value leaves them as they were."""
    from rclpy.parameter import Parameter

    from hems_ros.nodes.shoulder_module import ShoulderModuleNode

    node = ShoulderModuleNode(context=context)
    try:
        assert node.fault("index") == ""
        results = node.set_parameters(
            [Parameter("sensor_fault", value="nan_force"), Parameter("fault_finger", value="index")]
        )
        assert all(r.successful for r in results)
        assert (node.fault("index"), node.fault("middle")) == ("nan_force", "")
        (bad,) = node.set_parameters([Parameter("sensor_fault", value="melted")])
        assert not bad.successful and "must be one of" in bad.reason
        assert node.params["sensor_fault"] == "nan_force"
    finally:
        node.destroy_node()


def test_the_clock_chosen_at_start_up_cannot_be_switched_while_running(context):
    """A unit's grid timers, reception times and clock reads follow the clock it started on;
    a use_sim_time change while it runs is refused with the restart that would apply it, and
    setting the value it already has is accepted."""
    from rclpy.parameter import Parameter

    from hems_ros.nodes.actuation_unit import ActuationUnitNode

    node = ActuationUnitNode(context=context)
    try:
        assert node.wall_clock
        (switch,) = node.set_parameters([Parameter("use_sim_time", value=True)])
        assert not switch.successful
        assert "restart the node with -p use_sim_time:=true" in switch.reason
        assert node.get_parameter("use_sim_time").value is False
        assert not node.get_clock().ros_time_is_active
        (same,) = node.set_parameters([Parameter("use_sim_time", value=False)])
        assert same.successful
    finally:
        node.destroy_node()
