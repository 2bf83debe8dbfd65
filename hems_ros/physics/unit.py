"""Stepping API: one actuation unit advanced at a fixed step (1 kHz default) by a node.

    unit = ActuationUnit(load_params("sheathed_calibrated"), dt=1e-3)
    r = unit.step(duty=35.0)  # or current=4.0 (A), voltage=12.0 (V), temperature=80.0 (degC)
    r.encoder_counts, r.force_reading, r.wire_temperature_c, r.slider_position_m ...

Exactly one drive per step: ``duty`` in % (0-100) through the HEMS PWM stage (20 V, 4 A
limit), ``current`` in A (the dissertation's current source), ``voltage`` in V
(constant-voltage drive) or ``temperature``, the wire temperature in degC imposed at the
end of the step (a thermal cycle without the heat balance, kernel module docstring).
Out-of-range or non-finite inputs raise ``ValueError``.
The step is :func:`hems_ros.physics.kernel.step`, the same function the batch API loops,
so both give the same trajectory for the same input; a unit runs it compiled ahead of time
(compiled.step_kernel), so a process stepping units does not load numba.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from hems_ros.duty import valid_duty
from hems_ros.physics import compiled, rows, sensors
from hems_ros.physics.electrical import DRIVE_NAMES, select_drive
from hems_ros.physics.params import UnitParams


@dataclass(frozen=True, slots=True)
class StepResult:
    """Measurements (what the hardware sees) and simulation truth after one step."""

    time_s: float
    # measurements
    encoder_counts: int
    encoder_position_m: float
    force_reading_n: float
    force_saturated: bool
    # simulation truth
    wire_temperature_c: float
    martensite_fraction: float
    resistance_ohm: float
    current_a: float
    electrical_power_w: float
    energy_joule_j: float  # Joule heat delivered since reset
    stress_pa: float
    strain: float
    sheath_temperature_c: float
    sheath_helix_temperature_c: float  # ambient unless the sheath has a helix node
    slider_position_m: float
    slider_velocity_m_s: float
    tendon_position_m: float
    tendon_force_n: float
    wire_force_n: float


def check_drive(kind: str, value: float) -> None:
    """Raise ValueError for a non-finite drive or a duty outside 0-100 %."""
    if not math.isfinite(value):
        raise ValueError(f"{kind} = {value!r}: drive input must be finite")
    if kind == "duty" and not valid_duty(value):
        raise ValueError(
            f"duty = {value!r} %: must be within 0-100 % (the controller clamps, not the plant)"
        )


class ActuationUnit:
    """One SMA actuation unit (wire, sheath, slider, pulley, tendon load, sensors)."""

    def __init__(self, params: UnitParams | None = None, dt: float = 1e-3) -> None:
        if not (isinstance(dt, (int, float)) and math.isfinite(dt) and dt > 0):
            raise ValueError(f"dt = {dt!r}: must be a finite step > 0 s")
        self.params = params if params is not None else UnitParams()
        if not isinstance(self.params, UnitParams):
            raise TypeError("params must be a UnitParams")
        self.dt = float(dt)
        self._p = rows.pack(self.params)
        self._p_imposed = rows.pack(
            self.params, temperature_drive=True
        )  # the temperature drive row
        self._kernel_steps = compiled.step_kernel()
        self._out = np.zeros(rows.N_O)
        self.reset()

    def reset(self) -> None:
        """Go back to t = 0.

        The wire is martensitic and at rest at the start temperature (ambient plus
        ``params.start``); the sensor noise generator is re-seeded.
        """
        self._s = rows.initial_state(self.params)
        self._out[:] = 0.0
        self._steps = 0
        # a noiseless sensor draws nothing (as the batch API), which spares a unit node, whose
        # force sensor is the shoulder module's, two generator calls a tick, and spares its
        # process numpy.random
        fs = self.params.force_sensor
        self._rng = sensors.noise_generator(fs.seed) if fs.noise_std_n > 0 else None
        self._noise = 0.0

    def snapshot(self) -> tuple:
        """Everything :meth:`restore` needs to continue from here (state, time, noise draws)."""
        return (
            self._s.copy(),
            self._out.copy(),
            self._steps,
            None if self._rng is None else self._rng.bit_generator.state,
            self._noise,
        )

    def restore(self, snapshot: tuple) -> None:
        """Go back to a :meth:`snapshot` of this unit: the next steps repeat from there."""
        state, out, steps, rng_state, noise = snapshot
        self._s[:] = state
        self._out[:] = out
        self._steps = steps
        if self._rng is not None:
            self._rng.bit_generator.state = rng_state
        self._noise = noise

    @property
    def steps(self) -> int:
        """Steps taken since the last reset."""
        return self._steps

    @property
    def time(self) -> float:
        """Simulated time since the last reset, s."""
        return self._steps * self.dt

    @property
    def state(self) -> dict[str, float]:
        """The kernel state by name (temperatures, fraction, stress, position, energies)."""
        return {name: float(self._s[i]) for i, name in enumerate(rows.STATE_NAMES)}

    def wire(self) -> tuple[float, float, float]:
        """Return (wire temperature degC, martensite fraction, slider position m) now.

        The part of :attr:`state` a controller's thermal guard reads at every control step,
        without building the rest.
        """
        s = self._s
        return float(s[rows.S_T]), float(s[rows.S_XI]), float(s[rows.S_X])

    @property
    def energy(self) -> dict[str, float]:
        """Energy accumulators since reset, J (Joule = stored + convected + latent + to sheath)."""
        return {k: v for k, v in self.state.items() if k.startswith("energy_")}

    def step(
        self,
        duty: float | None = None,
        current: float | None = None,
        voltage: float | None = None,
        *,
        temperature: float | None = None,
    ) -> StepResult:
        """Advance by dt with one drive: duty %, current A, voltage V or wire temperature degC."""
        self.advance(duty, current, voltage, temperature=temperature)
        return self.result()

    def advance(
        self,
        duty: float | None = None,
        current: float | None = None,
        voltage: float | None = None,
        steps: int = 1,
        *,
        temperature: float | None = None,
    ) -> None:
        """Advance like :meth:`step`, ``steps`` times at one drive, without building a result.

        One kernel call: a node integrating at 1 kHz reads only the steps that end on a sensor
        sample (:meth:`result`), and the drive changes only with a command.
        """
        kind, value = select_drive(duty, current, voltage, temperature)
        value = float(value)
        check_drive(kind, value)
        if isinstance(steps, bool) or not isinstance(steps, int) or steps < 1:
            raise ValueError(f"steps = {steps!r}: must be a whole number >= 1")
        row = self._p_imposed if kind == "temperature" else self._p
        done = self._kernel_steps(row, self._s, DRIVE_NAMES[kind], value, self.dt, self._out, steps)
        self._steps += done
        if done < steps:
            raise FloatingPointError(
                f"state became non-finite at t = {self.time + self.dt:.6f} s ({self.state})"
            )
        # the result's force noise is the last step's draw; a block of draws continues the
        # generator's stream exactly as single draws would
        if self._rng is not None:
            self._noise = (
                self._rng.standard_normal() if steps == 1 else self._rng.standard_normal(steps)[-1]
            )

    def readings(self) -> tuple[int, float, float]:
        """Return (encoder counts, encoder position m, wire force N) after the last step.

        The part of :meth:`result` a node publishes at every encoder sample, without building
        the rest (a fifth of a unit node's Python time per tick went into the whole result).
        """
        enc = self.params.encoder
        counts = sensors.encoder_counts(float(self._s[rows.S_X]), enc.resolution_m, enc.gain)
        return counts, counts * enc.resolution_m, float(self._out[rows.O_FW])

    def electrical(self) -> tuple[float, float]:
        """Return (resistance ohm, mean current A) of the last step.

        What a drive board measures, without building the rest of :meth:`result`.
        """
        return float(self._out[rows.O_R]), float(self._out[rows.O_I])

    def result(self) -> StepResult:
        """Measurements and truth after the last step: what that :meth:`step` returned."""
        # one conversion of each array to Python floats: reading twenty numpy scalars one by
        # one cost a node a sixth of its tick's Python time
        s, o, prm = self._s.tolist(), self._out.tolist(), self.params
        counts, position, wire_force = self.readings()
        fs = prm.force_sensor
        time = self.time
        reading, saturated = sensors.force_reading(
            wire_force,
            float(self._noise) * fs.noise_std_n,
            fs.range_max_n,
            fs.resolution_n,
            fs.offset_n,
            fs.drift_n_per_s,
            time,
        )
        return StepResult(
            time_s=time,
            encoder_counts=counts,
            encoder_position_m=position,
            force_reading_n=reading,
            force_saturated=saturated,
            wire_temperature_c=s[rows.S_T],
            martensite_fraction=s[rows.S_XI],
            resistance_ohm=o[rows.O_R],
            current_a=o[rows.O_I],
            electrical_power_w=o[rows.O_P],
            energy_joule_j=s[rows.S_EJ],
            stress_pa=s[rows.S_SIG],
            strain=s[rows.S_X] / prm.wire.length_m,
            sheath_temperature_c=s[rows.S_TS],
            sheath_helix_temperature_c=s[rows.S_TH],
            slider_position_m=s[rows.S_X],
            slider_velocity_m_s=s[rows.S_V],
            tendon_position_m=o[rows.O_XT],
            tendon_force_n=o[rows.O_FT],
            wire_force_n=wire_force,
        )
