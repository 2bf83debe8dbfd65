"""A malformed serialized message on a hot topic is logged and dropped; the node keeps
running, and a unit treats an unreadable duty command as a rejected one (0 % duty)."""

from __future__ import annotations

GARBAGE = b"\x00\x01\x00\x00\x05\x00"  # CDR header, then a truncated message


def deliver(node, topic: str, data: bytes) -> None:
    """What the spin loop does with a message taken from ``topic``."""
    next(s for s in node.subscriptions if s.topic_name == topic).callback(data)


def test_unit_rejects_an_unreadable_duty_and_keeps_running(context, capfd):
    from hems_ros.nodes.actuation_unit import ActuationUnitNode

    node = ActuationUnitNode(context=context)
    try:
        node.driver.commanded_duty = 40.0
        deliver(node, "/hems/index/duty", GARBAGE)
        assert node.driver.rejected_commands == 1 and node.driver.commanded_duty == 0.0
        node.on_tick()
        assert node.driver.applied_duty == 0.0
    finally:
        node.destroy_node()
    assert (
        "unreadable message on /hems/index/duty dropped: hems_msgs/msg/DutyCommand"
        in capfd.readouterr().err
    )


def test_controller_module_and_supervisor_drop_unreadable_messages(context, capfd):
    from hems_ros.nodes.finger_controller import FingerControllerNode
    from hems_ros.nodes.shoulder_module import ShoulderModuleNode
    from hems_ros.nodes.supervisor import SupervisorNode

    controller = FingerControllerNode(context=context)
    module = ShoulderModuleNode(context=context)
    supervisor = SupervisorNode(context=context)
    try:
        deliver(controller, "/hems/index/encoder", GARBAGE)
        deliver(controller, "/hems/index/wire_force", GARBAGE)
        assert (
            controller.loop.readings["position"].value is None
            and controller.loop.readings["force"].value is None
            and controller.sequence == 0
        )
        deliver(module, "/hems/sim/index/wire_tension", GARBAGE)
        assert module.sequences["index"] == 0
        deliver(supervisor, "/hems/index/controller_status", GARBAGE)
        deliver(supervisor, "/hems/sim/index/state", GARBAGE)
        assert supervisor.encoder_stamps["index"] is None
    finally:
        for node in (controller, module, supervisor):
            node.destroy_node()
    err = capfd.readouterr().err
    for topic in (
        "/hems/index/encoder",
        "/hems/index/wire_force",
        "/hems/sim/index/wire_tension",
        "/hems/index/controller_status",
        "/hems/sim/index/state",
    ):
        assert f"unreadable message on {topic} dropped" in err, topic
