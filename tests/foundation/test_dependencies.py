"""Every third-party module hems_ros imports is a declared runtime dependency (setup.py
install_requires and package.xml), and the test-only packages stay out of hems_ros."""

from __future__ import annotations

import ast
import re
import sys
from pathlib import Path

REPO = Path(__file__).resolve().parents[2]
# import name -> distribution name, where they differ
DISTRIBUTION = {"yaml": "pyyaml", "mcap_ros2": "mcap-ros2-support"}
# provided by the ROS installation (package.xml exec_depend), not by PyPI requirements
ROS = {
    "rclpy",
    "rosidl_runtime_py",
    "builtin_interfaces",
    "std_msgs",
    "sensor_msgs",
    "diagnostic_msgs",
    "std_srvs",
    "rosgraph_msgs",
    "rcl_interfaces",
    "ament_index_python",
    "hems_msgs",
}
TEST_ONLY = {"pytest", "hypothesis", "rosbags", "mcap-ros2-support", "ruff", "mypy"}


def _imported_top_levels() -> set[str]:
    names = set()
    for path in (REPO / "hems_ros").rglob("*.py"):
        for node in ast.walk(ast.parse(path.read_text(), str(path))):
            if isinstance(node, ast.Import):
                names.update(alias.name.split(".")[0] for alias in node.names)
            elif isinstance(node, ast.ImportFrom) and node.level == 0 and node.module:
                names.add(node.module.split(".")[0])
    return names


def _install_requires() -> set[str]:
    text = (REPO / "setup.py").read_text()
    block = re.search(r"install_requires=\[(.*?)\]", text, re.S).group(1)
    return set(re.findall(r'"([^"]+)"', block))


def test_every_third_party_import_is_a_declared_runtime_dependency() -> None:
    third_party = {
        n
        for n in _imported_top_levels()
        if n not in sys.stdlib_module_names and n not in ROS and n != "hems_ros"
    }
    declared = _install_requires()
    missing = sorted(n for n in third_party if DISTRIBUTION.get(n, n) not in declared)
    assert not missing, f"imported by hems_ros but not in setup.py install_requires: {missing}"
    assert not declared & TEST_ONLY
    package_xml = (REPO / "package.xml").read_text()
    for name in third_party:
        key = DISTRIBUTION.get(name, name).replace("pyyaml", "yaml")
        assert re.search(
            rf"<exec_depend>python3-{re.escape(key)}(-pip)?</exec_depend>", package_xml
        ), name
