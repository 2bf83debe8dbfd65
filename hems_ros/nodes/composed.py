"""All nodes of the graph in one process (`hems up --composed`), on several threads.

One thread per shoulder module (its two units, their controllers and the module) and one for
the supervisor, each running lean_spin.spin_nodes over its nodes with one wait set: a finger's
encoder -> controller -> duty chain stays on one thread, and the threads only meet at the
interpreter lock, which each releases while it waits. rclpy's MultiThreadedExecutor, which
builds a wait set, a task and a coroutine per callback, could not keep the full graph within
its control periods here (the supervisor faulted on stale streams). A node the lean loop cannot
serve puts every node on that executor instead.

Usage: python -m hems_ros.nodes.composed <executable>:<node name>:<k=v,...> ... [--ros-args ...]
Each node gets its own name and parameters as node-level arguments; the global
``--ros-args`` (params file, use_sim_time) apply to all of them.
"""

from __future__ import annotations

import gc
import sys
import time

from hems_ros.graph import names
from hems_ros.nodes import lean_spin
from hems_ros.rosenv import apply_network_defaults

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


def thread_groups(nodes: list, cli_args: list[list[str]]) -> list[list]:
    """The nodes by shoulder module (through their finger or module parameter); the rest alone."""
    groups: dict[str, list] = {}
    for node, args in zip(nodes, cli_args):
        values = dict(args[i + 1].split(":=", 1) for i, arg in enumerate(args) if arg == "-p")
        key = values.get("module") or names.MODULE_OF.get(values.get("finger", ""), node.get_name())
        groups.setdefault(key, []).append(node)
    return list(groups.values())


def spin_in_threads(groups: list[list]) -> None:
    """lean_spin.spin_nodes for each group on its own thread, until the context shuts down."""
    import threading

    from rclpy.executors import ExternalShutdownException

    errors: list[BaseException] = []

    def run(group: list) -> None:
        try:
            lean_spin.spin_nodes(group)
        except ExternalShutdownException:
            pass
        except BaseException as error:  # noqa: BLE001 - handed to the main thread
            errors.append(error)

    # a thread woken by its wait set gets the interpreter lock within 1 ms, not Python's 5 ms
    sys.setswitchinterval(0.001)
    threads = [threading.Thread(target=run, args=(group,), name=group[0].get_name()) for group in groups]
    for thread in threads:
        thread.start()
    # Ctrl-C shuts the context down (the threads leave within a wait timeout) and also raises
    # KeyboardInterrupt here. The nodes must not be destroyed under a running thread, so the
    # wait goes on; it polls, because an interrupted Thread.join can report a live thread as
    # finished.
    interrupted = False
    while any(thread.is_alive() for thread in threads):
        try:
            time.sleep(0.05)
        except KeyboardInterrupt:
            interrupted = True
    if interrupted:
        raise KeyboardInterrupt
    if errors:
        raise errors[0]


def main(argv: list[str] | None = None) -> int:
    apply_network_defaults()
    import importlib

    import rclpy
    from rclpy.executors import ExternalShutdownException, MultiThreadedExecutor

    argv = sys.argv[1:] if argv is None else argv
    split = argv.index("--ros-args") if "--ros-args" in argv else len(argv)
    specs, ros_args = argv[:split], argv[split:]
    rclpy.init(args=["composed", *ros_args])
    executor = None
    nodes = []
    try:
        for spec in specs:
            executable, node_name, cli_args = parse_spec(spec)
            module, cls = NODE_CLASSES[executable]
            nodes.append(getattr(importlib.import_module(module), cls)(cli_args=cli_args))
        gc.collect()
        gc.freeze()     # as runner.run_node: keeps full collections short
        if all(lean_spin.can_spin(node) for node in nodes):
            spin_in_threads(thread_groups(nodes, [parse_spec(spec)[2] for spec in specs]))
        else:
            executor = MultiThreadedExecutor(num_threads=4)
            for node in nodes:
                executor.add_node(node)
            executor.spin()
    except (KeyboardInterrupt, ExternalShutdownException):
        pass
    except ValueError as error:
        print(f"composed: invalid configuration: {error}", file=sys.stderr)
        return 2
    finally:
        if executor is not None:
            executor.shutdown()
        for node in nodes:
            node.destroy_node()
        rclpy.try_shutdown()
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
