"""All nodes of the graph in one process (`hems up --composed`), on one thread.

The nodes spin on lean_spin.spin_nodes: one wait set for all of them, callbacks called in
turn. Python runs one thread at a time, and the callbacks are short, so threads only add
contention for the interpreter lock. Measured on the full graph here (bench_graph.py,
30 s): rclpy's MultiThreadedExecutor faulted within the run; a lean loop per shoulder
module on its own thread gave p99 9.6-35 ms and 0.4-6.5 % missed periods where this one
thread gave 4.9-5.1 ms and under 0.1 %. A node the lean loop cannot serve puts every node on
the multi-threaded executor instead.

Usage: python -m hems_ros.nodes.composed <executable>:<node name>:<k=v,...> ... [--ros-args ...]
Each node gets its own name and parameters as node-level arguments; the global
``--ros-args`` (params file, use_sim_time) apply to all of them.
"""

from __future__ import annotations

import sys

from hems_ros.ros import lean_spin
from hems_ros.ros.runner import freeze_long_lived_objects
from hems_ros.ros.teardown import end_ros
from hems_ros.rosenv import apply_network_defaults, skip_code_generators

NODE_CLASSES = {
    "actuation_unit": ("hems_ros.nodes.actuation_unit", "ActuationUnitNode"),
    "shoulder_module": ("hems_ros.nodes.shoulder_module", "ShoulderModuleNode"),
    "finger_controller": ("hems_ros.nodes.finger_controller", "FingerControllerNode"),
    "supervisor": ("hems_ros.nodes.supervisor", "SupervisorNode"),
}


def parse_spec(spec: str) -> tuple[str, str, list[str]]:
    executable, node, params = spec.split(":", 2)
    args = ["--ros-args", "-r", f"__node:={node}"]
    for pair in filter(None, _split_params(params)):
        key, value = pair.split("=", 1)
        args += ["-p", f"{key}:={value}"]
    return executable, node, args


def _split_params(text: str) -> list[str]:
    """Split k=v pairs on commas outside brackets (list values such as [index,middle])."""
    parts, depth, current = [], 0, ""
    for char in text:
        depth += char == "["
        depth -= char == "]"
        if char == "," and depth == 0:
            parts.append(current)
            current = ""
        else:
            current += char
    return parts + [current]


def main(argv: list[str] | None = None) -> int:
    apply_network_defaults()
    skip_code_generators()
    import importlib

    import rclpy
    from rclpy.executors import ExternalShutdownException, MultiThreadedExecutor

    argv = sys.argv[1:] if argv is None else argv
    split = argv.index("--ros-args") if "--ros-args" in argv else len(argv)
    specs, ros_args = argv[:split], argv[split:]
    rclpy.init(args=["composed", *ros_args])
    nodes = []
    try:
        for spec in specs:
            executable, node_name, cli_args = parse_spec(spec)
            module, cls = NODE_CLASSES[executable]
            nodes.append(getattr(importlib.import_module(module), cls)(cli_args=cli_args))
        # No defer_middleware_threads here (runner.run_node does it): the nodes share one
        # participant, whose messages to each other go from writer to reader without a
        # listener thread, and three alternating runs showed no gain.
        freeze_long_lived_objects()
        if all(lean_spin.can_spin(node) for node in nodes):
            lean_spin.spin_nodes(nodes)
        else:
            lean_spin.spin_on_executor(nodes, MultiThreadedExecutor(num_threads=4))
    except (KeyboardInterrupt, ExternalShutdownException):
        pass
    except ValueError as error:
        print(f"composed: invalid configuration: {error}", file=sys.stderr)
        return 2
    finally:
        end_ros(nodes)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
