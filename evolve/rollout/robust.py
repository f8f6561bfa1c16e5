"""Robust evaluation: a genome scored over K perturbed episodes instead of one exact episode.

Why: the simulator is deterministic and chaotic, so evolution can select a trajectory that holds
only for the exact action sequence it was scored on (docs/RESULTS.md: SGR champions losing a
quarter to all of their fitness under +-1e-3 action noise). Scoring each genome by a statistic of
K episodes with small perturbations selects behaviour that holds.

What is perturbed (`Perturbation`):
- every action of every step gets uniform(+-scale) or gaussian(0, scale) noise (before the
  simulator's clip to [0.6, 1.6], as noise on a real actuator's command);
- the robot's start is shifted right by uniform(+-offset) (evogym's length units, a voxel is 0.1).

Every random number is a pure function of one 64-bit episode key (`episode_keys`: run seed, a tag
naming the generation and genome, the episode index), the step and the actuator, computed by a
counter-based hash (splitmix64) in numpy: no generator state, so the noise of an episode does not
depend on the batch it is simulated in, the worker count, the machine or a resume.
"""

from __future__ import annotations

import hashlib
import re
from collections.abc import Sequence
from dataclasses import asdict, dataclass

import numpy as np

from tsim.errors import SgrError

NOISE_KINDS = ("none", "uniform", "gaussian")
MAX_EPISODES = 100_000  # perturbed episodes of one genome: more is a typo (it would run for days)
STATISTICS = ("mean", "min", "median", "qNN (a quantile in percent, e.g. q25)")

_M1, _M2 = np.uint64(0xBF58476D1CE4E5B9), np.uint64(0x94D049BB133111EB)
_STEP, _ACT = np.uint64(0x9E3779B97F4A7C15), np.uint64(0xD1B54A32D192ED03)
_STREAM = np.uint64(0xC2B2AE3D27D4EB4F)


def _mix(x: np.ndarray) -> np.ndarray:
    """splitmix64's finalizer: a bijection of uint64 whose outputs look independent."""
    x = x ^ (x >> np.uint64(30))
    x = x * _M1
    x = x ^ (x >> np.uint64(27))
    x = x * _M2
    return x ^ (x >> np.uint64(31))


def unit_uniform(keys: np.ndarray, stream: int, t: int, n: int) -> np.ndarray:
    """(B, n) numbers in [0, 1), one per (episode key, stream, step t, column); 53-bit exact."""
    with np.errstate(over="ignore"):
        x = (keys.astype(np.uint64)[:, None] + np.uint64(stream) * _STREAM + np.uint64(t) * _STEP
             + (np.arange(n, dtype=np.uint64)[None, :] + np.uint64(1)) * _ACT)
        x = _mix(_mix(x))
    return (x >> np.uint64(11)).astype(np.float64) * 2.0 ** -53


def episode_keys(seed: int, tags: Sequence[str], episode: int) -> np.ndarray:
    """(len(tags),) uint64 keys of episode `episode` of each tagged genome in a run seeded `seed`."""
    return np.array([int.from_bytes(hashlib.blake2b(f"{seed}|{tag}|{episode}".encode(),
                                                    digest_size=8).digest(), "little")
                     for tag in tags], dtype=np.uint64)


@dataclass(frozen=True)
class Perturbation:
    """What a perturbed episode changes: action noise of a kind and scale, and a start offset."""
    action_noise: str = "uniform"
    action_scale: float = 0.0
    offset: float = 0.0

    def actions(self, keys: np.ndarray, t: int, n: int) -> np.ndarray | None:
        """(B, n) noise added to the actions of step t, or None when there is none."""
        if self.action_noise == "none" or self.action_scale == 0.0:
            return None
        u = unit_uniform(keys, 0, t, n)
        if self.action_noise == "uniform":
            return self.action_scale * (2.0 * u - 1.0)
        v = unit_uniform(keys, 1, t, n)  # Box-Muller; 1 - u is in (0, 1]
        return self.action_scale * np.sqrt(-2.0 * np.log1p(-u)) * np.cos(2.0 * np.pi * v)

    def shifts(self, keys: np.ndarray) -> np.ndarray | None:
        """(B,) start offsets of the robots, or None when there are none."""
        if self.offset == 0.0:
            return None
        return self.offset * (2.0 * unit_uniform(keys, 2, 0, 1)[:, 0] - 1.0)


