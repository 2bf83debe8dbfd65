"""The finger controller's parameters, declared with their descriptions and checks, and the
FingerLoop (hems_ros.graph.finger_loop) they configure."""

from __future__ import annotations

from dataclasses import fields
from typing import Any

from hems_ros.control import STRATEGIES, make_controller, mode_gains
from hems_ros.control.base import DEFAULT_N_FILTER, DEFAULT_TS
from hems_ros.graph import names, transmission
from hems_ros.graph.finger_loop import FingerLoop
from hems_ros.graph.setpoints import MODES, SetpointLimits
from hems_ros.graph.thermal_guard import ThermalGuard
from hems_ros.physics import load_params
from hems_ros.ros.lean_node import LeanNode
from hems_ros.ros.params import PERIOD_LIMIT, Spec, declare, non_negative, one_of, positive

PARAMETERS = [
    Spec(
        "finger",
        "index",
        "finger this controller drives: " + ", ".join(names.FINGERS),
        one_of(*names.FINGERS),
        True,
    ),
    Spec("strategy", "bpid", "control law: bpid | pid | pipd", one_of(*STRATEGIES), True),
    Spec(
        "mode",
        "position",
        "initial mode: position | force (setpoints may switch it)",
        one_of(*MODES),
        True,
    ),
    Spec("ts", DEFAULT_TS, "control period Ts, s", PERIOD_LIMIT, True),
    Spec("n_filter", DEFAULT_N_FILTER, "derivative filter pole N, rad/s", positive, True),
    Spec(
        "pulley_ratio",
        transmission.PULLEY_RATIO,
        "tendon / wire displacement ratio of the slider pulley",
        positive,
        True,
    ),
    Spec(
        "max_position_m",
        SetpointLimits.max_position_m,
        "largest accepted tendon position setpoint, m",
        positive,
        True,
    ),
    Spec(
        "max_force_n",
        SetpointLimits.max_force_n,
        "largest accepted tendon force setpoint, N",
        positive,
        True,
    ),
    Spec(
        "idle_status_period_s",
        0.1,
        "status period while no feedback arrives, s (otherwise one per duty)",
        PERIOD_LIMIT,
        True,
    ),
    Spec(
        "status_every",
        2,
        "publish the status with every n-th duty (and whenever mode, setpoint, activity or "
        "fault change): 50 Hz keeps the supervisor's 50 ms stream checks fed at half the messages",
        positive,
        True,
    ),
    Spec(
        "feedback_lag_s",
        0.025,
        "0 % duty while the other mode's readings (force in position mode, encoder in "
        "force mode) are older than this against the feedback's, on the unit's stamps, s: without "
        "them over-force and over-travel cannot be seen; a shoulder module that stops stops a "
        "position loop within three samples (30 ms)",
        PERIOD_LIMIT,
        True,
    ),
    Spec(
        "physics_config",
        "ch6_hems_index",
        "physics parameter set of the unit (a config/physics name or a "
        "YAML path): the model the wire temperature is estimated with",
        None,
        True,
    ),
    Spec(
        "cut_temperature_c",
        150.0,
        "estimated wire temperature at which the duty is held at 0, degC "
        "(from the drive board's readings, hems_ros.graph.thermal_guard)",
        positive,
        True,
    ),
    Spec(
        "resume_temperature_c",
        140.0,
        "estimated wire temperature below which heating may resume, degC",
        positive,
        True,
    ),
]


def declare_loop(node: LeanNode) -> tuple[dict[str, Any], FingerLoop]:
    """Declare every parameter of the node (invalid ones raise ValueError naming them) and
    build the loop they configure."""
    p = declare(node, PARAMETERS)
    gains = {mode: _declare_gains(node, p["strategy"], mode) for mode in MODES}
    try:
        guard = ThermalGuard(
            load_params(p["physics_config"]),
            p["cut_temperature_c"],
            p["resume_temperature_c"],
            p["ts"],
        )
    except (OSError, ValueError) as error:
        raise ValueError(
            f"parameters 'physics_config', 'cut_temperature_c', 'resume_temperature_c': {error}"
        ) from None
    controller = make_controller(
        p["strategy"], p["mode"], gains[p["mode"]], ts=p["ts"], n_filter=p["n_filter"]
    )
    limits = SetpointLimits(p["max_position_m"], p["max_force_n"])
    return p, FingerLoop(controller, gains, limits, p["pulley_ratio"], p["feedback_lag_s"], guard)


def _declare_gains(node: LeanNode, strategy: str, mode: str) -> Any:
    """The ``gains.*`` (position) or ``force_gains.*`` parameters, defaults from the core."""
    default = mode_gains(strategy, mode)
    prefix = "gains" if mode == "position" else "force_gains"
    values = declare(
        node,
        [
            Spec(
                f"{prefix}.{f.name}",
                float(getattr(default, f.name)),
                f"{strategy} {mode}-mode gain {f.name} (default hems_ros.control.mode_gains; "
                f"errors scaled per the gains' {mode}_scale)",
                non_negative,
                True,
            )
            for f in fields(default)
        ],
    )
    return type(default)(**{name.split(".", 1)[1]: value for name, value in values.items()})
