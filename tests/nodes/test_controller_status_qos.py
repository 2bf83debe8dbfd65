"""The controller status is offered best effort: a reliable reader held every later status
back behind a lost one until the writer's next heartbeat (about 200 ms at 50 Hz), and the
supervisor took that for a dead controller (docs/design.md)."""

from __future__ import annotations

import time


def test_the_controller_status_is_offered_best_effort_and_a_best_effort_reader_gets_it(context):
    import rclpy
    from hems_msgs.msg import ControllerStatus
    from rclpy.executors import SingleThreadedExecutor
    from rclpy.qos import ReliabilityPolicy

    from hems_ros.nodes.finger_controller import FingerControllerNode
    from hems_ros.ros import qos

    node = FingerControllerNode(context=context)
    helper = rclpy.create_node("status_reader", context=context)
    executor = SingleThreadedExecutor(context=context)
    executor.add_node(helper)
    received = []
    try:
        helper.create_subscription(
            ControllerStatus,
            "/hems/index/controller_status",
            received.append,
            qos.CONTROLLER_STATUS,
        )
        deadline = time.monotonic() + 10.0
        while not (offered := helper.get_publishers_info_by_topic("/hems/index/controller_status")):
            assert time.monotonic() < deadline, "the controller's status writer was not discovered"
            time.sleep(0.05)
        assert [info.qos_profile.reliability for info in offered] == [ReliabilityPolicy.BEST_EFFORT]
        while not received:
            assert time.monotonic() < deadline, "no status reached a best-effort reader"
            node.publish_status()
            executor.spin_once(timeout_sec=0.05)
        assert received[-1].finger == "index"
    finally:
        executor.shutdown()
        helper.destroy_node()
        node.destroy_node()
