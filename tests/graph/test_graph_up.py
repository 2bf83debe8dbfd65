"""`hems up` starts its node processes (one composed, or 16 with --separate) and Ctrl-C stops
all of them, and the readiness watcher, within 3 s."""

import os
import signal
import subprocess
import time

import pytest

pytestmark = [pytest.mark.slow, pytest.mark.graph_realtime]


def children_of(pid: int) -> set[int]:
    found = set()
    for entry in os.listdir("/proc"):
        if entry.isdigit():
            try:
                with open(f"/proc/{entry}/stat") as stat:
                    if int(stat.read().rsplit(")", 1)[1].split()[1]) == pid:
                        found.add(int(entry))
            except (OSError, ValueError, IndexError):
                continue
    return found


def is_node(pid: int) -> bool:
    try:
        with open(f"/proc/{pid}/cmdline") as cmdline:
            text = cmdline.read()
    except OSError:
        return False
    return "lib/hems_ros/" in text or "hems_ros.nodes.composed" in text


@pytest.mark.parametrize("layout, nodes", [([], 1), (["--separate"], 16)])
def test_up_then_ctrl_c_leaves_no_process_after_3_seconds(venv, layout, nodes):
    up = subprocess.Popen(
        [str(venv / "bin" / "hems"), "up", *layout, "--log-level", "warn"],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )
    deadline = time.monotonic() + 60
    children: set[int] = set()
    while time.monotonic() < deadline and sum(map(is_node, children)) < nodes:
        time.sleep(0.5)
        children = children_of(up.pid)
    assert sum(map(is_node, children)) == nodes, f"{len(children)} processes"
    time.sleep(5.0)
    started = time.monotonic()
    up.send_signal(signal.SIGINT)
    up.wait(10)
    while (
        any(os.path.exists(f"/proc/{pid}") for pid in children) and time.monotonic() - started < 10
    ):
        time.sleep(0.02)
    elapsed = time.monotonic() - started
    left = [pid for pid in children if os.path.exists(f"/proc/{pid}")]
    assert not left, f"still running: {left}"
    assert elapsed <= 3.0, f"stopping took {elapsed:.2f} s"
