"""Environment defaults every process of the project starts with.

Fast DDS multicasts discovery on every interface unless told otherwise, so the project keeps
all DDS traffic on the loopback interface unless the user explicitly chose a range. Fast DDS
reads the project's writer settings from ``config/fastdds_profiles.xml`` unless the user
named a profiles file of their own. The venv is also made an ament prefix so that package
lookups (``ros2 run``, share folders) find ``hems_ros`` and ``hems_msgs`` without sourcing
anything.
"""

from __future__ import annotations

import ctypes
import fcntl
import os
import signal
import sys
from typing import IO

from hems_ros.paths import config_path

DISCOVERY_VARIABLE = "ROS_AUTOMATIC_DISCOVERY_RANGE"
DEFAULT_DISCOVERY_RANGE = "LOCALHOST"
PROFILES_VARIABLE = "FASTDDS_DEFAULT_PROFILES_FILE"
PROFILES_FILE = "fastdds_profiles.xml"
RECORDER_PROFILES_FILE = "fastdds_recorder.xml"


PR_SET_PDEATHSIG = 1


def die_with_parent() -> None:
    """``preexec_fn`` of a child process: SIGTERM it when its parent dies, even by SIGKILL or
    a crash, so that no node or recorder of a run outlives it in the DDS domain."""
    ctypes.CDLL("libc.so.6", use_errno=True).prctl(PR_SET_PDEATHSIG, signal.SIGTERM)


def skip_code_generators() -> None:
    """Keep ROS's message code generator out of this process (call before importing rclpy).

    The type support every message loads at run time comes from rosidl_generator_py, whose
    package also imports its generator (empy, lark, the IDL parser and through lark OpenSSL:
    some 3 MB and 40 modules a process) and goes on without it when that import fails, as
    a missing module in ``sys.modules`` makes it. The graph generates no code at run time.
    """
    sys.modules.setdefault("rosidl_generator_py.generate_py_impl", None)  # type: ignore[arg-type]


def apply_network_defaults(env: dict[str, str] | os._Environ | None = None):
    """Set ``ROS_AUTOMATIC_DISCOVERY_RANGE=LOCALHOST`` and the Fast DDS profiles file (each
    unless set) and the ament prefix."""
    target = os.environ if env is None else env
    target.setdefault(DISCOVERY_VARIABLE, DEFAULT_DISCOVERY_RANGE)
    target.setdefault(PROFILES_VARIABLE, str(config_path(PROFILES_FILE)))
    prefixes = [p for p in target.get("AMENT_PREFIX_PATH", "").split(os.pathsep) if p]
    if sys.prefix not in prefixes:
        target["AMENT_PREFIX_PATH"] = os.pathsep.join(prefixes + [sys.prefix])
    return target


def child_environment(
    extra: dict[str, str] | None = None, profiles: str = PROFILES_FILE
) -> dict[str, str]:
    """A copy of this process's environment for a child process, with the defaults applied;
    ``profiles``: the project's Fast DDS profiles file the child takes unless the user named
    one of their own."""
    env = dict(os.environ)
    apply_network_defaults(env)
    # a child that dies by a signal (a crash inside the middleware or a compiled kernel)
    # prints the Python stack of each of its threads to the stderr it shares with the caller
    env.setdefault("PYTHONFAULTHANDLER", "1")
    if env[PROFILES_VARIABLE] == str(config_path(PROFILES_FILE)):
        env[PROFILES_VARIABLE] = str(config_path(profiles))
    if extra:
        env.update(extra)
    return env


# clear of 0 (everyone's default) and within the 0-101 range Fast DDS maps to ports
PRIVATE_DOMAIN_IDS = range(11, 101)


def reserve_domain_id(start: int | None = None) -> tuple[int, IO[str]]:
    """A ROS domain id no other reserving process on this machine holds, and its lock.

    Test runs and benchmarks each start whole graphs; two of them in one domain would
    answer each other's samples. The id is held (an exclusive lock on
    ``/tmp/hems-ros-domain-<id>.lock``) until the returned file is closed or the process ends.
    """
    ids = PRIVATE_DOMAIN_IDS
    first = (os.getpid() if start is None else start) % len(ids)
    for offset in range(len(ids)):
        domain = ids[(first + offset) % len(ids)]
        handle = open(f"/tmp/hems-ros-domain-{domain}.lock", "w")
        try:
            fcntl.flock(handle, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except OSError:
            handle.close()
            continue
        return domain, handle
    raise RuntimeError(f"every ROS domain id {ids.start}-{ids.stop - 1} is held by another process")


def use_private_domain() -> IO[str] | None:
    """Unless ``ROS_DOMAIN_ID`` is set, set it to a reserved id; keep the lock it returns."""
    if "ROS_DOMAIN_ID" in os.environ:
        return None
    domain, lock = reserve_domain_id()
    os.environ["ROS_DOMAIN_ID"] = str(domain)
    return lock
