"""`--no-parameter-services` (hems_ros.ros.runner): a node started with it offers no
parameter services, one started without it offers the six that `ros2 param` calls; both
keep their own services."""

from __future__ import annotations

import signal
import subprocess
import time

PARAMETER_SERVICES = {
    "describe_parameters",
    "get_parameter_types",
    "get_parameters",
    "list_parameters",
    "set_parameters",
    "set_parameters_atomically",
}


def test_a_node_started_without_parameter_services_offers_none(venv, ros_domain_id, context):
    from rclpy.node import Node, NodeNameNonExistentError

    started = {
        name: subprocess.Popen(
            [
                str(venv / "bin" / "python"),
                "-m",
                "hems_ros.nodes.supervisor",
                *flags,
                "--ros-args",
                "-r",
                f"__node:={name}",
                "--log-level",
                "error",
            ]
        )
        for name, flags in (("sup_plain", []), ("sup_lean", ["--no-parameter-services"]))
    }
    probe = Node("parameter_services_probe", context=context)
    try:

        def offered(name: str) -> set[str]:
            try:
                return {
                    s.rsplit("/", 1)[1]
                    for s, _ in probe.get_service_names_and_types_by_node(name, "/hems")
                }
            except NodeNameNonExistentError:  # not discovered yet
                return set()

        deadline = time.monotonic() + 30
        while not (
            PARAMETER_SERVICES | {"get_type_description"} <= offered("sup_plain")
            and "get_type_description" in offered("sup_lean")
        ):
            assert (
                time.monotonic() < deadline
            ), f"not discovered: {offered('sup_plain')}, {offered('sup_lean')}"
            assert all(p.poll() is None for p in started.values()), "a node exited"
            time.sleep(0.2)
        time.sleep(1.0)  # whatever else the lean node would announce has come by now
        assert not PARAMETER_SERVICES & offered("sup_lean")
    finally:
        probe.destroy_node()
        for process in started.values():
            process.send_signal(signal.SIGINT)
        for process in started.values():
            process.wait(timeout=10)
