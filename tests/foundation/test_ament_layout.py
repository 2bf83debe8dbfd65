"""The venv is an ament prefix: `ros2 run hems_ros <executable>` resolves there."""

from __future__ import annotations

import os
import signal
import subprocess
import time

import pytest

from hems_ros.executables import EXECUTABLES

NODE_EXECUTABLES = sorted(
    name for name, target in EXECUTABLES.items() if target.startswith("hems_ros.nodes.")
)


def test_package_index_entry_and_share_folder(venv):
    marker = venv / "share" / "ament_index" / "resource_index" / "packages" / "hems_ros"
    assert marker.is_file()
    assert (venv / "share" / "hems_ros" / "package.xml").is_file()
    assert (venv / "share" / "hems_ros" / "config").is_dir()
    assert (venv / "share" / "ament_index" / "resource_index" / "packages" / "hems_msgs").is_file()


def test_ament_index_resolves_the_prefix_as_ros2_run_does(venv):
    script = (
        "from ament_index_python.packages import get_package_prefix; "
        "print(get_package_prefix('hems_ros'))"
    )
    env = dict(os.environ, AMENT_PREFIX_PATH=str(venv))
    result = subprocess.run(
        [str(venv / "bin" / "python"), "-c", script],
        env=env,
        capture_output=True,
        text=True,
        timeout=60,
    )
    assert result.returncode == 0, result.stderr
    assert os.path.realpath(result.stdout.strip()) == os.path.realpath(venv)


@pytest.mark.parametrize("name", sorted(EXECUTABLES))
def test_every_executable_is_installed_and_answers_help(venv, name):
    for folder in ("lib/hems_ros", "bin"):
        path = venv / folder / name
        assert path.is_file() and os.access(path, os.X_OK), f"{path} missing or not executable"
    result = subprocess.run(
        [str(venv / "lib" / "hems_ros" / name), "--help"],
        capture_output=True,
        text=True,
        timeout=60,
    )
    assert result.returncode == 0, result.stderr
    assert result.stdout.startswith("usage:")


@pytest.mark.parametrize("name", NODE_EXECUTABLES)
def test_every_node_starts_and_stops_cleanly_on_sigint_and_sigterm(venv, name, tmp_path):
    for stop in (signal.SIGINT, signal.SIGTERM):
        # run in a scratch folder: a recorder started without `output` writes its bag to the cwd
        process = subprocess.Popen(
            [str(venv / "lib" / "hems_ros" / name), "--ros-args", "--log-level", "warn"],
            stdout=subprocess.PIPE,
            stderr=subprocess.PIPE,
            text=True,
            cwd=tmp_path,
        )
        time.sleep(3.0)
        assert process.poll() is None, f"{name} exited early: {process.communicate()[1]}"
        started = time.monotonic()
        process.send_signal(stop)
        _, stderr = process.communicate(timeout=10)
        assert (
            process.returncode == 0
        ), f"{name} on {stop.name}: exit {process.returncode}: {stderr}"
        assert time.monotonic() - started < 3.0
        assert "Traceback" not in stderr


@pytest.mark.parametrize(
    "name", ["actuation_unit", "finger_controller", "shoulder_module", "supervisor", "sim_clock"]
)
def test_a_node_help_lists_every_parameter_with_its_default(name):
    import importlib

    from hems_ros.ros.runner import node_help

    module = importlib.import_module(f"hems_ros.nodes.{name}")
    node_class = next(
        v
        for v in vars(module).values()
        if isinstance(v, type)
        and v.__module__ == module.__name__
        and hasattr(v, "__init__")
        and v.__name__.endswith("Node")
    )
    text = node_help(node_class, name)
    assert module.PARAMETERS
    for spec in module.PARAMETERS:
        assert f"  {spec.name} (default {spec.default!r}" in text, spec.name
