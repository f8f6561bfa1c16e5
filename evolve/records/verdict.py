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

One headline per champion: a run's end records its champion's verdict at the top of champion.json
(`headline`, written by `Verdict.to_headline`, read back by `from_headline`), and the console, `sgr
report` and `load_champion(...)`'s repr all show that one record: the mean return of episodes that
took no part in choosing the champion, under the run's own noise (final selection's held-out
episodes; for a run without final selection, `REPLAYS` replays under the run's noise, or under
uniform(±`EPS`) for a nominal run), its sd, and the verdict by `RULE` against the exact episode.
Final selection tests its candidates by the same comparison (`clears`) with its own, stricter
tolerance on the episodes that chose them; its words for that are "passes" and "fails", never
"holds", so the console never says "holds" and "knife-edge" of one champion (`sgr explain RUN`
tells how the two tests can differ).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from evolve.rollout.robust import Robust

EPS = 1e-3  # a physical actuator's error, 0.1 % of the action range's scale
REPLAYS = 20
TOLERANCE = 0.10
RULE = (f"holds: the mean return of episodes under noise (final selection's held-out episodes under the "
        f"run's noise, else {REPLAYS} replays with uniform(±{EPS:g}) added to every action) is at "
        f"least {100 * (1 - TOLERANCE):.0f} % of the noise-free return; otherwise knife-edge")


HELD_OUT = "held-out episodes"  # final selection's: the chosen genome alone, on fresh episodes
REPLAYS_WORD = "replays"  # replays of champion.json's robot, their noise a function of their index


def clears(mean, nominal, tolerance: float = TOLERANCE):
    """Whether a mean return under noise is at least the exact return less `tolerance` of its size
    (numbers or arrays; NaN clears nothing): the comparison of the verdict (`TOLERANCE`) and of
    final selection's test (its config's `tolerance`)."""
    with np.errstate(invalid="ignore"):
        out = (np.asarray(mean) >= np.asarray(nominal) - tolerance * np.abs(nominal)) & np.isfinite(mean)
    return bool(out) if np.ndim(out) == 0 else out


def noise_words(kind: str, scale: float, offset: float = 0.0) -> str:
    """A perturbation in words: "uniform ±0.001", "gaussian sd 0.01, start ±0.05"."""
    words = f"uniform ±{scale:g}" if kind == "uniform" else f"{kind} sd {scale:g}"
    return words + (f", start ±{offset:g}" if offset else "")


@dataclass(frozen=True)
class Verdict:
    """A champion's noise-free return, the mean of its noisy episodes, and what follows; `sd`,
    `worst` and `median_replay` (the episode, from 1, whose return is their median) when the
    episodes themselves are known (`from_returns`), else NaN and 0. `eps`, `kind` and `offset`:
    their noise; `episodes`: which they were (`REPLAYS_WORD` or `HELD_OUT`)."""
    nominal: float
    noisy_mean: float
    replays: int
    eps: float
    sd: float = math.nan
    worst: float = math.nan
    median_replay: int = 0
    median: float = math.nan
    kind: str = "uniform"
    offset: float = 0.0
    episodes: str = REPLAYS_WORD

    @property
    def holds(self) -> bool:
        """The rule (module docstring): noisy mean >= nominal - TOLERANCE x |nominal|."""
        return clears(self.noisy_mean, self.nominal)

    @property
    def share(self) -> float:
        """The noisy mean as a share of the noise-free return (NaN unless that is positive)."""
        return self.noisy_mean / self.nominal if self.nominal > 0 else math.nan

    @property
    def label(self) -> str:
        """"holds" or "knife-edge"."""
        return "holds" if self.holds else "knife-edge"

    @property
    def noise(self) -> str:
        """Its episodes' noise in words (`noise_words`)."""
        return noise_words(self.kind, self.eps, self.offset)

    def line(self) -> str:
        """One line for a person, the return under noise first, e.g. "holds: mean return 5.120, sd
        0.210, worst 4.650 over 20 replays under uniform ±0.001; exact episode 5.210"."""
        spread = "" if math.isnan(self.sd) else f", sd {self.sd:.3f}, worst {self.worst:.3f}"
        short = "" if self.holds else f" (the mean is more than {100 * TOLERANCE:.0f} % below it)"
        return (f"{self.label}: mean return {self.noisy_mean:.3f}{spread} over {self.replays} "
                f"{self.episodes} under {self.noise}; exact episode {self.nominal:.3f}{short}")

    def to_json(self) -> dict:
        """The verdict as data (what `sgr report` and scripts keep)."""
        return {"holds": self.holds, "label": self.label, "nominal": self.nominal,
                "noisy_mean": self.noisy_mean, "share": self.share, "replays": self.replays,
                "eps": self.eps, "rule": RULE, "noisy_sd": self.sd, "noisy_worst": self.worst,
                "median_replay": self.median_replay}

    def to_headline(self) -> dict:
        """champion.json's `headline` block: the one figure every place shows (module docstring)."""
        return {"return": self.noisy_mean, "sd": self.sd, "worst": self.worst, "episodes": self.replays,
                "which": self.episodes,
                "noise": {"kind": self.kind, "scale": self.eps, "offset": self.offset},
                "exact": self.nominal, "verdict": self.label, "rule": RULE}


def from_headline(block: object) -> Verdict | None:
    """The `Verdict` of a champion record's `headline` block (`Verdict.to_headline`); None when the
    block is missing or not one (a record written before headlines, or a hand-made one)."""
    try:
        noise = block["noise"]
        v = Verdict(float(block["exact"]), float(block["return"]), int(block["episodes"]),
                    float(noise["scale"]), float(block["sd"]), float(block["worst"]),
                    kind=str(noise["kind"]), offset=float(noise["offset"]), episodes=str(block["which"]))
    except (KeyError, TypeError, ValueError, OverflowError):
        return None
    return v if v.replays > 0 and v.episodes in (HELD_OUT, REPLAYS_WORD) else None


def from_returns(returns: np.ndarray, eps: float = EPS, kind: str = "uniform", offset: float = 0.0,
                 episodes: str = REPLAYS_WORD) -> Verdict:
    """The verdict of `replay_champion`'s returns: element 0 noise-free, the rest noisy (under `kind`
    noise of scale `eps`, start shifted by up to `offset`; `episodes`: which they are)."""
    returns = np.asarray(returns, dtype=float)
    if len(returns) < 2:
        raise ValueError("a verdict needs the noise-free return and at least one noisy replay")
    noisy = returns[1:]
    m = median_replay(returns)
    sd = float(noisy.std(ddof=1)) if len(noisy) > 1 else 0.0
    # the mean as `Robust.score` takes it (summed in order): a held-out headline is its fitness, bit for bit
    mean = float(Robust().score(noisy[:, None])[0])
    return Verdict(float(returns[0]), mean, len(noisy), eps, sd, float(noisy.min()), m,
                   float(returns[m]), kind, offset, episodes)


def median_replay(returns: np.ndarray) -> int:
    """The replay (1 to n) whose return is the median of the noisy ones, `returns[1:]` (for even n
    the lower of the middle two; equal returns keep the replays' order): the typical perturbed
    episode that champion.gif shows."""
    noisy = np.asarray(returns, dtype=float)[1:]
    if len(noisy) == 0:
        raise ValueError("a median replay needs at least one noisy replay")
    return int(np.argsort(noisy, kind="stable")[(len(noisy) - 1) // 2]) + 1
