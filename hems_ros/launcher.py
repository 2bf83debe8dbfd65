"""Starting and stopping the HEMS graph as child processes (no rclpy here).

Each node runs as its own process (``lib/hems_ros/<executable>`` in the prefix, like
``ros2 run``), or all of them in one process on one thread (``--composed``:
hems_ros/nodes/composed.py). Children die with the launcher even if it is killed (PR_SET_PDEATHSIG),
and :meth:`Graph.stop` ends every child within ``grace_s`` (SIGINT, then SIGKILL). Before a
start, the Fast DDS files that killed processes left in /dev/shm are removed
(hems_ros/fastdds_files.py).
"""

from __future__ import annotations

import subprocess
import sys
from dataclasses import dataclass, field
from pathlib import Path

from hems_ros.fastdds_files import remove_orphans
from hems_ros.graph import names
from hems_ros.paths import config_path
from hems_ros.processes import exit_description, stop_processes
from hems_ros.ros.runner import NO_PARAMETER_SERVICES_FLAG
from hems_ros.rosenv import child_environment, die_with_parent


def default_params_file() -> Path:
    """config/hems.yaml of the source tree, or of share/hems_ros when installed elsewhere."""
    return config_path("hems.yaml")


@dataclass
class GraphOptions:
    params_file: Path = field(default_factory=default_params_file)
    # applied after params_file, each over the ones before (ROS takes the last value of a
    # parameter): the gains `hems tune --write-params` writes, a lab's own overrides
    extra_params_files: tuple[Path, ...] = ()
    # one process for all nodes (hems_ros/nodes/composed.py): the default layout, a third of
    # the CPU and a tenth of the memory of sixteen processes (docs/design.md); False: each
    # node in its own process, as `ros2 run` starts them
    composed: bool = True
    sim_time: bool = False
    rate: float = 1.0
    fingers: tuple[str, ...] = names.FINGERS
    # every node's namespace (two hands in one domain: /left and /right)
    namespace: str = names.NAMESPACE
    extra_ros_args: tuple[str, ...] = ()
    log_level: str = "info"
    # False: the separate processes start without parameter services (no `ros2 param`), which
    # makes a process joining the domain cost them less (hems_ros.ros.runner); the composed
    # process, one participant, keeps them
    parameter_services: bool = True


def node_specs(options: GraphOptions) -> list[tuple[str, str, dict[str, str]]]:
    """(executable, node name, parameters) for the requested fingers (all 16 nodes by default)."""
    wanted = set(options.fingers)
    specs = []
    for executable, node, params in names.node_names():
        if "finger" in params and params["finger"] not in wanted:
            continue
        if "module" in params and not wanted & set(names.MODULES[params["module"]]):
            continue
        if executable == "supervisor" and wanted != set(names.FINGERS):
            params = {"fingers": "[" + ",".join(f for f in names.FINGERS if f in wanted) + "]"}
        specs.append((executable, node, params))
    return specs


def common_ros_arguments(options: GraphOptions) -> list[str]:
    """The ROS arguments every node process gets, separate or composed."""
    args = ["--ros-args", "--params-file", str(options.params_file)]
    for extra in options.extra_params_files:
        args += ["--params-file", str(extra)]
    return args + namespace_arguments(options) + ["--log-level", options.log_level]


def namespace_arguments(options: GraphOptions) -> list[str]:
    return [] if options.namespace == names.NAMESPACE else ["-r", f"__ns:={options.namespace}"]


def ros_arguments(node: str, params: dict[str, str], options: GraphOptions) -> list[str]:
    args = common_ros_arguments(options) + ["-r", f"__node:={node}"]
    for key, value in params.items():
        args += ["-p", f"{key}:={value}"]
    if options.sim_time:
        args += ["-p", "use_sim_time:=true", "-p", "lockstep:=true"]
    return args + list(options.extra_ros_args)


def executable_path(executable: str) -> list[str]:
    installed = Path(sys.prefix) / "lib" / "hems_ros" / executable
    if installed.is_file():
        return [str(installed)]
    return [sys.executable, "-m", f"hems_ros.nodes.{executable}"]


