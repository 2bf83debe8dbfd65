"""The dissertation's results to compare against (dissertation chapters 5 and 6).

Tables 5.2-5.5 (chapter 5, straight actuator with a 40 N mass, three controllers) and
Tables 6.1-6.2 (chapter 6, HEMS index finger, BPID), keyed by the protocol names of
:data:`hems_ros.control.references.PROTOCOLS` and the figure names of
:func:`hems_ros.experiments.lockstep.figures`.
"""

from __future__ import annotations

CH5_PROTOCOLS = ("ch5_sine_0.125", "ch5_sine_0.25", "ch5_sine_0.5", "ch5_step", "ch5_staircase")
CH5_STRATEGIES = ("pid", "pipd", "bpid")
STRATEGY_LABELS = {"pid": "PID", "pipd": "PI-PD", "bpid": "BPID"}
PROTOCOL_LABELS = {
    "ch5_sine_0.125": "sine 0.125 Hz",
    "ch5_sine_0.25": "sine 0.25 Hz",
    "ch5_sine_0.5": "sine 0.5 Hz",
    "ch5_step": "step",
    "ch5_staircase": "staircase",
    "ch6_position_sine_0.125": "sine 0.125 Hz",
    "ch6_position_ramp": "ramp",
    "ch6_position_step": "step",
    "ch6_position_staircase": "staircase",
    "ch6_force_sine_0.125": "sine 0.125 Hz",
    "ch6_force_sine_0.25": "sine 0.25 Hz",
    "ch6_force_step": "step",
    "ch6_force_staircase": "staircase",
}


def _rows(values: dict[str, tuple[float, ...]]) -> dict[tuple[str, str], float]:
    return {(p, s): v[i] for s, v in values.items() for i, p in enumerate(CH5_PROTOCOLS)}


CH5_TABLES = {
    # metric key: (table title, unit, {(protocol, strategy): value}, factor ours -> table)
    "rmse": (
        "Table 5.2: RMSE",
        "mm",
        _rows(
            {
                "pid": (1.71, 4.25, 7.66, 4.40, 1.96),
                "pipd": (1.95, 3.87, 6.50, 4.27, 1.75),
                "bpid": (1.72, 3.51, 7.08, 4.10, 1.58),
            }
        ),
        1.0,
    ),
    "iae": (
        "Table 5.3: IAE (sum of |e| in mm over 10 ms samples, x1e3)",
        "x1e3 mm",
        _rows(
            {
                "pid": (1.95, 5.85, 11.79, 18.1, 7.33),
                "pipd": (2.05, 5.01, 9.44, 16.2, 6.41),
                "bpid": (2.06, 4.79, 10.72, 13.0, 5.42),
            }
        ),
        1e-3,
    ),
    "macsi": (
        "Table 5.4: MACSI",
        "% per sample",
        _rows(
            {
                "pid": (14.13, 8.81, 6.24, 0.71, 1.92),
                "pipd": (9.73, 4.88, 2.89, 0.24, 0.68),
                "bpid": (21.69, 8.37, 5.44, 1.87, 5.83),
            }
        ),
        1.0,
    ),
    "apc_w": (
        "Table 5.5: APC",
        "W",
        _rows(
            {
                "pid": (30.62, 31.54, 33.64, 10.87, 9.04),
                "pipd": (25.23, 29.83, 32.04, 10.56, 8.23),
                "bpid": (32.56, 33.62, 35.41, 11.46, 10.99),
            }
        ),
        1.0,
    ),
}

CH5_RISE_TIME_S = {"pid": 1.2, "pipd": 1.1, "bpid": 1.4}
CH5_SS_ERROR_MM = {"pid": 0.02, "pipd": 0.12, "bpid": 0.02}

CH6_POSITION = (
    "ch6_position_sine_0.125",
    "ch6_position_ramp",
    "ch6_position_step",
    "ch6_position_staircase",
)
CH6_FORCE = ("ch6_force_sine_0.125", "ch6_force_sine_0.25", "ch6_force_step", "ch6_force_staircase")
NAN = float("nan")
CH6_TABLES = {
    # Table 6.1 (position, mm) and 6.2 (force, N): RMSE, mean power W, rise time s
    "position": (
        "Table 6.1: BPID position control of the index finger",
        "mm",
        {
            "ch6_position_sine_0.125": {"rmse": 0.083, "apc_w": 27.14, "rise_time_s": NAN},
            "ch6_position_ramp": {"rmse": 0.019, "apc_w": 9.98, "rise_time_s": NAN},
            "ch6_position_step": {"rmse": 0.072, "apc_w": 10.63, "rise_time_s": 0.84},
            "ch6_position_staircase": {"rmse": 0.038, "apc_w": 9.15, "rise_time_s": 0.31},
        },
    ),
    "force": (
        "Table 6.2: BPID force control of the index finger",
        "N",
        {
            "ch6_force_sine_0.125": {"rmse": 0.10, "apc_w": 19.83, "rise_time_s": NAN},
            "ch6_force_sine_0.25": {"rmse": 0.18, "apc_w": 24.13, "rise_time_s": NAN},
            "ch6_force_step": {"rmse": 0.12, "apc_w": 13.03, "rise_time_s": 0.77},
            "ch6_force_staircase": {"rmse": 0.11, "apc_w": 13.14, "rise_time_s": 0.22},
        },
    ),
}
CH6_SS_ERROR = {
    "ch6_position_step": 0.03,
    "ch6_position_staircase": 0.01,
    "ch6_force_step": 0.05,
    "ch6_force_staircase": 0.04,
}
CH6_HOLD = {"force": "about 0.1"}
"""Oscillation about the level while a force is held (dissertation chapter 6, N, text not table);
the position tests report none (no limit cycles) without a figure."""
