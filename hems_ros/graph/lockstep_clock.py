"""When the simulated clock may take its next step (plain Python, no ROS).

A simulator that runs a flight stack holds its clock until the stack has answered the
latest sensor sample; the graph's clock does the same. It advances by ``step_s`` only when
every finger that takes part has published its encoder sample for the current time, its
shoulder module has relayed the force of that sample, its controller has answered that
sample with a duty command, and the supervisor's status is no older than
``supervisor_lag_s``. A run's figures then follow from its inputs, not from how fast the host
is: ``rate`` only caps the pace (0: as fast as the graph answers).

A finger takes part from its controller's first answer. One that does not answer within
``stall_s`` of wall time (a killed controller) is left out, so the rest go on, and takes
part again from its next answer to its latest sample; such stalls are counted. Until a
finger takes part the clock runs at real time at most, as the graph comes up.
"""

from __future__ import annotations

from dataclasses import dataclass, field

EPS_S = 1e-6
#: wall time a finger's answer is waited for before it is left out (a stopped controller)
STALL_S = 5.0
#: how old the supervisor's latest status may be when the clock steps: its statuses come every
#: 20 ms and a unit's heating permission lasts 35 ms from a status's stamp, so the status a unit
#: needs to heat through the next 10 ms step has then been sent, and the unit waits for it
SUPERVISOR_LAG_S = 0.02


@dataclass
class FingerState:
    encoder_s: float = -1.0  # stamp of the latest encoder sample
    force_s: float = -1.0  # stamp of the latest force reading
    answered_s: float = -1.0  # measurement stamp of the latest duty command
    joined: bool = False


@dataclass
class LockstepClock:
    fingers: tuple[str, ...]
    start_s: float = 1.0
    step_s: float = 0.01
    rate: float = 1.0  # simulated s per wall s at most; 0: no cap
    stall_s: float = STALL_S
    supervisor_lag_s: float = SUPERVISOR_LAG_S
    now_s: float = field(init=False)
    stalls: int = field(default=0, init=False)
    steps: int = field(default=0, init=False)

    def __post_init__(self) -> None:
        self.now_s = self.start_s
        self.state = {finger: FingerState() for finger in self.fingers}
        self.supervisor_s: float | None = None
        self._wall0: float | None = None
        self._waiting_since: float | None = None

    # what the graph published ------------------------------------------------
    def encoder(self, finger: str, stamp_s: float) -> None:
        state = self.state.get(finger)
        if state is not None:
            state.encoder_s = stamp_s
            self._join(state)

    def force(self, finger: str, stamp_s: float) -> None:
        if finger in self.state:
            self.state[finger].force_s = stamp_s

    def duty(self, finger: str, measurement_s: float) -> None:
        state = self.state.get(finger)
        if state is None:
            return
        state.answered_s = measurement_s
        self._join(state)

    @staticmethod
    def _join(state: FingerState) -> None:
        # the controller answers the unit's latest sample (whichever of the two came first)
        if not state.joined and abs(state.answered_s - state.encoder_s) < EPS_S:
            state.joined = True

    def supervisor(self, stamp_s: float) -> None:
        self.supervisor_s = stamp_s

    # the clock ---------------------------------------------------------------
    def _finger_done(self, state: FingerState) -> bool:
        return (
            self.now_s - self.step_s + EPS_S < state.encoder_s <= self.now_s + EPS_S
            and abs(state.answered_s - state.encoder_s) < EPS_S
            and abs(state.force_s - state.encoder_s) < EPS_S
        )

    def waiting_for(self) -> list[str]:
        """What the current step still waits for (empty: it may advance)."""
        waiting = [f for f, s in self.state.items() if s.joined and not self._finger_done(s)]
        if (
            self.supervisor_s is not None
            and self.supervisor_s < self.now_s - self.supervisor_lag_s - EPS_S
        ):
            waiting.append("supervisor")
        return waiting

    @property
    def joined(self) -> list[str]:
        return [f for f, s in self.state.items() if s.joined]

    def try_advance(self, wall_s: float) -> float | None:
        """The next clock value if the step may be taken at wall time ``wall_s``, else None."""
        if self._wall0 is None:
            self._wall0 = wall_s
        waiting = self.waiting_for()
        if waiting:
            if self._waiting_since is None:
                self._waiting_since = wall_s
            if wall_s - self._waiting_since < self.stall_s:
                return None
            self.stalls += 1
            for finger in waiting:
                if finger in self.state:
                    self.state[finger].joined = False
            if "supervisor" in waiting:
                self.supervisor_s = None
        # nothing answering yet: the graph is starting; real time at most, which the nodes
        # coming up keep (their first answers then come within the watchdog's three periods)
        rate = (min(self.rate, 1.0) if self.rate > 0 else 1.0) if not self.joined else self.rate
        if rate > 0 and wall_s < self._wall0 + (self.now_s + self.step_s - self.start_s) / rate:
            return None
        self._waiting_since = None
        self.now_s = self.start_s + (self.steps + 1) * self.step_s
        self.steps += 1
        return self.now_s
