"""Nothing commanded goes unrecorded: every setpoint a controller received and every service
call of the supervisor is in the bag (/hems/<finger>/commands, /hems/supervisor/commands),
whichever tool sent it, also when the recorder had not matched the tool's writer in time to
get the setpoint itself (real DDS, a one-finger graph, the recorder in its own process)."""

from __future__ import annotations

import math
import subprocess

import numpy as np
import pytest
from bag_helpers import run_command_publisher

from hems_ros.bag import load_bag
from hems_ros.bag.recording import RecorderProcess
from hems_ros.graph import names

pytestmark = pytest.mark.slow

FINGER = "index"
CLI_SETPOINTS_MM = [2.0, 4.0, 6.0, 8.0, 10.0, 12.0]
# short-lived writers, as a user running `ros2 topic pub -r 100` until the finger takes it: the
# recorder, a third participant, may not have matched them in time
QUICK_SETPOINTS_MM = [21.0, 22.0, 23.0, 24.0]


def test_every_setpoint_and_supervisor_call_is_in_the_bag(ros_domain_id, tmp_path, venv):
    from hems_ros.client.graph_client import GraphClient
    from hems_ros.launcher import Graph, GraphOptions

    output = tmp_path / "recording"
    graph = Graph(GraphOptions(fingers=(FINGER,), composed=False, log_level="warn"))
    graph.start()
    recorder = RecorderProcess(output, regex=r"/hems/.*")
    try:
        commands = names.topic(FINGER, "commands")
        recorder.wait_for_topics([commands, names.SUPERVISOR_COMMANDS_TOPIC], timeout=60.0)
        with GraphClient("hems_test_command_records") as client:
            assert not client.fingers_without_readers((FINGER,), timeout=60.0)
            client.call("disable")
            for value in CLI_SETPOINTS_MM:
                subprocess.run(
                    [str(venv / "bin" / "hems"), "setpoint", FINGER, f"{value:g}", "--unit", "mm"],
                    capture_output=True,
                    text=True,
                    timeout=120,
                )
            for value in QUICK_SETPOINTS_MM:
                run_command_publisher(
                    "--subscribers", "1", "--value", f"{value:g}", "--until-taken"
                )
            client.call("estop")
            client.call("reset")
            client.spin_for(1.0)
    finally:
        recorder.stop()
        graph.stop()
    bag = load_bag(output)
    records = bag[names.topic(FINGER, "commands")]
    received = [v * 1e3 for v in records["value"]]
    # every value the tools sent reached the controller, and every one of them is in the bag
    expected = CLI_SETPOINTS_MM + QUICK_SETPOINTS_MM
    assert [
        v for v in expected if any(math.isclose(v, r, abs_tol=1e-9) for r in received)
    ] == expected
    assert np.array_equal(records["sequence"], np.arange(1, len(records) + 1))  # no record lost
    assert all(records["accepted"]) and set(records["command"]) == {"position"}
    supervisor = bag[names.SUPERVISOR_COMMANDS_TOPIC]
    assert list(supervisor["command"])[-3:] == ["disable", "estop", "reset"]
    assert list(supervisor["accepted"])[-3:] == [True, True, True]
