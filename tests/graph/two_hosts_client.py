"""Run inside one network namespace of tests/graph/test_two_hosts.py: enable the index finger's
graph, step it to 15 mm, read the unit's duty-command latency from /diagnostics, then e-stop
and time the unit's duty reaching 0 (its drive readings). Prints one JSON line."""

from __future__ import annotations

import json
import sys
import time

from diagnostic_msgs.msg import DiagnosticArray
from hems_msgs.msg import ControllerStatus, EncoderReading

from hems_ros.client.graph_client import GraphClient
from hems_ros.graph import names
from hems_ros.ros import qos

FINGER, TARGET_M = "index", 0.015


def main() -> int:
    out: dict = {}
    with GraphClient("two_hosts_client") as client:
        status: list[ControllerStatus] = []
        drive: list[tuple[float, float]] = []
        latency: dict[str, float] = {}

        def on_diagnostics(message: DiagnosticArray) -> None:
            for entry in message.status:
                if entry.hardware_id == f"actuation_unit_{FINGER}":
                    latency.update(
                        {
                            kv.key: float(kv.value)
                            for kv in entry.values
                            if kv.key.startswith("latency_p")
                        }
                    )

        client.node.create_subscription(
            ControllerStatus,
            names.topic(FINGER, "controller_status"),
            status.append,
            qos.CONTROLLER_STATUS,
        )
        client.node.create_subscription(
            EncoderReading,
            names.topic(FINGER, "encoder"),
            lambda m: drive.append((time.monotonic(), m.duty_percent)),
            qos.SENSOR,
        )
        client.node.create_subscription(DiagnosticArray, "/diagnostics", on_diagnostics, 10)
        ok, message = client.enable_when_ready(90.0, reset=True, retry_s=1.0)
        out["enabled"] = message
        if not ok:
            print(json.dumps(out))
            return 1
        out["setpoint_taken"] = bool(
            client.send_setpoint(FINGER, "position", TARGET_M, confirm_s=10.0).confirmed
        )
        start = time.monotonic()
        while time.monotonic() - start < 20.0 and not (
            status and abs(status[-1].measurement - TARGET_M) < 0.5e-3
        ):
            client.spin_for(0.1)
        out["reached_s"] = (
            time.monotonic() - start
            if status and abs(status[-1].measurement - TARGET_M) < 0.5e-3
            else None
        )
        latency.clear()
        client.spin_for(2.5)  # a fresh /diagnostics (1 Hz) from the hold
        out["latency_p50_s"] = latency.get("latency_p50_s")
        out["latency_p99_s"] = latency.get("latency_p99_s")
        heated_before = any(duty > 0 for _, duty in drive[-20:])
        sent = time.monotonic()
        out["estop"] = client.call("estop")[1]
        client.spin_for(1.0)
        zero = next((t for t, duty in drive if t >= sent and duty == 0.0), None)
        out["heated_before_estop"] = heated_before
        out["estop_zero_duty_s"] = None if zero is None else zero - sent
        out["heated_after"] = any(duty > 0 for t, duty in drive if t >= sent + 0.2)
    print(json.dumps(out))
    return 0


if __name__ == "__main__":
    sys.exit(main())
