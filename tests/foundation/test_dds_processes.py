"""Two separate OS processes exchange hems_msgs messages over Fast DDS."""

from __future__ import annotations

import json
import subprocess
import time

from hems_ros.processes import stop_process

PUBLISHER = r"""
import time, rclpy
from rclpy.qos import QoSProfile, ReliabilityPolicy
from hems_msgs.msg import FingerSetpoint
rclpy.init()
node = rclpy.create_node("test_setpoint_publisher")
qos = QoSProfile(depth=10, reliability=ReliabilityPolicy.RELIABLE)
pub = node.create_publisher(FingerSetpoint, "/hems/index/setpoint", qos)
deadline = time.monotonic() + 30
while time.monotonic() < deadline:
    msg = FingerSetpoint(mode=FingerSetpoint.MODE_FORCE, value=12.345)
    msg.header.frame_id = "index_tendon"
    msg.header.stamp.sec = 1234
    msg.header.stamp.nanosec = 567
    pub.publish(msg)
    rclpy.spin_once(node, timeout_sec=0.05)
"""

SUBSCRIBER = r"""
import json, os, rclpy
from rclpy.qos import QoSProfile, ReliabilityPolicy
from hems_msgs.msg import FingerSetpoint
rclpy.init()
node = rclpy.create_node("test_setpoint_subscriber")
got = []
qos = QoSProfile(depth=10, reliability=ReliabilityPolicy.RELIABLE)
node.create_subscription(FingerSetpoint, "/hems/index/setpoint", got.append, qos)
while not got:
    rclpy.spin_once(node, timeout_sec=0.1)
m = got[0]
print(json.dumps({"pid": os.getpid(), "mode": m.mode, "value": m.value,
                  "frame_id": m.header.frame_id, "sec": m.header.stamp.sec,
                  "nanosec": m.header.stamp.nanosec}))
"""


def test_setpoint_crosses_between_two_processes(venv):
    python = str(venv / "bin" / "python")
    publisher = subprocess.Popen([python, "-c", PUBLISHER])
    try:
        received = subprocess.run(
            [python, "-c", SUBSCRIBER], capture_output=True, text=True, timeout=60
        )
    finally:
        stop_process(publisher, 10.0)
    assert received.returncode == 0, received.stderr
    fields = json.loads(received.stdout.strip().splitlines()[-1])
    assert fields["pid"] not in (publisher.pid, None)
    assert fields["mode"] == "force"
    assert fields["value"] == 12.345
    assert fields["frame_id"] == "index_tendon"
    assert (fields["sec"], fields["nanosec"]) == (1234, 567)


def test_hems_ping_round_trips_through_a_responder_process(venv):
    started = time.monotonic()
    result = subprocess.run(
        [str(venv / "bin" / "hems"), "ping", "--count", "30", "--rate", "100"],
        capture_output=True,
        text=True,
        timeout=60,
    )
    assert result.returncode == 0, result.stdout + result.stderr
    assert "30/30 answers over DDS" in result.stdout
    assert time.monotonic() - started < 60


def test_import_rclpy_and_messages_in_the_venv(venv):
    result = subprocess.run(
        [
            str(venv / "bin" / "python"),
            "-c",
            "import rclpy, hems_msgs.msg; print(hems_msgs.msg.SupervisorStatus.ESTOP)",
        ],
        capture_output=True,
        text=True,
        timeout=60,
    )
    assert result.returncode == 0, result.stderr
    assert result.stdout.strip() == "4"
