"""Shared bag-test helpers: serialized hems messages with known values, bag builders."""

from __future__ import annotations

import signal
import subprocess
import sys
from pathlib import Path

HERE = Path(__file__).resolve().parent
PUBLISHER_SCRIPT = HERE / "synthetic_publisher.py"
COMMAND_SCRIPT = HERE / "command_publisher.py"
PUBLISHED = "command_publisher: published"
sys.path.insert(0, str(HERE))

FINGERS = ("index", "middle", "thumb_flexion")


def run_command_publisher(*args: str) -> None:
    """Run command_publisher.py to its end; fails unless it published everything.

    A crash inside rclpy's destroy_node after the publisher reported its work is let pass: the
    Fast DDS participant's teardown now and then ends in SIGSEGV (seen once in some hundred
    process exits of a test run), which is not what these tests are about.
    """
    from hems_ros.rosenv import child_environment

    result = subprocess.run(
        [sys.executable, str(COMMAND_SCRIPT), *args],
        env=child_environment(),
        capture_output=True,
        text=True,
        timeout=60,
    )
    assert PUBLISHED in result.stdout, result.stdout + result.stderr
    crashed_in_teardown = (
        result.returncode == -signal.SIGSEGV and "in destroy_node" in result.stderr
    )
    assert result.returncode == 0 or crashed_in_teardown, result.stderr


def wire_force(i: int):
    from hems_msgs.msg import WireForce

    # finger names of different lengths give messages of several byte layouts on one topic
    message = WireForce(
        finger=FINGERS[i % 3],
        force=0.125 * i - 3.0,
        saturated=i % 5 == 0,
        over_force=i % 7 == 0,
        sequence=i,
    )
    message.header.stamp.sec, message.header.stamp.nanosec = 100 + i // 1000, (i % 1000) * 1_000_000
    message.header.frame_id = "wire" if i % 4 else ""
    return message


def encoder(i: int):
    from hems_msgs.msg import EncoderReading

    return EncoderReading(
        finger="index", counts=-5 * i, position=-5e-6 * i, resolution=1e-6, sequence=i
    )


def actuator_state(i: int):
    from hems_msgs.msg import ActuatorState

    return ActuatorState(
        finger="index",
        duty_percent=float(i % 100),
        watchdog_tripped=i % 3 == 0,
        wire_temperature_c=20.0 + 0.5 * i,
        martensite_fraction=(i % 11) / 10,
        stress=1.5e6 * i,
        tendon_force=0.01 * i,
        sequence=i,
    )


def joint_state(i: int):
    from sensor_msgs.msg import JointState

    names = ["index", "middle"] if i % 2 else ["index"]
    return JointState(
        name=names,
        position=[i * 0.001 + k for k in range(len(names))],
        velocity=[] if i % 3 == 0 else [0.5] * len(names),
        effort=[float(i)] * len(names),
    )


def supervisor(i: int):
    from hems_msgs.msg import SupervisorStatus

    return SupervisorStatus(
        state=i % 5,
        state_name=f"S{i}",
        faults=["over force"] * (i % 3),
        fault_fingers=["index"] * (i % 2),
    )


def diagnostics(i: int):
    from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus, KeyValue

    return DiagnosticArray(
        status=[
            DiagnosticStatus(
                level=bytes([i % 3]),
                name=f"unit{k}",
                message="ok",
                values=[KeyValue(key="n", value=str(i))],
            )
            for k in range(i % 3)
        ]
    )


TOPICS = {  # topic: (type, factory)
    "/hems/index/wire_force": ("hems_msgs/msg/WireForce", wire_force),
    "/hems/index/encoder": ("hems_msgs/msg/EncoderReading", encoder),
    "/hems/sim/index/state": ("hems_msgs/msg/ActuatorState", actuator_state),
    "/hems/joint_states": ("sensor_msgs/msg/JointState", joint_state),
    "/hems/supervisor/status": ("hems_msgs/msg/SupervisorStatus", supervisor),
    "/diagnostics": ("diagnostic_msgs/msg/DiagnosticArray", diagnostics),
}
T0 = 1_700_000_000_000_000_000


def log_time(topic_index: int, i: int) -> int:
    return T0 + i * 1_000_000 + topic_index * 1000


def write_bag(
    folder: Path,
    count: int = 300,
    chunk_size: int = 4096,
    compression: str = "zstd",
    topics: dict | None = None,
) -> dict[str, list]:
    """A bag with ``count`` messages on each topic; returns the messages written per topic."""
    from rclpy.serialization import serialize_message

    from hems_ros.bag import BagWriter, offered_qos

    written: dict[str, list] = {}
    with BagWriter(folder, compression=compression, chunk_size=chunk_size) as writer:
        for k, (topic, (type_name, _)) in enumerate((topics or TOPICS).items()):
            writer.add_topic(
                topic, type_name, [offered_qos(k % 2 == 0, topic.endswith("status"), 10)]
            )
        for i in range(count):
            for k, (topic, (_, factory)) in enumerate((topics or TOPICS).items()):
                message = factory(i)
                writer.write(
                    writer.topics[topic].channel_id, log_time(k, i), serialize_message(message)
                )
                written.setdefault(topic, []).append(message)
    return written
