"""Closed-loop runs of many parameter sets at once, for tables of closed-loop figures.

The same loop as :func:`hems_ros.experiments.lockstep.simulate_loop` (controller at Ts
reading the encoder, duty held for Ts of plant steps), with the plant of every set advanced
by one call of the batch kernel per control sample instead of one set after the other.
"""

from __future__ import annotations

import numpy as np

from hems_ros.control import make_controller
from hems_ros.control.references import PROTOCOLS
from hems_ros.experiments.lockstep import DEFAULT_DT, figures
from hems_ros.physics import kernel
from hems_ros.physics.batch import CHANNELS
from hems_ros.physics.electrical import DRIVE_NAMES
from hems_ros.physics.params import UnitParams

TS = 0.01
_CHANNELS = np.array([CHANNELS.index("slider_position_m")], dtype=np.int64)


def run_figures(protocol: str, strategy: str, sets: list[UnitParams], dt: float = DEFAULT_DT) -> list[dict]:
    """Figures of merit (lockstep.figures, dissertation units) of ``protocol`` under
    ``strategy`` on every set; position protocols only."""
    proto = PROTOCOLS[protocol]
    if proto.mode != "position":
        raise ValueError(f"{protocol}: only position protocols are replayed in closed loop")
    t, r = proto.generate(TS)
    sub = int(round(TS / dt))
    n = len(sets)
    packed = np.ascontiguousarray(np.stack([kernel.pack(p) for p in sets]))
    states = np.ascontiguousarray(np.stack([kernel.initial_state(p) for p in sets]))
    resolution = np.array([p.encoder.resolution_m for p in sets])
    gain = np.array([p.encoder.gain for p in sets])
    controllers = [make_controller(strategy, "position") for _ in sets]
    meas, duty, pos = (np.zeros((n, t.size)) for _ in range(3))
    records = np.zeros((_CHANNELS.size, n, 1))
    failed = np.full(n, -1, dtype=np.int64)
    broken = np.zeros(n, dtype=bool)
    drives = np.zeros((n, sub))
    for k in range(t.size):
        x = states[:, kernel.S_X]
        y = np.rint(gain * x / resolution) * resolution
        u = np.array([c.update(r[k], yi) for c, yi in zip(controllers, y)])
        meas[:, k], duty[:, k], pos[:, k] = y, u, x
        drives[:] = u[:, None]
        kernel.run_batch(packed, states, DRIVE_NAMES["duty"], drives, dt, sub, _CHANNELS, records, failed)
        broken |= failed >= 0
    return [{} if broken[i] else
            figures(t, r, meas[i], duty[i], "position", proto.segment, rest=float(r[0]), y_true=pos[i])
            for i in range(n)]
