"""Whether a champion holds: its return when its actions carry a real actuator's error.

Why: the simulator is deterministic and chaotic, so evolution scored by one exact episode can select
a trajectory that only its exact action sequence produces; 0.1 % of actuator error then destroys it
(docs/RESULTS.md "Champions that hold"). Every place that shows a champion (the console at a run's
end, `sgr report`, `load_champion`) says which kind it is, by one rule, `RULE`:

- the champion is replayed `REPLAYS` times with uniform(+-`EPS`) added to every action (replay i's
  noise is a pure function of i: `replay_champion`), and once without noise;
- it *holds* when the mean of the noisy returns is at least its noise-free return less
  `TOLERANCE` of that return's size (>= 90 % of it for a positive return); otherwise it is
  *knife-edge*.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

EPS = 1e-3  # a physical actuator's error, 0.1 % of the action range's scale
REPLAYS = 20
TOLERANCE = 0.10
RULE = (f"holds: the mean return of {REPLAYS} replays with uniform(±{EPS:g}) added to every action is at "
        f"least {100 * (1 - TOLERANCE):.0f} % of the noise-free return; otherwise knife-edge")


@dataclass(frozen=True)
class Verdict:
    """A champion's noise-free return, the mean of its noisy replays, and what follows."""
    nominal: float
    noisy_mean: float
    replays: int
    eps: float

    @property
    def holds(self) -> bool:
        """The rule (module docstring): noisy mean >= nominal - TOLERANCE x |nominal|."""
        return bool(self.noisy_mean >= self.nominal - TOLERANCE * abs(self.nominal))

    @property
    def share(self) -> float:
        """The noisy mean as a share of the noise-free return (NaN unless that is positive)."""
        return self.noisy_mean / self.nominal if self.nominal > 0 else math.nan

    @property
    def label(self) -> str:
        """"holds" or "knife-edge"."""
        return "holds" if self.holds else "knife-edge"

    def line(self) -> str:
        """One line for a person, e.g. "holds: 97 % of its return 5.21 under ±0.001 (20 replays)"."""
        finite = math.isfinite(self.share)
        kept = f"{100 * self.share:.0f} % of" if finite else f"{self.noisy_mean:.3f} against"
        return (f"{self.label}: {kept} its return {self.nominal:.3f} under ±{self.eps:g} "
                f"({self.replays} replays)")

    def to_json(self) -> dict:
        """The verdict as data (what `sgr report` and scripts keep)."""
        return {"holds": self.holds, "label": self.label, "nominal": self.nominal,
                "noisy_mean": self.noisy_mean, "share": self.share, "replays": self.replays,
                "eps": self.eps, "rule": RULE}


def from_returns(returns: np.ndarray, eps: float = EPS) -> Verdict:
    """The verdict of `replay_champion`'s returns: element 0 noise-free, the rest noisy."""
    returns = np.asarray(returns, dtype=float)
    if len(returns) < 2:
        raise ValueError("a verdict needs the noise-free return and at least one noisy replay")
    return Verdict(float(returns[0]), float(returns[1:].mean()), len(returns) - 1, eps)
