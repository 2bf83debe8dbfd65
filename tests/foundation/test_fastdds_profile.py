"""config/fastdds_profiles.xml takes effect: Fast DDS parses it without complaint, a
reliable writer sending to a reader in another process no longer wakes its participant's
event thread at every sample (the nack-suppression timer), and a shared-memory listener
sleeps 50 ms at most (see the file's comments)."""

from __future__ import annotations

import subprocess
import sys
import textwrap
import time

from hems_ros.rosenv import PROFILES_VARIABLE, child_environment

SAMPLES = 200

# A writer process: waits for the test's reader, sends SAMPLES reliable messages at 200 Hz,
# then prints its event thread's voluntary context switches during the sending.
# The start of both test scripts: each thread's voluntary context switches, by (thread id, name).
THREAD_SWITCHES = textwrap.dedent("""
    import os

    def thread_switches():
        counts = {}
        for tid in os.listdir("/proc/self/task"):
            with open(f"/proc/self/task/{tid}/comm") as comm:
                name = comm.read().strip()
            with open(f"/proc/self/task/{tid}/status") as status:
                counts[tid, name] = sum(
                    int(line.split()[1]) for line in status if line.startswith("voluntary_ctxt")
                )
        return counts
""")

WRITER = THREAD_SWITCHES + textwrap.dedent(f"""
    import time
    import rclpy
    import rclpy.duration
    from std_msgs.msg import Int32
    from rclpy.qos import QoSProfile, ReliabilityPolicy

    def event_thread_switches():
        return sum(n for (_, name), n in thread_switches().items() if name.startswith("dds.ev"))

    rclpy.init()
    node = rclpy.create_node("profile_writer")
    qos = QoSProfile(depth={SAMPLES}, reliability=ReliabilityPolicy.RELIABLE)
    publisher = node.create_publisher(Int32, "/hems_test/profile", qos)
    deadline = time.monotonic() + 20
    while publisher.get_subscription_count() < 1 and time.monotonic() < deadline:
        time.sleep(0.05)
    time.sleep(0.5)
    before = event_thread_switches()
    for i in range({SAMPLES}):
        publisher.publish(Int32(data=i))
        time.sleep(0.005)
    print("SWITCHES", event_thread_switches() - before, flush=True)
    # a repair can wait out the 50 ms window: stay until the reader has every sample
    publisher.wait_for_all_acked(rclpy.duration.Duration(seconds=5))
""")


def event_thread_switches(env: dict[str, str]) -> tuple[int, str]:
    import rclpy
    from rclpy.qos import QoSProfile, ReliabilityPolicy
    from std_msgs.msg import Int32

    rclpy.init()
    node = rclpy.create_node("profile_reader")
    received = []
    # both histories hold every sample: a busy moment of either process then loses none
    node.create_subscription(
        Int32,
        "/hems_test/profile",
        received.append,
        QoSProfile(depth=SAMPLES, reliability=ReliabilityPolicy.RELIABLE),
    )
    writer = subprocess.Popen(
        [sys.executable, "-c", WRITER],
        env=env,
        text=True,
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
    )
    try:
        deadline = time.monotonic() + 40
        while writer.poll() is None and time.monotonic() < deadline:
            rclpy.spin_once(node, timeout_sec=0.01)
        out, err = writer.communicate(timeout=10)
    finally:
        writer.kill()
        node.destroy_node()
        rclpy.shutdown()
    assert [m.data for m in received] == list(
        range(SAMPLES)
    ), f"reader got {len(received)} of {SAMPLES}; writer said {err}"
    line = next(line for line in out.splitlines() if line.startswith("SWITCHES"))
    return int(line.split()[1]), err


def test_the_profile_parses_and_spares_the_event_thread_a_wake_up_per_sample(ros_domain_id):
    with_profile = child_environment()
    assert with_profile[PROFILES_VARIABLE].endswith("fastdds_profiles.xml")
    without = dict(with_profile, **{PROFILES_VARIABLE: ""})
    ours, err = event_thread_switches(with_profile)
    assert "XMLPARSER" not in err and "Error" not in err, err
    default, _ = event_thread_switches(without)
    # Fast DDS's default wakes the event thread at least once per sample; the profile's
    # 50 ms window at 200 Hz about twice per eleven samples
    assert default >= SAMPLES
    assert ours <= 0.5 * SAMPLES


# An idle node process: after a second to settle, the most voluntary context switches one of
# its shared-memory listener threads made in two seconds. Only the listeners of its domain's
# ports (7400 + 250 x domain onwards) count: a port's sleep is set by the process that created
# it, and every process of the host, in any domain, also listens on port 7000, which another
# process may have made (a graph with the profile running elsewhere on the host).
IDLE_LISTENER = THREAD_SWITCHES + textwrap.dedent("""
    import time
    import rclpy

    FIRST_PORT = 7400 + 250 * int(os.environ["ROS_DOMAIN_ID"])

    def listener_switches():
        return {
            key: n for key, n in thread_switches().items()
            if key[1].startswith("dds.shm.") and key[1][8:].isdigit()
            and FIRST_PORT <= int(key[1][8:]) < FIRST_PORT + 250
        }

    rclpy.init()
    node = rclpy.create_node("idle_listener")
    time.sleep(1.0)
    before = listener_switches()
    time.sleep(2.0)
    after = listener_switches()
    print("WAKES", max(after[key] - before[key] for key in before if key in after), flush=True)
""")


def idle_listener_wakes(env: dict[str, str]) -> int:
    out = subprocess.run(
        [sys.executable, "-c", IDLE_LISTENER], env=env, text=True, capture_output=True, timeout=60
    ).stdout
    return int(next(line for line in out.splitlines() if line.startswith("WAKES")).split()[1])


def test_a_shared_memory_listener_sleeps_50_ms_at_most(ros_domain_id):
    """A listener wakes on a writer's signal or at a third of healthy_check_timeout_ms; when
    a signal is lost, the message waits for that timeout (see the file's comment)."""
    with_profile = child_environment()
    default = idle_listener_wakes(dict(with_profile, **{PROFILES_VARIABLE: ""}))
    ours = idle_listener_wakes(with_profile)
    # two seconds of 333 ms sleeps (Fast DDS's default) make 6, of 50 ms sleeps 40
    assert default <= 8, default
    assert ours >= 25, ours
