"""`hems setpoint` checks that the controller's status shows the setpoint, and sends it again
if not: a controller whose reader had not matched the new writer yet drops the sample, and a
process that exits at once never repairs it (real DDS, a stand-in controller in its own
participant)."""

from __future__ import annotations

import pytest
from background_spin import BackgroundSpin


class StandInController:
    """Takes /hems/index/setpoint like a finger_controller and reports it in its status at 50 Hz."""

    def __init__(
        self, context, drop_first: bool = False, reject: bool = False, status: bool = True
    ) -> None:
        import rclpy
        from hems_msgs.msg import ControllerStatus, FingerSetpoint

        from hems_ros.ros import qos

        self.received = 0
        self.mode, self.setpoint, self.rejected, self.last_rejection = "position", 0.0, 0, ""
        self._drop_first, self._reject = drop_first, reject
        self.node = rclpy.create_node("controller_stand_in", context=context)
        self.node.create_subscription(
            FingerSetpoint, "/hems/index/setpoint", self.on_setpoint, qos.COMMAND
        )
        if status:
            publisher = self.node.create_publisher(
                ControllerStatus, "/hems/index/controller_status", qos.CONTROLLER_STATUS
            )
            self.node.create_timer(
                0.02,
                lambda: publisher.publish(
                    ControllerStatus(
                        finger="index",
                        mode=self.mode,
                        setpoint=self.setpoint,
                        rejected_setpoints=self.rejected,
                        last_rejection=self.last_rejection,
                    )
                ),
            )
        self.spinner = BackgroundSpin(self.node)

    def on_setpoint(self, message) -> None:
        self.received += 1
        if self._drop_first and self.received == 1:
            return  # as a reader that had not matched the writer yet
        if self._reject:
            self.rejected += 1
            self.last_rejection = "outside this controller's limits"
            return
        self.mode, self.setpoint = message.mode, message.value

    def stop(self) -> None:
        self.spinner.stop()
        self.node.destroy_node()


@pytest.fixture
def client(ros_domain_id):
    from hems_ros.client.graph_client import GraphClient

    with GraphClient("confirm_test") as graph_client:
        yield graph_client


@pytest.fixture
def stand_in(context, request):
    controller = StandInController(context, **request.param)
    yield controller
    controller.stop()


@pytest.mark.parametrize("stand_in", [{"drop_first": True}], indirect=True)
def test_a_dropped_setpoint_is_sent_again_until_the_status_shows_it(client, stand_in):
    result = client.send_setpoint("index", "position", 0.012, confirm_s=5.0)
    assert result and result.confirmed is True
    assert result.message == "in force (controller status)"
    assert stand_in.received >= 2 and stand_in.setpoint == 0.012
    # a setpoint already in force is confirmed by the next status
    assert client.send_setpoint("index", "position", 0.012, confirm_s=5.0).confirmed is True


@pytest.mark.parametrize("stand_in", [{"reject": True}], indirect=True)
def test_a_setpoint_the_controller_rejects_is_reported(client, stand_in):
    result = client.send_setpoint("index", "position", 0.012, confirm_s=5.0)
    assert not result and result.sent
    assert result.message == "rejected by the controller: outside this controller's limits"


@pytest.mark.parametrize("stand_in", [{"status": False}], indirect=True)
def test_without_a_status_the_setpoint_is_not_called_in_force(client, stand_in):
    result = client.send_setpoint("index", "force", 3.0, confirm_s=1.0)
    assert not result and result.sent and result.confirmed is False
    assert result.message == "sent, but not in force after 1 s (no controller status received)"
    assert stand_in.received >= 3  # sent again every RESEND_S while unconfirmed
    assert stand_in.setpoint == 3.0


def test_without_a_controller_nothing_is_sent(client):
    result = client.send_setpoint("index", "position", 0.012, timeout=0.5, confirm_s=1.0)
    assert not result and not result.sent
    assert result.message == "no finger_controller subscribed to /hems/index/setpoint"


def test_a_status_from_before_the_setpoint_does_not_confirm_it(client, context):
    first = StandInController(context)
    try:
        assert client.send_setpoint("index", "position", 0.012, confirm_s=5.0).confirmed is True
    finally:
        first.stop()
    client.spin_for(0.5)  # the client takes the last statuses of the stopped one meanwhile
    # restarted, and its status not (yet) reaching the client: the cached status of the
    # controller before shows 0.012, which the new one has never been sent
    second = StandInController(context, status=False)
    try:
        result = client.send_setpoint("index", "position", 0.012, confirm_s=1.0)
        assert result.sent and result.confirmed is False
        assert result.message == "sent, but not in force after 1 s (no controller status received)"
        assert second.setpoint == 0.012
    finally:
        second.stop()
