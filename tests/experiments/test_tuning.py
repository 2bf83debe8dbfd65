"""`hems tune`: BPID gains tuned on the chapter 5 model, and the params file that takes them
to the graph's finger controllers."""

from __future__ import annotations

import subprocess
import time

import pytest
import yaml

from hems_ros.control import TABLE_5_1
from hems_ros.experiments.dissertation import CH6_POSITION
from hems_ros.experiments.tuning import compare, params_file_text, rig, tune_bpid
from hems_ros.processes import stop_process


@pytest.fixture(scope="module")
def tuned():
    return tune_bpid("ch5_step", macsi_weight=0.1, max_evaluations=12)


def test_tuning_lowers_the_cost_from_table_5_1(tuned):
    gains, before, after = tuned
    assert before == pytest.approx(
        5.418, abs=0.01
    )  # RMSE 5.371 mm + 0.1 x MACSI 0.47 % on the step
    assert after < before - 0.05
    assert gains != TABLE_5_1["bpid"] and gains.ki == 0.0


def test_a_chapter_6_protocol_tunes_on_the_unit_the_graph_simulates():
    assert rig("ch6_position_step") == ("ch6_hems_index", CH6_POSITION)
    assert rig("ch5_staircase")[0] == "ch5_straight_40n"
    with pytest.raises(ValueError, match="cannot tune on 'ch6_force_step'"):
        rig("ch6_force_step")
    gains, before, after = tune_bpid("ch6_position_step", max_evaluations=12)
    assert before == pytest.approx(
        0.364 + 0.1 * 0.215, abs=0.005
    )  # Table 6.1 run: RMSE 0.364 mm, MACSI 0.21 %
    assert after < before
    rows = compare(gains, "ch6_position_step")
    assert [p for p, _, _ in rows] == list(CH6_POSITION)
    assert rows[2][1]["rmse"] == pytest.approx(0.364, abs=0.001)


def test_params_file_gives_the_finger_controllers_the_tuned_gains(
    tuned, tmp_path, venv, ros_domain_id
):
    import rclpy
    from rclpy.parameter_client import AsyncParameterClient

    from hems_ros.client.graph_client import GraphClient
    from hems_ros.launcher import Graph, GraphOptions

    gains = tuned[0]
    path = tmp_path / "tuned.yaml"
    path.write_text(params_file_text(gains, "tuned here\nsecond line"))
    loaded = yaml.safe_load(path.read_text())["/**"]["ros__parameters"]
    assert (
        loaded["gains.kp"] == gains.kp
        and loaded["gains.kb"] == gains.kb
        and loaded["strategy"] == "bpid"
    )

    command = Graph(
        GraphOptions(
            fingers=("index",), extra_params_files=(path,), composed=False, log_level="error"
        )
    ).commands()["finger_controller_index"]
    assert command.count("--params-file") == 2 and command[-1] != str(path)
    process = subprocess.Popen(command)
    try:
        with GraphClient("tuned_params_probe") as probe:
            client = AsyncParameterClient(probe.node, "/hems/finger_controller_index")
            assert client.wait_for_services(
                timeout_sec=30
            ), "finger_controller_index offers no parameter services"
            future = client.get_parameters(["gains.kp", "gains.kd", "gains.kb", "ts"])
            deadline = time.monotonic() + 10
            while not future.done() and time.monotonic() < deadline:
                rclpy.spin_once(probe.node, timeout_sec=0.1)
        values = [v.double_value for v in future.result().values]
        # the tuned gains over config/hems.yaml, whose other settings (ts) still hold
        assert values == [gains.kp, gains.kd, gains.kb, 0.01]
    finally:
        stop_process(process, 10.0)
