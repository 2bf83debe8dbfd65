"""Network defaults every process of the project starts with.

Fast DDS multicasts discovery on every interface unless told otherwise; the project keeps
all DDS traffic on the loopback interface unless the user explicitly chose a range.
"""

from __future__ import annotations

import os

DISCOVERY_VARIABLE = "ROS_AUTOMATIC_DISCOVERY_RANGE"
DEFAULT_DISCOVERY_RANGE = "LOCALHOST"


def apply_network_defaults(env: dict[str, str] | None = None) -> dict[str, str]:
    """Set ``ROS_AUTOMATIC_DISCOVERY_RANGE=LOCALHOST`` unless already set; return the env."""
    target = os.environ if env is None else env
    target.setdefault(DISCOVERY_VARIABLE, DEFAULT_DISCOVERY_RANGE)
    return target


def child_environment(extra: dict[str, str] | None = None) -> dict[str, str]:
    """A copy of this process's environment for a child process, with the defaults applied."""
    env = dict(os.environ)
    apply_network_defaults(env)
    if extra:
        env.update(extra)
    return env
