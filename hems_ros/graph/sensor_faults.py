"""Faults injected into the simulated sensors at run time, for the fault matrix
(docs/reliability.md): the actuation unit's and the shoulder module's ``sensor_fault``
parameter names one of these, and their readings pass through a :class:`FaultySensor`.

A stuck sensor keeps delivering fresh samples with the value it had when it stuck, which no
stream monitor sees; the others jump, saturate, turn noisy or fail to NaN.
"""

from __future__ import annotations

from typing import Any, TypeVar, cast

# a reading: (counts, position m) of an encoder, (force N, saturated) of a load cell
_Reading = TypeVar("_Reading", tuple[int, float], tuple[float, bool])

ENCODER_FAULTS = ("", "stuck_encoder", "encoder_jump", "nan_encoder")
FORCE_FAULTS = ("", "stuck_force", "force_saturation", "force_noise_burst", "nan_force")
#: what an encoder_jump adds to the reading, m
JUMP_M = 5e-3
#: how much a force_noise_burst multiplies the sensor's noise
NOISE_BURST = 50.0


def noise_scale(fault: str) -> float:
    """The factor on a force sensor's noise under ``fault``."""
    return NOISE_BURST if fault == "force_noise_burst" else 1.0


class FaultySensor:
    """One sensor's readings through the fault currently set on it."""

    def __init__(self) -> None:
        self._held: tuple[Any, ...] | None = None  # the reading a stuck sensor repeats

    def _stuck(self, stuck: bool, reading: _Reading) -> _Reading:
        if not stuck:
            self._held = None
            return reading
        if self._held is None:
            self._held = reading
        # a sensor is an encoder or a load cell for good: what it holds is what it reads
        return cast(_Reading, self._held)

    def encoder(
        self, fault: str, counts: int, position_m: float, resolution_m: float
    ) -> tuple[int, float]:
        """(counts, position m) the encoder reports."""
        if not fault and self._held is None:  # a healthy encoder: the reading as it is
            return counts, position_m
        counts, position_m = self._stuck(fault == "stuck_encoder", (counts, position_m))
        if fault == "encoder_jump":
            counts += int(round(JUMP_M / resolution_m))
            return counts, counts * resolution_m
        if fault == "nan_encoder":
            return counts, float("nan")
        return counts, position_m

    def force(
        self, fault: str, force_n: float, saturated: bool, range_max_n: float
    ) -> tuple[float, bool]:
        """(force N, saturated) the load cell reports."""
        if not fault and self._held is None:  # a healthy load cell: the reading as it is
            return force_n, saturated
        force_n, saturated = self._stuck(fault == "stuck_force", (force_n, saturated))
        if fault == "force_saturation":
            return range_max_n, True
        if fault == "nan_force":
            return float("nan"), saturated
        return force_n, saturated