def warm_physics_cache(env: dict[str, str]) -> None:
    """Load the physics kernel the units and controllers step with, once, before they start.

    With the kernel compiled ahead of time by `make setup` (hems_ros.physics.compiled) this
    loads no numba and costs a fraction of a second. It matters when that module is missing or
    was built from other sources (the physics edited without `make setup`, or another commit's
    tree: benchmarks/bench_graph_ab.py): the nodes then fall back to numba's JIT kernel, and
    without this every one of them would compile it at the same time, which starves the whole
    graph of CPU for tens of seconds. The fallback's warning is then printed here first.
    """
    done = subprocess.run(
        [
            sys.executable,
            "-c",
            "from hems_ros.physics import ActuationUnit; ActuationUnit().step(duty=0.0)",
        ],
        env=env,
        process_group=0,
    )
    if done.returncode:
        raise RuntimeError(f"the physics kernel did not load (exit code {done.returncode})")


class Graph:
    """The running graph: child processes, started by :meth:`start`, ended by :meth:`stop`."""

    def __init__(self, options: GraphOptions) -> None:
        self.options = options
        self.processes: dict[str, subprocess.Popen] = {}
        self.node_env: dict[str, dict[str, str]] = {}
        self.killed: list[str] = []  # children that needed SIGKILL at the last stop
        # Fast DDS files of killed processes removed before the start (fastdds_files.py)
        self.orphans_removed = 0

    def commands(self) -> dict[str, list[str]]:
        specs = node_specs(self.options)
        commands = {}
        if self.options.sim_time:
            commands["sim_clock"] = [
                sys.executable,
                "-m",
                "hems_ros.nodes.sim_clock",
                "--ros-args",
                "-p",
                f"rate:={self.options.rate}",
                "-p",
                "fingers:=" + ",".join(self.options.fingers),
                *namespace_arguments(self.options),
            ]
        if self.options.composed:
            spec_args = [
                f"{exe}:{node}:" + ",".join(f"{k}={v}" for k, v in params.items())
                for exe, node, params in specs
            ]
            commands["composed"] = (
                [sys.executable, "-m", "hems_ros.nodes.composed", *spec_args]
                + common_ros_arguments(self.options)
                + (
                    ["-p", "use_sim_time:=true", "-p", "lockstep:=true"]
                    if self.options.sim_time
                    else []
                )
                + list(self.options.extra_ros_args)
            )
        else:
            for executable, node, params in specs:
                flags = [] if self.options.parameter_services else [NO_PARAMETER_SERVICES_FLAG]
                commands[node] = (
                    executable_path(executable) + flags + ros_arguments(node, params, self.options)
                )
        return commands

    def start(self, node_env: dict[str, dict[str, str]] | None = None) -> None:
        """Start every node's process; ``node_env`` adds variables to the environment of the
        named ones (benchmarks/bench_graph_ab.py runs some nodes on another commit's code)."""
        self.node_env = dict(node_env or {})
        self.orphans_removed = remove_orphans()
        warm_physics_cache(child_environment())
        for name, command in self.commands().items():
            self._spawn(name, command)

    def restart(self, name: str) -> None:
        """Start the named node's process again (after it died or was killed)."""
        old = self.processes[name]
        if old.poll() is None:
            raise RuntimeError(f"{name} is still running (pid {old.pid})")
        self._spawn(name, self.commands()[name])

    def environment(self, name: str) -> dict[str, str]:
        """The environment the named node's process starts with."""
        return {**child_environment(), **self.node_env.get(name, {})}

    def _spawn(self, name: str, command: list[str]) -> None:
        # a process group of its own: a Ctrl-C in the terminal reaches the launcher only, which
        # stops every node itself (stop), whatever each was doing, loading rclpy included
        self.processes[name] = subprocess.Popen(
            command, env=self.environment(name), preexec_fn=die_with_parent, process_group=0
        )

    def exited(self) -> dict[str, int]:
        return {name: p.returncode for name, p in self.processes.items() if p.poll() is not None}

    def with_exits(self, message: str) -> str:
        """``message`` followed by the nodes that have exited and their exit codes, if any:
        what to print when the graph does not come up (the supervisor names the missing
        streams, not a node that died at start-up)."""
        exited = sorted(self.exited().items())
        if not exited:
            return message
        return (
            f"{message} (exited: "
            + ", ".join(f"{name} {exit_description(code)}" for name, code in exited)
            + ")"
        )

    def stop(self, grace_s: float = 2.5) -> dict[str, int]:
        """SIGTERM every child, SIGKILL what is left after ``grace_s``; return exit codes."""
        killed = stop_processes(self.processes.values(), grace_s)
        self.killed = [name for name, p in self.processes.items() if p in killed]
        return {name: p.returncode for name, p in self.processes.items()}

    def __enter__(self) -> "Graph":
        self.start()
        return self

    def __exit__(self, *exc) -> None:
        self.stop()

    @property
    def pids(self) -> list[int]:
        return [p.pid for p in self.processes.values()]
