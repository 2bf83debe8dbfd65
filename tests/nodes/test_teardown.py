"""A process whose ROS teardown wedges (as Fast DDS's participant destruction can, spinning a
core with the GIL held) is ended by the teardown's timer; a teardown that returns disarms it."""

from __future__ import annotations

import signal
import subprocess
import sys
import textwrap

from hems_ros.rosenv import child_environment

SCRIPT = textwrap.dedent("""
    import sys, time
    import rclpy
    from hems_ros.ros import teardown

    teardown.TEARDOWN_S = 1.0
    rclpy.init()
    node = rclpy.create_node("teardown_test")
    if sys.argv[1] == "wedged":
        def spin_forever():
            while True:
                pass
        node.destroy_node = spin_forever
    teardown.end_ros([node])
    time.sleep(2.0)  # past the timer: a timer left armed would end the process here
    print("ended normally", flush=True)
""")


def _run(mode: str) -> subprocess.CompletedProcess:
    return subprocess.run(
        [sys.executable, "-c", SCRIPT, mode],
        env=child_environment(),
        capture_output=True,
        text=True,
        timeout=60,
    )


def test_a_wedged_teardown_ends_the_process_by_its_timer():
    done = _run("wedged")
    assert done.returncode == -signal.SIGALRM, (done.returncode, done.stderr)
    assert "ended normally" not in done.stdout


def test_a_teardown_that_returns_leaves_the_process_running():
    done = _run("normal")
    assert done.returncode == 0, done.stderr
    assert "ended normally" in done.stdout