@dataclass(frozen=True)
class EpisodeNoise:
    """The perturbation of each world of a batch: its episode key, and whether it is perturbed at
    all (False: the exact, nominal episode)."""
    perturbation: Perturbation
    keys: np.ndarray
    on: np.ndarray

    def take(self, idx: Sequence[int]) -> EpisodeNoise:
        """The noise of the worlds `idx` (a chunk of the batch)."""
        idx = np.asarray(idx, dtype=np.int64)
        return EpisodeNoise(self.perturbation, self.keys[idx], self.on[idx])

    def actions(self, t: int, n: int) -> np.ndarray | None:
        """(B, n) action noise of step t (zero rows for nominal worlds), or None."""
        a = self.perturbation.actions(self.keys, t, n)
        return None if a is None else np.where(self.on[:, None], a, 0.0)

    def shifts(self) -> np.ndarray | None:
        """(B,) start offsets (zero for nominal worlds), or None."""
        s = self.perturbation.shifts(self.keys)
        return None if s is None else np.where(self.on, s, 0.0)


def check_mapping(raw: object, known, name: str) -> None:
    """SgrError unless `raw` is a mapping whose keys are among `known` (in the order given); `name`
    is the source and the key, without its closing quote ("run.yaml: key 'ppo")."""
    if not isinstance(raw, dict):
        raise SgrError(f"{name}' must be a mapping ({', '.join(known)}), got {raw!r}")
    for k in raw:
        if k not in known:
            raise SgrError(f"{name}': unknown key {k!r}; known keys: {', '.join(known)}")


def config_dataclass(cls, raw: object, name: str):
    """`cls` (a dataclass) built from a config mapping whose keys are its fields; ValueError
    naming `name` (the source and the key, without its closing quote) when `raw` is not a mapping
    or holds an unknown key. Values are the caller's to check."""
    fields = list(cls.__dataclass_fields__)
    if not isinstance(raw, dict):
        raise ValueError(f"{name}' must be a mapping ({', '.join(fields)}) or null, got {raw!r}")
    for key in raw:
        if key not in fields:
            raise ValueError(f"{name}': unknown key {key!r}; known keys: {', '.join(sorted(fields))}")
    return cls(**raw)


