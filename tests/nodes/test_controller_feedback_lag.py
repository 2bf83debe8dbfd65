"""A controller in position mode sends 0 % while its force readings lag its encoder by more
than feedback_lag_s on the unit's stamps: a lost force sensor must not leave the wire heating
blind to over-force (and the supervisor then latches only a loss that persists). With the
default 25 ms, a shoulder module that stops or dies stops a position loop at the third encoder
sample after its last reading, within 30 ms of it."""

from __future__ import annotations


def _stamp(seconds: float) -> tuple[int, int]:
    ns = int(round(seconds * 1e9))
    return ns // 1_000_000_000, ns % 1_000_000_000


def test_duty_is_zero_while_the_other_sensor_lags_and_back_when_it_returns(context):
    from hems_ros.graph.finger_loop import Reading
    from hems_ros.nodes.finger_controller import FingerControllerNode

    node = FingerControllerNode(context=context)
    loop = node.loop
    try:
        loop.supervisor(True)
        loop.set_point("position", 0.02)
        t0 = 1000.0
        loop.reading("force", 4.0, _stamp(t0))  # the module's last reading
        duties = []
        for sample in range(1, 6):
            loop.reading("position", 0.0, _stamp(t0 + 0.01 * sample))
            node.control(_stamp(t0 + 0.01 * sample))
            duties.append(loop.duty)
        assert duties == [100.0, 100.0, 0.0, 0.0, 0.0]  # 30 ms behind (unit clock): 0 %
        loop.reading("force", 4.0, _stamp(t0 + 0.05))  # the sensor is back
        node.control(_stamp(t0 + 0.06))
        assert loop.duty == 100.0
        loop.readings["force"] = Reading()  # never a force reading: no heating either
        node.control(_stamp(t0 + 0.07))
        assert loop.duty == 0.0
    finally:
        node.destroy_node()


def test_in_force_mode_the_encoder_is_the_other_sensor(context):
    from hems_ros.nodes.finger_controller import FingerControllerNode

    node = FingerControllerNode(context=context)
    loop = node.loop
    try:
        loop.supervisor(True)
        loop.reading("force", 4.0, _stamp(2000.2))
        loop.set_point("force", 10.0)
        loop.reading("position", 0.0, _stamp(2000.0))
        node.control(_stamp(2000.2))  # encoder 200 ms behind the force feedback
        assert loop.duty == 0.0
        loop.reading("position", 0.0, _stamp(2000.2))
        node.control(_stamp(2000.2))
        assert loop.duty > 0.0
    finally:
        node.destroy_node()
