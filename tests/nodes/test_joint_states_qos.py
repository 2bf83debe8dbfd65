"""/hems/joint_states reaches a subscriber with default QoS (reliable, as RViz displays and
plain scripts create it) as well as a best-effort one."""

from __future__ import annotations

import subprocess
import time

from hems_ros.launcher import GraphOptions, executable_path, ros_arguments
from hems_ros.processes import stop_process
from hems_ros.rosenv import child_environment


def test_default_and_best_effort_subscribers_both_receive_joint_states(ros_domain_id):
    import rclpy
    from rclpy.qos import qos_profile_sensor_data
    from sensor_msgs.msg import JointState

    command = executable_path("supervisor") + ros_arguments(
        "supervisor", {}, GraphOptions(log_level="error")
    )
    process = subprocess.Popen(command, env=child_environment(), process_group=0)
    context = rclpy.Context()
    rclpy.init(context=context)
    try:
        node = rclpy.create_node("joint_states_reader", context=context)
        default, best_effort = [], []
        node.create_subscription(JointState, "/hems/joint_states", default.append, 10)
        node.create_subscription(
            JointState, "/hems/joint_states", best_effort.append, qos_profile_sensor_data
        )
        executor = rclpy.executors.SingleThreadedExecutor(context=context)
        executor.add_node(node)
        end = time.monotonic() + 30.0
        while time.monotonic() < end and (len(default) < 5 or len(best_effort) < 5):
            executor.spin_once(timeout_sec=0.1)
        assert len(default) >= 5 and len(best_effort) >= 5, (len(default), len(best_effort))
        assert list(default[-1].name) == [
            "thumb_flexion",
            "thumb_abduction",
            "index",
            "middle",
            "ring",
            "little",
        ]
    finally:
        stop_process(process, 10.0)
        rclpy.try_shutdown(context=context)