@dataclass(frozen=True)
class Robust:
    """The `robust` config key: each genome's fitness is `statistic` over `episodes` perturbed
    episodes (`Perturbation`), all simulated in the generation's batch. `reevaluate`: elites are
    simulated again every generation, with that generation's noise, instead of keeping the score
    of their first episodes (a lucky score then does not last). `accumulate` (with `reevaluate`):
    a genome's fitness is the mean of its scores over every generation it has been evaluated in,
    so one fresh episode a generation adds up to many for the genomes that survive, at the cost of
    a nominal run. `race` (with `accumulate`): the `race` genomes ranked highest after a
    generation's episodes get `episodes` more that generation (NeatSearch). `settle` (with
    `accumulate`; 0: never): a genome scored `settle` times keeps that mean and is not simulated
    again."""
    episodes: int = 4
    action_noise: str = "uniform"
    action_scale: float = 1e-3
    offset: float = 0.0
    statistic: str = "mean"
    reevaluate: bool = False
    accumulate: bool = False
    race: int = 0
    settle: int = 0

    @property
    def perturbation(self) -> Perturbation:
        """The perturbation of every episode."""
        return Perturbation(self.action_noise, self.action_scale, self.offset)

    def noise(self, seed: int, tags: Sequence[str]) -> EpisodeNoise:
        """The perturbations of the K episodes of each tagged genome of a run seeded `seed`, episode
        major: world e * len(tags) + i is episode e of genome i (what `score` reshapes)."""
        keys = np.concatenate([episode_keys(seed, tags, e) for e in range(self.episodes)])
        return EpisodeNoise(self.perturbation, keys, np.ones(len(keys), dtype=bool))

    def score(self, returns: np.ndarray) -> np.ndarray:
        """(K, N) returns -> (N,) fitness; a non-finite return makes the genome's fitness -inf
        only through the statistic itself (min and quantiles see it, mean gives nan)."""
        s = self.statistic
        if s == "mean":  # summed episode by episode: numpy's mean sums pairwise or not depending on
            total = returns[0].astype(float)  # the array's shape, so one genome scored alone (K, 1)
            for r in returns[1:]:  # would differ in the last bit from its column of a (K, N) batch
                total = total + r
            return total / len(returns)
        if s == "min":
            return returns.min(axis=0)
        if s == "median":
            return np.median(returns, axis=0)
        return np.quantile(returns, int(s[1:]) / 100.0, axis=0)

    def to_json(self) -> dict:
        """The config mapping: every key, but `accumulate`, `race` and `settle` only when set (the records
        of runs made before they existed stay as they were)."""
        out = asdict(self)
        for key in ("accumulate", "race", "settle"):
            if not out[key]:
                del out[key]
        return out

    @classmethod
    def from_config(cls, raw: object, source: str = "config") -> Robust | None:
        """The checked `robust` mapping of a config; None (or a missing key) is nominal evaluation.
        ValueError naming `source` and the key."""
        if raw is None:
            return None
        name = f"{source}: key 'robust"
        r = config_dataclass(cls, raw, name)
        k = r.episodes
        if not isinstance(k, int) or isinstance(k, bool) or not 1 <= k <= MAX_EPISODES:
            raise ValueError(f"{name}.episodes' must be an int from 1 to {MAX_EPISODES:,}, got {k!r}")
        if r.action_noise not in NOISE_KINDS:
            raise ValueError(f"{name}.action_noise' must be one of {', '.join(NOISE_KINDS)}, "
                             f"got {r.action_noise!r}")
        for key in ("action_scale", "offset"):
            v = getattr(r, key)
            if isinstance(v, bool) or not isinstance(v, int | float) or not np.isfinite(v) or v < 0:
                raise ValueError(f"{name}.{key}' must be a number >= 0, got {v!r}")
        s = r.statistic
        # ASCII digits only: str.isdigit() takes '²', which int() does not, and '٣', which it does
        quantile = isinstance(s, str) and re.fullmatch(r"q[0-9]{1,3}", s) is not None and int(s[1:]) <= 100
        if s not in STATISTICS[:3] and not quantile:
            raise ValueError(f"{name}.statistic' must be one of {', '.join(STATISTICS)}, got {s!r}")
        for key in ("reevaluate", "accumulate"):
            if not isinstance(getattr(r, key), bool):
                raise ValueError(f"{name}.{key}' must be true or false, got {getattr(r, key)!r}")
        if r.accumulate and not r.reevaluate:
            raise ValueError(f"{name}.accumulate' needs reevaluate: true (a survivor's scores are "
                             "averaged over the generations it is simulated in)")
        for key in ("race", "settle"):
            v = getattr(r, key)
            if not isinstance(v, int) or isinstance(v, bool) or v < 0:
                raise ValueError(f"{name}.{key}' must be an int >= 0, got {v!r}")
            if v and not r.accumulate:
                raise ValueError(f"{name}.{key}' needs accumulate: true (a genome's scores are averaged)")
        return cls(r.episodes, r.action_noise, float(r.action_scale), float(r.offset), s, r.reevaluate,
                   r.accumulate, r.race, r.settle)
