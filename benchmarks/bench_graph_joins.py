"""What a process joining the ROS domain does to a running, enabled graph.

Every command-line tool (`hems setpoint`, `hems status`, `ros2 topic pub`...) is a new DDS
participant, and every participant of the graph takes part in its discovery. This runs the
enabled graph with three fingers holding 10-11 mm, then ``--joins`` times runs
`hems setpoint index ...` as a separate process, and counts the joins after which the
supervisor left ENABLED (it latches FAULT when a stream stalls for longer than its limit;
duties are then 0). After a FAULT the benchmark resets and enables through its own client,
which stays in the domain the whole run so that only the measured commands join. Modes as
in bench_graph.py: separate processes (16 participants) and composed (one);
``--no-parameter-services`` starts the separate processes as `hems up
--no-parameter-services` does (the comparison in tests/graph/README.md).

Usage: .venv/bin/python benchmarks/bench_graph_joins.py [--joins 8] [--modes separate,composed]
       [--no-parameter-services]
"""

from __future__ import annotations

import argparse
import collections
import subprocess
import sys
import time

from hems_ros.rosenv import apply_network_defaults, use_private_domain

apply_network_defaults()
DOMAIN_LOCK = use_private_domain()  # no test session or other benchmark shares it

from hems_msgs.msg import SupervisorStatus  # noqa: E402

from hems_ros.cli.graph_client import GraphClient  # noqa: E402
from hems_ros.graph import names  # noqa: E402
from hems_ros.launcher import Graph, GraphOptions  # noqa: E402
from hems_ros.nodes import qos  # noqa: E402

HOLDING = ("index", "middle", "ring")
SETTLE_S = 2.0   # after each command, before judging and before the next one


def fault_kind(fault: str) -> str:
    """'index: wire_force stale (60 ms ...)' -> 'wire_force stale'."""
    return fault.split(": ", 1)[-1].split(" (")[0].split(" for ")[0]


def hold(client: GraphClient, position_m: float) -> None:
    for finger in HOLDING:
        client.send_setpoint(finger, "position", position_m)


def run(composed: bool, joins: int, parameter_services: bool) -> dict:
    graph = Graph(GraphOptions(composed=composed, log_level="error", parameter_services=parameter_services))
    graph.start()
    faults: list[tuple[float, str]] = []

    def on_status(message: SupervisorStatus) -> None:
        if message.state_name != "ENABLED" and (not faults or faults[-1][1] != "; ".join(message.faults)):
            faults.append((time.monotonic(), "; ".join(message.faults) or message.state_name))

    try:
        with GraphClient("hems_bench_joins") as client:
            client.node.create_subscription(SupervisorStatus, names.SUPERVISOR_STATUS_TOPIC, on_status, qos.STATUS)
            ok, message = client.enable_when_ready(90, reset=True, retry_s=1.0)
            if not ok:
                return {"error": f"could not enable: {graph.with_exits(message)}"}
            hold(client, 0.010)
            client.spin_for(4.0)
            faults.clear()
            faulted, kinds = 0, collections.Counter()
            for i in range(joins):
                started, target_mm = time.monotonic(), str(10 + (i + 1) % 2)
                print(f"  join {i + 1}/{joins}: hems setpoint index {target_mm} mm", flush=True)
                # the hems command's own code path, in this interpreter (as the installed script)
                command = subprocess.run([sys.executable, "-m", "hems_ros.cli.main", "setpoint", "index", target_mm,
                                          "--mode", "position", "--unit", "mm"], capture_output=True, text=True,
                                         timeout=60)
                if command.returncode != 0:
                    return {"error": f"hems setpoint failed ({command.returncode}): {command.stderr.strip()[-300:]}"}
                client.spin_for(SETTLE_S)
                new = [text for t, text in faults if t >= started]
                if new:
                    faulted += 1
                    # the supervisor adds faults to its list as they come: count each once per join
                    kinds.update({fault_kind(part) for text in new for part in text.split("; ")})
                    ok, message = client.enable_when_ready(30, reset=True, retry_s=0.5)
                    if not ok:
                        return {"error": f"could not enable again: {message}"}
                    hold(client, 0.010)
                    client.spin_for(SETTLE_S)
    finally:
        graph.stop()
    return {"joins": joins, "faulted": faulted, "kinds": dict(kinds)}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--joins", type=int, default=8, help="command-line processes to run per mode (default 8)")
    parser.add_argument("--modes", default="separate,composed",
                        help="comma-separated modes to run: separate, composed (default both)")
    parser.add_argument("--no-parameter-services", dest="parameter_services", action="store_false",
                        help="separate processes without parameter services (hems up --no-parameter-services)")
    args = parser.parse_args()
    results = {}
    for mode in args.modes.split(","):
        print(f"{mode}: {args.joins} joins", flush=True)
        results[mode] = run(mode == "composed", args.joins, args.parameter_services)
    print("mode        joins  supervisor left ENABLED  faults named (in how many of those joins)")
    for mode, r in results.items():
        if "error" in r:
            print(f"{mode:10s}  {r['error']}")
            continue
        kinds = ", ".join(f"{k} x{n}" for k, n in sorted(r["kinds"].items())) or "-"
        print(f"{mode:10s}  {r['joins']:5d}  {r['faulted']:4d} ({100 * r['faulted'] / r['joins']:3.0f} %)"
              f"            {kinds}")


if __name__ == "__main__":
    main()
