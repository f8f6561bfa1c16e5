"""Whether a champion holds: its return when its actions carry a real actuator's error.

Why: the simulator is deterministic and chaotic, so evolution scored by one exact episode can select
a trajectory that only its exact action sequence produces; 0.1 % of actuator error then destroys it
(docs/history/RESULTS.md "Champions that hold"). Every place that shows a champion (the console at a run's
end, `sgr report`, `load_champion`) says which kind it is, by one rule, `RULE`:

- the champion is replayed `REPLAYS` times with uniform(+-`EPS`) added to every action (replay i's
  noise is a pure function of i: `replay_champion`), and once without noise;
- it *holds* when the mean of the noisy returns is at least its noise-free return less
  `TOLERANCE` of that return's size (>= 90 % of it for a positive return); otherwise it is
  *knife-edge*.

`Verdict.line` leads with what the robot returns under that noise (mean, sd, worst replay) and puts
the exact episode beside it: the exact episode is one draw of a chaotic system, so a share of it
("592 % of its return 0.044") says more about that draw than about the robot. `median_replay` is the
replay a typical perturbed episode is shown by (champion.gif, `sgr render`).
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
    """A champion's noise-free return, the mean of its noisy replays, and what follows; `sd`,
    `worst` and `median_replay` (the replay, from 1, whose return is their median) when the
    replays themselves are known (`from_returns`), else NaN and 0."""
    nominal: float
    noisy_mean: float
    replays: int
    eps: float
    sd: float = math.nan
    worst: float = math.nan
    median_replay: int = 0
    median: float = math.nan

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
        """One line for a person, the return under noise first, e.g. "holds: mean return 5.120, sd
        0.210, worst 4.650 under ±0.001 (20 replays); exact episode 5.210"."""
        spread = "" if math.isnan(self.sd) else f", sd {self.sd:.3f}, worst {self.worst:.3f}"
        short = "" if self.holds else f" (the mean is more than {100 * TOLERANCE:.0f} % below it)"
        return (f"{self.label}: mean return {self.noisy_mean:.3f}{spread} under ±{self.eps:g} "
                f"({self.replays} replays); exact episode {self.nominal:.3f}{short}")

    def to_json(self) -> dict:
        """The verdict as data (what `sgr report` and scripts keep)."""
        return {"holds": self.holds, "label": self.label, "nominal": self.nominal,
                "noisy_mean": self.noisy_mean, "share": self.share, "replays": self.replays,
                "eps": self.eps, "rule": RULE, "noisy_sd": self.sd, "noisy_worst": self.worst,
                "median_replay": self.median_replay}


def from_returns(returns: np.ndarray, eps: float = EPS) -> Verdict:
    """The verdict of `replay_champion`'s returns: element 0 noise-free, the rest noisy."""
    returns = np.asarray(returns, dtype=float)
    if len(returns) < 2:
        raise ValueError("a verdict needs the noise-free return and at least one noisy replay")
    noisy = returns[1:]
    m = median_replay(returns)
    sd = float(noisy.std(ddof=1)) if len(noisy) > 1 else 0.0
    return Verdict(float(returns[0]), float(noisy.mean()), len(noisy), eps, sd, float(noisy.min()), m,
                   float(returns[m]))


def median_replay(returns: np.ndarray) -> int:
    """The replay (1 to n) whose return is the median of the noisy ones, `returns[1:]` (for even n
    the lower of the middle two; equal returns keep the replays' order): the typical perturbed
    episode that champion.gif shows."""
    noisy = np.asarray(returns, dtype=float)[1:]
    if len(noisy) == 0:
        raise ValueError("a median replay needs at least one noisy replay")
    return int(np.argsort(noisy, kind="stable")[(len(noisy) - 1) // 2]) + 1
