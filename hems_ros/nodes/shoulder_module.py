"""One HEMS shoulder module: the fixed anchor of two actuators with their two wire-force
sensors (range 0-50 N, resolution, seeded noise, saturation; dissertation chapter 6).

Subscribes  /hems/sim/<finger>/wire_tension  hems_msgs/WireForce  best effort (physical tension,
                                                                  simulation link)
Publishes   /hems/<finger>/wire_force        hems_msgs/WireForce  best effort, one reading per
                                                                  tension sample (100 Hz)

Each reading carries ``saturated`` (clipped at 0 or the range) and ``over_force``
(reading at or above ``over_force_n``). Both topics carry serialized messages
(hems_ros.ros.wire).
"""

from __future__ import annotations

from hems_msgs.msg import WireForce

from hems_ros.graph import names
from hems_ros.graph.sensor_faults import FORCE_FAULTS, FaultySensor, noise_scale
from hems_ros.physics import sensors
from hems_ros.physics.params import ForceSensor
from hems_ros.ros import qos
from hems_ros.ros.lean_node import LeanNode
from hems_ros.ros.params import Spec, declare, non_negative, one_of, positive
from hems_ros.ros.runner import run_node
from hems_ros.ros.wire import codec

_SENSOR = ForceSensor()
WIRE_FORCE = codec(WireForce)


PARAMETERS = [
    Spec(
        "module",
        "index_middle",
        "shoulder module: " + ", ".join(names.MODULES),
        one_of(*names.MODULES),
        True,
    ),
    Spec(
        "range_max_n",
        _SENSOR.range_max_n,
        "force sensor range, N (readings clip at 0 and here)",
        positive,
        True,
    ),
    Spec("resolution_n", _SENSOR.resolution_n, "force sensor resolution, N", positive, True),
    Spec(
        "noise_std_n",
        _SENSOR.noise_std_n,
        "force sensor noise standard deviation, N",
        non_negative,
        True,
    ),
    Spec(
        "seed", _SENSOR.seed, "seed of the noise generator (each sensor adds its index)", None, True
    ),
    Spec("over_force_n", 50.0, "over-force flag threshold, N (wire side)", positive, True),
    Spec(
        "sensor_fault",
        "",
        "force-sensor fault injected from now on, for fault tests: '' (none), stuck_force "
        "(fresh samples, frozen reading), force_saturation (reads its range), force_noise_burst "
        "(noise x50), nan_force; settable while running",
        one_of(*FORCE_FAULTS),
    ),
    Spec(
        "fault_finger",
        "",
        "the finger whose sensor sensor_fault hits ('' both of the module's)",
        lambda v: None
        if v in ("", *names.FINGERS)
        else f"must be '' or one of {', '.join(names.FINGERS)}",
    ),
]


class ShoulderModuleNode(LeanNode):
    """Two wire-force sensors of one shoulder module."""

    def __init__(self, **node_kwargs) -> None:
        super().__init__("shoulder_module", namespace=names.NAMESPACE, **node_kwargs)
        self.graph_ns = self.get_namespace()
        p = declare(self, PARAMETERS)
        self.params = p
        self.publishers_ = {}
        self.sequences = {}
        self.rngs = {}
        self.sensors: dict[str, FaultySensor] = {}
        for index, finger in enumerate(names.MODULES[p["module"]]):
            self.publishers_[finger] = self.create_publisher(
                WireForce, names.topic(finger, "wire_force", self.graph_ns), qos.SENSOR
            )
            self.sequences[finger] = 0
            self.sensors[finger] = FaultySensor()
            self.rngs[finger] = sensors.noise_generator(p["seed"] + index)
            self.subscribe_serialized(
                WireForce,
                names.sim_topic(finger, "wire_tension", self.graph_ns),
                lambda tension, f=finger: self.on_tension(f, tension),
                qos.SENSOR,
            )

    def fault(self, finger: str) -> str:
        """The fault injected into ``finger``'s sensor ('' none)."""
        p = self.params
        return p["sensor_fault"] if p["fault_finger"] in ("", finger) else ""

    def on_tension(self, finger: str, tension) -> None:
        p = self.params
        fault = self.fault(finger)
        noise = self.rngs[finger].standard_normal() * p["noise_std_n"]
        if fault:
            noise *= noise_scale(fault)
        force, saturated = sensors.force_reading(
            tension.force, noise, p["range_max_n"], p["resolution_n"]
        )
        force, saturated = self.sensors[finger].force(fault, force, saturated, p["range_max_n"])
        self.sequences[finger] += 1
        self.publishers_[finger].publish(
            WIRE_FORCE.encode(
                tension._replace(
                    finger=finger,
                    force=force,
                    saturated=saturated,
                    over_force=force >= p["over_force_n"],
                    sequence=self.sequences[finger],
                )
            )
        )


def main() -> int:
    return run_node(ShoulderModuleNode)


if __name__ == "__main__":
    raise SystemExit(main())
