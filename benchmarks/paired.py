"""Whether one state of the graph costs more CPU than another on a host whose speed drifts.

The development VM's speed drifts by a third within minutes, so two states measured in one
window each differ by that drift as much as by what they cost. They are measured in windows
that alternate instead; each window of the state in question is compared with the windows of
the other state on either side of it, which cancels a steady drift, and the spread of those
differences is the noise the verdict allows for (a one-sided Student's t at 97.5 %): with
equal costs the state reads costlier in one run of forty.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from statistics import mean, stdev

from scipy.stats import t

CONFIDENCE = 0.975


@dataclass(frozen=True)
class Excess:
    """What one state costs beyond the other, cores, from alternating windows."""

    differences: tuple[float, ...]  # each window of the state minus its neighbours' mean
    state_cores: float  # mean of the state's windows
    other_cores: float  # mean of the neighbours' means
    allowance: float  # what the differences' spread allows their mean to reach

    @property
    def mean(self) -> float:
        return mean(self.differences)

    @property
    def ratio(self) -> float:
        """Above 1: the state costs measurably more than the other."""
        return self.state_cores / (self.other_cores + self.allowance)


def excess(windows: list[tuple[str, float]], state: str) -> Excess:
    """``state``'s excess over the other state in ``windows``, (state, cores) in time order.

    Each window of ``state`` is set against the nearest window of another state before it and
    the nearest after it (one of them at either end)."""
    differences, neighbours = [], []
    for i, (name, cores) in enumerate(windows):
        if name != state:
            continue
        before = next((c for n, c in reversed(windows[:i]) if n != state), None)
        after = next((c for n, c in windows[i + 1 :] if n != state), None)
        around = [c for c in (before, after) if c is not None]
        if not around:
            raise ValueError(f"no window of another state beside a {state} window")
        neighbours.append(mean(around))
        differences.append(cores - neighbours[-1])
    if len(differences) < 2:
        raise ValueError(f"at least two {state} windows are needed, got {len(differences)}")
    spread = stdev(differences) / math.sqrt(len(differences))
    return Excess(
        differences=tuple(differences),
        state_cores=mean(c for n, c in windows if n == state),
        other_cores=mean(neighbours),
        allowance=float(t.ppf(CONFIDENCE, len(differences) - 1)) * spread,
    )
