"""The common ``main()`` of every node executable."""

from __future__ import annotations

import gc
import os
import sys
from collections.abc import Callable
from typing import Any

from hems_ros.ros.middleware_threads import defer_middleware_threads
from hems_ros.ros.teardown import end_ros
from hems_ros.rosenv import apply_network_defaults, skip_code_generators

# Every rclpy node offers six parameter services (twelve DDS endpoints, more than half of a
# graph node's), and every participant announces all of its endpoints to each process that
# joins the domain: with sixteen participants on two cores, fewer endpoints means fewer joins
# that hold the graph's streams up past the supervisor's limit (figures: docs/design.md).
# Without them `ros2 param` does not reach the node, so they stay on unless asked
# (`hems up --no-parameter-services`).
NO_PARAMETER_SERVICES_FLAG = "--no-parameter-services"


def run_node(
    make_node: Callable[..., Any],
    argv: list[str] | None = None,
    spin: Callable[[Any], None] | None = None,
    config_errors: tuple[type[Exception], ...] = (ValueError,),
) -> int:
    """Initialise rclpy, spin the node until Ctrl-C or SIGTERM, shut down cleanly.

    ``-h``/``--help`` before ``--ros-args`` prints the node's documentation and exits.
    ``--no-parameter-services`` before ``--ros-args`` starts the node without rclpy's six
    parameter services (NO_PARAMETER_SERVICES_FLAG).
    A ``config_errors`` exception (``ValueError`` by default) raised while constructing the
    node is a configuration error: it is printed with the node's name and the process exits
    with code 2. ``spin(node)`` replaces the default spin for nodes that drive their own loop.
    """
    args = sys.argv if argv is None else argv
    user_args = args[1 : args.index("--ros-args")] if "--ros-args" in args else args[1:]
    if "-h" in user_args or "--help" in user_args:
        print(node_help(make_node, args[0]))
        return 0
    node_kwargs = (
        {"start_parameter_services": False} if NO_PARAMETER_SERVICES_FLAG in user_args else {}
    )
    apply_network_defaults()
    skip_code_generators()
    import rclpy
    from rclpy.executors import ExternalShutdownException, SingleThreadedExecutor

    try:
        rclpy.init(args=args)
    except Exception as error:  # rcl reports bad arguments and params files this way
        print(f"{os.path.basename(args[0])}: cannot start: {error}", file=sys.stderr)
        return 2
    node = None
    try:
        node = make_node(**node_kwargs)
        freeze_long_lived_objects()
        defer_middleware_threads()
        if spin is None:
            from hems_ros.ros import lean_spin

            spin = (
                lean_spin.spin
                if lean_spin.can_spin(node)
                else lambda node: lean_spin.spin_on_executor([node], SingleThreadedExecutor())
            )
        spin(node)
    except (KeyboardInterrupt, ExternalShutdownException):
        pass
    except RuntimeError:
        if rclpy.ok():
            raise
        # a take interrupted by the shutdown signal: the node was stopping anyway
    except config_errors as error:
        print(
            f"{getattr(make_node, '__name__', 'node')}: invalid configuration: {error}",
            file=sys.stderr,
        )
        return 2
    finally:
        end_ros([] if node is None else [node])
    return 0


def freeze_long_lived_objects() -> None:
    """Exempt everything alive now from garbage collection; call once the nodes exist.

    Imports (rclpy, numpy, the message types) leave ~3 x 10^4 long-lived objects, 1.2 x 10^5
    in a process that runs numba's JIT kernel, that every full collection would walk, pausing
    the node for up to tens of milliseconds; frozen, the collector's pauses stay far below the
    10 ms control period."""
    gc.collect()
    gc.freeze()


def node_help(make_node: Callable[[], object], program: str) -> str:
    """Usage text of a node executable: its class documentation and the ROS argument form."""
    import inspect

    # the class says what the node is; its module documents topics, parameters and behaviour
    module = sys.modules[make_node.__module__]
    parts = [make_node.__doc__, module.__doc__]
    doc = "\n\n".join(inspect.cleandoc(part) for part in parts if part)
    specs = getattr(module, "PARAMETERS", ())
    if specs:
        doc += "\n\nParameters (-p <name>:=<value>; units in the name or the text):\n" + "\n".join(
            f"  {spec.name} (default {spec.default!r}{', read-only' if spec.read_only else ''}): "
            f"{spec.description}"
            for spec in specs
        )
    name = os.path.basename(program)
    return (
        f"usage: {name} [{NO_PARAMETER_SERVICES_FLAG}] [--ros-args -p <parameter>:=<value> ... | "
        f"--params-file <file>]\n\n{doc}\n\n{NO_PARAMETER_SERVICES_FLAG}: no parameter services "
        f"(ros2 param does not reach the node; it then costs a process joining the domain less).\n"
        "Stops cleanly on Ctrl-C (SIGINT) or SIGTERM."
    )
