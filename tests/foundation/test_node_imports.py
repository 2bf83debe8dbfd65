"""The graph's node processes load neither numba nor llvmlite nor scipy (about 120 MB each):
importing a node's module and running the physics it builds stays on numpy and the kernel
compiled ahead of time (hems_ros/physics/compiled.py). Units, controllers and the supervisor
load no OpenSSL either (3 MB, through hashlib); a shoulder module draws sensor noise, and
numpy's generators bring it."""

from __future__ import annotations

import subprocess
import sys

import pytest

UNIT = """
from hems_ros.graph.unit_driver import UnitDriver
from hems_ros.physics import ActuationUnit, load_params
physics = load_params("ch6_hems_index").replace({"force_sensor.noise_std_n": 0.0})
driver = UnitDriver(ActuationUnit(physics), 0.0)
driver.command(60.0, 0.0)
driver.advance(0.05)
"""
CONTROLLER = """
from hems_ros.graph.thermal_guard import ThermalGuard
from hems_ros.physics import load_params
ThermalGuard(load_params("ch6_hems_index"), 90.0, 80.0, 0.01).reading(60.0, 1.5, 12.0)
"""
MODULE = """
from hems_ros.physics import sensors
from hems_ros.physics.params import ForceSensor
sensor = ForceSensor()
sensors.force_reading(5.0, 0.0, sensor.range_max_n, sensor.resolution_n)
"""
NODES = {
    "actuation_unit": UNIT,
    "finger_controller": CONTROLLER,
    "shoulder_module": MODULE,
    "supervisor": "",
    "composed": "import hems_ros.nodes.actuation_unit, hems_ros.nodes.finger_controller\n"
    "import hems_ros.nodes.shoulder_module, hems_ros.nodes.supervisor\n" + UNIT + CONTROLLER,
}
REPORT = """
import sys
heavy = ("numba", "llvmlite", "scipy") + ({openssl})
print(" ".join(m for m in heavy if m in sys.modules) or "none")
"""


@pytest.mark.parametrize("node", sorted(NODES))
def test_a_node_process_loads_no_numba_llvmlite_or_scipy(node):
    openssl = "()" if node in ("shoulder_module", "composed") else '("_hashlib",)'
    script = f"import hems_ros.nodes.{node}\n" + NODES[node] + REPORT.format(openssl=openssl)
    done = subprocess.run(
        [sys.executable, "-W", "error", "-c", script], capture_output=True, text=True, timeout=120
    )
    # -W error: a stale compiled kernel (its fallback warns) fails here, naming `make setup`
    assert done.returncode == 0, done.stderr[-2000:]
    assert done.stdout.split() == ["none"]
