"""One HEMS shoulder module: the fixed anchor of two actuators with their two wire-force
sensors (range 0-50 N, resolution, seeded noise, saturation; digest section 1).

Subscribes  /hems/sim/<finger>/wire_tension  hems_msgs/WireForce  best effort (physical tension, simulation link)
Publishes   /hems/<finger>/wire_force        hems_msgs/WireForce  best effort, one reading per tension sample (100 Hz)

Each reading carries ``saturated`` (clipped at 0 or the range) and ``over_force``
(reading at or above ``over_force_n``); its stamp is the tension sample's. Both topics carry
serialized messages (hems_ros.nodes.wire).

On wall-clock time the module samples at its own 100 Hz instants, ``sample_delay_s`` after
its two units' tick on the clock's grid (hems_ros.graph.cadence.module_phase_s), and turns
every tension sample received since the last instant into a reading: one wake-up a period
for both sensors, where waking for each tension took one or two (the units are separate
processes, and their tensions often came apart). A tension that arrives after the instant
is read at the next one. On sim time (/clock) each tension is read when it arrives.
"""

from __future__ import annotations

from hems_msgs.msg import WireForce
from hems_ros.graph import names
from hems_ros.graph.cadence import module_phase_s
from hems_ros.nodes import qos
from hems_ros.nodes.grid_timer import create_grid_timer
from hems_ros.nodes.lean_node import LeanNode
from hems_ros.nodes.params import Spec, declare, non_negative, one_of, positive
from hems_ros.nodes.runner import run_node
from hems_ros.nodes.wire import codec
from hems_ros.physics import sensors
from hems_ros.physics.params import ForceSensor

_SENSOR = ForceSensor()
WIRE_FORCE = codec(WireForce)


PARAMETERS = [
    Spec("module", "index_middle", "shoulder module: " + ", ".join(names.MODULES), one_of(*names.MODULES), True),
    Spec("range_max_n", _SENSOR.range_max_n, "force sensor range, N (readings clip at 0 and here)", positive, True),
    Spec("resolution_n", _SENSOR.resolution_n, "force sensor resolution, N", positive, True),
    Spec("noise_std_n", _SENSOR.noise_std_n, "force sensor noise standard deviation, N", non_negative, True),
    Spec("seed", _SENSOR.seed, "seed of the noise generator (each sensor adds its index)", None, True),
    Spec("over_force_n", 50.0, "over-force flag threshold, N (wire side)", positive, True),
    Spec("sample_period_s", 0.01, "sampling period on wall-clock time, s (the units' encoder period)", positive,
         True),
    Spec("sample_delay_s", 0.002, "sampling instant after the units' tick on the clock's grid, s (wall-clock "
         "time; room for both tensions to arrive)", non_negative, True),
]


class ShoulderModuleNode(LeanNode):
    """Two wire-force sensors of one shoulder module."""

    def __init__(self, **node_kwargs) -> None:
        super().__init__("shoulder_module", namespace=names.NAMESPACE, **node_kwargs)
        p = declare(self, PARAMETERS)
        self.params = p
        self.publishers_ = {}
        self.sequences = {}
        self.rngs = {}
        self.tension_subs = []
        for index, finger in enumerate(names.MODULES[p["module"]]):
            self.publishers_[finger] = self.create_publisher(WireForce, names.topic(finger, "wire_force"), qos.SENSOR)
            self.sequences[finger] = 0
            self.rngs[finger] = sensors.noise_generator(p["seed"] + index)
            self.tension_subs.append(self.subscribe_serialized(
                WireForce, names.sim_topic(finger, "wire_tension"),
                lambda tension, f=finger: self.on_tension(f, tension), qos.SENSOR))
        self.sample_timer = None
        if not self.get_parameter("use_sim_time").value:
            if p["sample_delay_s"] >= p["sample_period_s"]:
                raise ValueError(f"parameter 'sample_delay_s' = {p['sample_delay_s']!r}: must be shorter than "
                                 f"sample_period_s ({p['sample_period_s']!r})")
            self.poll(*self.tension_subs)
            phase_s = module_phase_s(p["module"], p["sample_period_s"]) + p["sample_delay_s"]
            self.sample_timer = create_grid_timer(self, p["sample_period_s"], phase_s, self.sample)

    def sample(self) -> None:
        for subscription in self.tension_subs:
            self.drain(subscription)

    def on_tension(self, finger: str, tension) -> None:
        p = self.params
        noise = self.rngs[finger].standard_normal() * p["noise_std_n"]
        force, saturated = sensors.force_reading(tension.force, noise, p["range_max_n"], p["resolution_n"])
        self.sequences[finger] += 1
        self.publishers_[finger].publish(WIRE_FORCE.encode(tension._replace(
            finger=finger, force=force, saturated=saturated, over_force=force >= p["over_force_n"],
            sequence=self.sequences[finger])))


def main() -> int:
    return run_node(ShoulderModuleNode)


if __name__ == "__main__":
    raise SystemExit(main())
