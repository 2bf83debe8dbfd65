"""The common ``main()`` of every node executable."""

from __future__ import annotations

import sys
from collections.abc import Callable

from hems_ros.rosenv import apply_network_defaults


def run_node(make_node: Callable[[], object], argv: list[str] | None = None) -> int:
    """Initialise rclpy, spin the node until Ctrl-C or SIGTERM, shut down cleanly.

    A ``ValueError`` raised while constructing the node is a configuration error: it is
    printed with the node's name and the process exits with code 2.
    """
    apply_network_defaults()
    import rclpy
    from rclpy.executors import ExternalShutdownException

    rclpy.init(args=sys.argv if argv is None else argv)
    node = None
    try:
        node = make_node()
        rclpy.spin(node)
    except (KeyboardInterrupt, ExternalShutdownException):
        pass
    except ValueError as error:
        print(f"{getattr(make_node, '__name__', 'node')}: invalid configuration: {error}", file=sys.stderr)
        return 2
    finally:
        if node is not None:
            node.destroy_node()
        rclpy.try_shutdown()
    return 0
