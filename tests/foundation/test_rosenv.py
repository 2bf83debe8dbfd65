import sys

from hems_ros.rosenv import apply_network_defaults, child_environment


def test_discovery_defaults_to_localhost_and_keeps_a_user_choice():
    assert apply_network_defaults({})["ROS_AUTOMATIC_DISCOVERY_RANGE"] == "LOCALHOST"
    chosen = apply_network_defaults({"ROS_AUTOMATIC_DISCOVERY_RANGE": "SUBNET"})
    assert chosen["ROS_AUTOMATIC_DISCOVERY_RANGE"] == "SUBNET"


def test_the_interpreter_prefix_becomes_an_ament_prefix_once():
    env = apply_network_defaults({"AMENT_PREFIX_PATH": "/opt/other"})
    assert env["AMENT_PREFIX_PATH"].split(":") == ["/opt/other", sys.prefix]
    assert apply_network_defaults(dict(env))["AMENT_PREFIX_PATH"] == env["AMENT_PREFIX_PATH"]


def test_child_environment_carries_the_test_domain(ros_domain_id):
    env = child_environment({"EXTRA": "1"})
    assert env["ROS_DOMAIN_ID"] == str(ros_domain_id)
    assert env["ROS_AUTOMATIC_DISCOVERY_RANGE"] == "LOCALHOST"
    assert env["EXTRA"] == "1"
    assert 11 <= ros_domain_id <= 100


def test_a_child_that_crashes_prints_its_python_stack_and_is_named_by_its_signal():
    import subprocess

    from hems_ros.processes import exit_description

    crash = subprocess.run(
        [
            sys.executable,
            "-c",
            "import ctypes\ndef read_null():\n    ctypes.string_at(0)\nread_null()",
        ],
        env=child_environment(),
        capture_output=True,
        text=True,
    )
    assert exit_description(crash.returncode) == "killed by SIGSEGV"
    assert "Fatal Python error: Segmentation fault" in crash.stderr
    assert "in read_null" in crash.stderr
    assert exit_description(3) == "with code 3"


def test_fast_dds_reads_the_project_profiles_unless_the_user_named_a_file():
    from hems_ros.rosenv import PROFILES_VARIABLE

    path = apply_network_defaults({})[PROFILES_VARIABLE]
    assert path.endswith("config/fastdds_profiles.xml")
    assert "<nack_supression_duration>" in open(path).read()
    assert (
        apply_network_defaults({PROFILES_VARIABLE: "/tmp/mine.xml"})[PROFILES_VARIABLE]
        == "/tmp/mine.xml"
    )


def test_a_reserved_domain_is_not_given_twice_until_released() -> None:
    from hems_ros.rosenv import PRIVATE_DOMAIN_IDS, reserve_domain_id

    first, first_lock = reserve_domain_id(start=5)
    second, second_lock = reserve_domain_id(start=5)
    try:
        assert first in PRIVATE_DOMAIN_IDS and second in PRIVATE_DOMAIN_IDS
        assert second != first
        first_lock.close()
        again, again_lock = reserve_domain_id(start=5)
        again_lock.close()
        assert again == first
    finally:
        first_lock.close()
        second_lock.close()


def test_a_node_process_runs_its_messages_without_the_code_generator(ros_domain_id):
    """skip_code_generators keeps rosidl's generator (empy, lark and OpenSSL) out, and the
    messages still load and travel: a node publishes and takes one of the graph's messages."""
    import subprocess

    script = """
import sys
from hems_ros.rosenv import skip_code_generators
skip_code_generators()
import rclpy
from hems_msgs.msg import FingerSetpoint
rclpy.init()
node = rclpy.create_node("generator_free")
got = []
node.create_subscription(FingerSetpoint, "/generator_free", got.append, 10)
pub = node.create_publisher(FingerSetpoint, "/generator_free", 10)
pub.publish(FingerSetpoint(mode="position", value=0.02))
rclpy.spin_once(node, timeout_sec=2.0)
print(got[0].value, " ".join(m for m in ("em", "lark", "_hashlib") if m in sys.modules) or "none")
"""
    done = subprocess.run(
        [sys.executable, "-c", script], capture_output=True, text=True, timeout=60
    )
    assert done.returncode == 0, done.stderr[-2000:]
    assert done.stdout.split() == ["0.02", "none"]
