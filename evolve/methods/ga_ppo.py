"""The ga-ppo method: evogym's genetic-algorithm co-design, each body's controller trained by PPO.

The algorithm is evogym's GA (the Evolution Gym paper; its `examples/ga`), written anew:
- generation 1: `pop_size` distinct random bodies (evogym's sampling: empty 3/7, each material
  1/7, redrawn until connected with an actuator);
- every body is trained by PPO (evolve/rollout/ppo.py), a generation's new bodies all at once in one
  batched simulation, each with its own policy; its fitness is its trained policy's deterministic
  episode, scored as the run's `robust` key says (honest by default), not the training's returns;
- each next generation keeps the best fraction (survivors: their bodies, controllers and scores;
  not trained again) and fills the rest with mutants of survivors drawn uniformly: each cell
  redrawn with probability `mutation_rate` from the sampling distribution, again until connected
  with an actuator (50 tries), a body never seen before in the run;
- the survivors' fraction falls linearly from `survival` (0.6) to 0 (at least 2 survive): by
  evaluations over `max_evaluations` when it is set (evogym's run_ga.py: no new body after it),
  else by generations over the run's `generations`.

Every random draw of generation g comes from generators seeded by (seed, g), so a run resumed
from a checkpoint makes the generations the uninterrupted run made.
"""

from __future__ import annotations

import base64
import math
import statistics
import time
from dataclasses import dataclass, field

import numpy as np

from evolve.methods import formats
from evolve.methods.base import Problem
from evolve.methods.packaged import PackagedConfig
from evolve.nn.mlp import FORMAT as MLP_FORMAT
from evolve.nn.mlp import MlpController, mlp_policy
from evolve.rollout.ppo import PpoSettings, require_torch, train_bodies
from evolve.rollout.robust import check_mapping
from evolve.search.body_distance import mean_pairwise_body_distance
from evolve.search.state_codec import StateError, check, get
from tsim.body import has_actuator, is_connected
from tsim.errors import SgrError

STATE_FORMAT = "sgr-ga-ppo-1"
GA_KEYS = {"mutation_rate": 0.1, "survival": 0.6, "max_evaluations": None}
SAMPLING = np.array([3, 1, 1, 1, 1]) / 7  # evogym's: empty 0.6, each material 0.2, normalised
MUTATION_TRIES = 50  # evogym's num_attempts
CHILD_TRIES = 1000  # mutants tried per child asked for, at most, before a generation goes on with fewer


def _mlp(record: dict) -> MlpController:
    return MlpController.from_json(record["controller"])


formats.register(MLP_FORMAT, _mlp)


@dataclass(frozen=True)
class GaSettings:
    """The `ga` config key (module docstring): `mutation_rate`, `survival`, `max_evaluations`."""
    mutation_rate: float = 0.1
    survival: float = 0.6
    max_evaluations: int | None = None

    @classmethod
    def from_config(cls, raw: object, pop_size: int, source: str = "config") -> GaSettings:
        """The checked `ga` mapping; SgrError naming the key otherwise."""
        name = f"{source}: key 'ga"
        check_mapping(raw, list(GA_KEYS), name)
        v = {k: raw.get(k, d) for k, d in GA_KEYS.items()}
        for k in ("mutation_rate", "survival"):
            x = v[k]
            if isinstance(x, bool) or not isinstance(x, int | float) or not 0 <= x <= 1:
                raise SgrError(f"{name}.{k}' must be a number from 0 to 1, got {x!r}")
        m = v["max_evaluations"]
        if m is not None and (isinstance(m, bool) or not isinstance(m, int) or not pop_size <= m <= 10**9):
            raise SgrError(f"{name}.max_evaluations' must be null or an int from pop_size ({pop_size}) "
                           f"to 1,000,000,000, got {m!r}")
        return cls(float(v["mutation_rate"]), float(v["survival"]), m)


@dataclass
class Robot:
    """One body of the population: its controller once trained, and its scores (fitness: their mean)."""
    key: int
    body: np.ndarray
    born: int  # the search's generation (from 0) it was made and trained in
    controller: MlpController | None = None
    total: float = 0.0
    tags: list[str] = field(default_factory=list)
    training: dict = field(default_factory=dict)  # timesteps, episodes, mean_return of its training

    valid = True  # (a Phenotype: every body made is a valid robot)

    @property
    def fitness(self) -> float | None:
        """The mean of its scores (None: not scored yet)."""
        return self.total / len(self.tags) if self.tags else None

# configs/ga-ppo/<task>.yaml (tools/gen_configs.py writes one per task; tests check the files)
GA_PPO_CONFIG = PackagedConfig(
    template="""\
# evogym's GA co-design on $task$about
# All of a generation's new bodies train together in one batched simulation, each with its own
# policy (docs/RL.md "Co-design with PPO").
method: ga-ppo
task: $task
generations: 20
pop_size: 16                 # bodies per generation; the best survive untrained, mutants fill the rest
seed: 0
robot_shape: [5, 5]
$episode
checkpoint_every: 1          # a generation trains for long: a checkpoint after each
render_champion: true
ga:
  mutation_rate: 0.1         # evogym's: each voxel redrawn with this probability
  survival: 0.6              # the first survivors' fraction, falling linearly to 0 (at least 2)
  max_evaluations: null      # null: it falls over the generations; N: over N bodies (evogym's run_ga.py)
ppo:                         # evogym's PPO arguments (examples/ppo/args.py), per body
  timesteps: 1000000         # 16 new bodies: ~2.7 h on a 2-vCPU VM (docs/BENCHMARKS.md, "GA + PPO")
  n_envs: 1
  n_steps: 128
  batch_size: 4
  n_epochs: 4
  learning_rate: 0.00025
  gamma: 0.99
  gae_lambda: 0.95
  clip_range: 0.1
  ent_coef: 0.01
  vf_coef: 0.5
  max_grad_norm: 0.5
  hidden: [64, 64]           # SB3's MlpPolicy: policy and value networks of two 64-unit tanh layers
# Honest by default (docs/EVOLVE.md "Robust evaluation"): a body's fitness is its trained policy's
# deterministic episode under uniform(±1e-3) actuator noise, a survivor's the mean of its scores so far
# (8 at most: settle); the champion chosen at the end among the final population (final_selection).
robust: {episodes: 1, action_noise: uniform, action_scale: 0.001, offset: 0.0, statistic: mean, \
reevaluate: true, accumulate: true, settle: 8}
final_selection: {candidates: auto, episodes: auto, statistic: mean, tolerance: 0.05, rank: pooled, \
confirm: auto, holdout: auto}
""",
    about=(": bodies by a genetic algorithm, each body's controller trained by PPO\n"
           "# (evogym's examples/ga with its PPO arguments; evogym's episode length).",
           ": bodies by a genetic algorithm, each body's controller trained by PPO\n"
           "# (evogym's examples/ga with its PPO arguments; evogym's episode length)."),
    paper_episode=None)


class GaPpoProblem(Problem):
    """evogym's GA over bodies, each body's controller trained by PPO (module docstring)."""

    name = "ga-ppo"
    packaged = GA_PPO_CONFIG
    uses_neat = False
    config_keys = {"ppo": (dict, {}), "ga": (dict, {})}
    config_docs = {
        "ppo": "PPO's settings per body (evogym's defaults): timesteps, n_envs, n_steps, batch_size, "
               "n_epochs, learning_rate, gamma, gae_lambda, clip_range, ent_coef, vf_coef, max_grad_norm, "
               "hidden (docs/RL.md).",
        "ga": "The genetic algorithm: mutation_rate (0.1), survival (the first survivors' fraction, 0.6) "
              "and max_evaluations (null: the survivors' fraction falls over the generations).",
    }

    def __init__(self, cfg, neat_config=None, pool=None):
        super().__init__(cfg, neat_config, pool)
        self.ppo = PpoSettings.from_config(dict(self.cfg.ppo))
        self.ga = GaSettings.from_config(dict(self.cfg.ga), self.cfg.pop_size)

    @classmethod
    def validate(cls, cfg, source: str) -> None:
        """The `ppo` and `ga` keys, no `start_from`, and torch installed."""
        PpoSettings.from_config(dict(cfg.ppo), source)
        GaSettings.from_config(dict(cfg.ga), cfg.pop_size, source)
        if cfg.start_from is not None:
            raise SgrError(f"{source}: key 'start_from' is not for method 'ga-ppo': it continues a "
                           "NEAT population")
        require_torch()

    def decode(self, robot: Robot) -> Robot:
        """A robot is its own phenotype: its body and trained controller."""
        return robot

    def train(self, robots: list[Robot], generation: int) -> None:
        """Train every robot's controller, all in one batch, with PPO seeded by (seed, generation)."""
        seed = int(np.random.SeedSequence([self.cfg.seed, generation]).generate_state(1)[0] >> 1)
        trained = train_bodies(self.cfg.task, [r.body for r in robots], self.ppo, seed,
                               self.cfg.episode_steps, precision=self.cfg.precision)
        for r, t in zip(robots, trained, strict=True):
            r.controller = t.controller
            r.training = {"timesteps": t.timesteps, "episodes": t.episodes,
                          "mean_return": None if math.isnan(t.mean_return) else t.mean_return}

    def evaluate(self, phenotypes, tags=None) -> tuple[np.ndarray, int]:
        """Each trained robot's deterministic episode (K with `robust`, `Problem.rollout`)."""
        return self.rollout([p.body for p in phenotypes], [p.controller for p in phenotypes], mlp_policy,
                            tags)

    def champion(self, robot: Robot) -> dict:
        """The body, the trained policy's actor and how it was trained."""
        return {"body": robot.body.tolist(), "controller": robot.controller.to_json(),
                "training": {**robot.training, "ppo": self.ppo.to_json()}}

    def genome_record(self, robot: Robot) -> dict:
        """A robot has no genome beyond its body: its key."""
        return {"key": robot.key}

    def make_search(self, neat_config, seed: int, state: dict | None = None) -> GaSearch:
        """evogym's GA over this problem (`state`: a checkpoint's, decoded)."""
        require_torch()
        return GaSearch(self, seed=seed, state=state)

    @classmethod
    def encode_search(cls, state: dict) -> dict:
        """`GaSearch.state()` is JSON data already."""
        return state

    @classmethod
    def decode_search(cls, data, neat_config, cfg) -> dict:
        """A checkpoint's search data checked field by field (`GaSearch.decode_state`)."""
        return GaSearch.decode_state(data, tuple(cfg.robot_shape))


def mutate(body: np.ndarray, rate: float, rng: np.random.Generator) -> np.ndarray | None:
    """evogym's mutation: each cell redrawn from the sampling distribution with probability `rate`,
    repeated on the mutant until it is connected with an actuator (at most 50 times); None when it
    never is."""
    child = body.copy()
    for _ in range(MUTATION_TRIES):
        hit = rng.random(child.shape) < rate
        child = np.where(hit, rng.choice(5, size=child.shape, p=SAMPLING), child)
        if is_connected(child) and has_actuator(child):
            return child.astype(np.int64)
    return None


def _body_key(body: np.ndarray) -> str:
    return "".join(str(int(v)) for v in body.reshape(-1))


class GaSearch:
    """evogym's GA (module docstring) with NeatSearch's face: `generation`, `step()` -> the row of
    generations.csv, `best`, `population`, `decode`, `state()`."""

    def __init__(self, problem: GaPpoProblem, *, seed: int, state: dict | None = None):
        self.problem, self.cfg, self.seed = problem, problem.cfg, seed
        self.ga = problem.ga
        self.decode = problem.decode
        robust = self.cfg.robust
        self.reevaluate = robust is not None and robust.reevaluate
        self.accumulate = robust is not None and robust.accumulate
        self.settle = robust.settle if robust is not None else 0
        self.robots: list[Robot] = []
        self.seen: set[str] = set()
        self.generation, self.next_key, self.evaluations = 0, 1, 0
        self.best: dict | None = None
        if state is not None:
            self._restore(state)

    @property
    def population(self) -> dict[int, Robot]:
        """The scored robots by key (final selection's candidates)."""
        return {r.key: r for r in self.robots}

    def _rng(self, what: int) -> np.random.Generator:
        return np.random.default_rng([self.seed, self.generation, what])

    def survivors(self) -> int:
        """How many of the population survive into the next generation (at least 2)."""
        pop, top = self.cfg.pop_size, self.ga.survival
        if self.ga.max_evaluations is not None:
            m = self.ga.max_evaluations
            frac = top * (m - self.evaluations - 1) / (m - 1) if m > 1 else 0.0
        else:
            g, n = self.generation, self.cfg.generations  # g: the generation about to be made, from 0
            frac = top * (n - g - 1) / (n - 1) if n > 1 else 0.0
        return max(2, math.ceil(pop * max(frac, 0.0)))

    def step(self) -> dict:
        """Make, train and score one generation; returns its row of generations.csv."""
        t0 = time.perf_counter()
        if self.generation == 0:
            new = self._first()
        else:
            new = self._next()
        t1 = time.perf_counter()
        if new:
            self.problem.train(new, self.generation)
        t2 = time.perf_counter()
        again = [r for r in self.robots if r.tags and self.reevaluate
                 and not (self.accumulate and self.settle and len(r.tags) >= self.settle)]
        scored = new + again
        g = self.generation
        tags = [f"{g}/{r.key}" for r in scored]
        fit, episodes = self.problem.evaluate(scored, tags) if scored else (np.zeros(0), 0)
        for r, f, tag in zip(scored, fit, tags, strict=True):
            if self.accumulate or not r.tags:
                r.total, r.tags = r.total + float(f), [*r.tags, tag]
            else:
                r.total, r.tags = float(f), [tag]
        self.robots.sort(key=lambda r: (-_finite(r.fitness), r.key))
        self._track_best()
        fits = [r.fitness for r in self.robots if math.isfinite(r.fitness)]
        t3 = time.perf_counter()
        row = {"generation": g, "best": max(fits) if fits else math.nan,
               "mean": statistics.fmean(fits) if fits else math.nan,
               "median": statistics.median(fits) if fits else math.nan,
               "n_valid": len(new), "n_invalid": 0, "episodes": int(episodes),
               "body_diversity": mean_pairwise_body_distance([r.body for r in self.robots]),
               "trained": len(new), "timesteps": len(new) * self.problem.ppo.updates
               * self.problem.ppo.n_steps * self.problem.ppo.n_envs,
               "build_s": t2 - t1, "sim_s": t3 - t2, "neat_s": t1 - t0, "total_s": t3 - t0}
        self.generation += 1
        return row

    def _first(self) -> list[Robot]:
        """`pop_size` distinct random bodies."""
        from tsim.sampling import sample_robot

        rng = self._rng(0)
        shape = tuple(self.cfg.robot_shape)
        while len(self.robots) < self.cfg.pop_size:
            self._add(sample_robot(shape, rng, tuple(SAMPLING)))
        return list(self.robots)

    def _add(self, body: np.ndarray) -> bool:
        """Add `body` as a new robot unless it was seen before in the run; whether it was added."""
        k = _body_key(body)
        if k in self.seen:
            return False
        self.seen.add(k)
        self.robots.append(Robot(self.next_key, body, self.generation))
        self.next_key += 1
        self.evaluations += 1
        return True

    def _next(self) -> list[Robot]:
        """The survivors, then mutants of survivors drawn uniformly until `pop_size` (or
        `max_evaluations`) bodies; returns the mutants."""
        keep = self.robots[:self.survivors()]
        self.robots = list(keep)
        rng = self._rng(1)
        cap = self.ga.max_evaluations
        want = self.cfg.pop_size - len(keep)
        made = 0
        for _ in range(CHILD_TRIES * max(want, 1)):
            if made == want or (cap is not None and self.evaluations >= cap):
                break
            parent = keep[int(rng.integers(len(keep)))]
            child = mutate(parent.body, self.ga.mutation_rate, rng)
            if child is not None and self._add(child):
                made += 1
        return self.robots[len(keep):]

    def _track_best(self) -> None:
        """`best`: the best-ever robot as NeatSearch.best holds its genome (with its scores'
        tags), kept when a better one appears."""
        def entry(r: Robot) -> dict:
            return {"fitness": r.fitness, "generation": r.born, "key": r.key, "genome": r, "phenotype": r,
                    "tags": list(r.tags)}

        if self.best is not None:  # still alive: its fitness is the mean of its scores so far
            live = self.population.get(self.best["key"])
            if live is not None and math.isfinite(_finite(live.fitness)):
                self.best = entry(live)
        top = self.robots[0] if self.robots and math.isfinite(_finite(self.robots[0].fitness)) else None
        if top is not None and (self.best is None or top.fitness > self.best["fitness"]):
            self.best = entry(top)

    # ------------------------------------------------------------------ checkpoint state
    def state(self) -> dict:
        """Everything that decides the rest of the run, as JSON data: the population (bodies,
        controllers, scores), the best-ever robot, every body seen, the counters."""
        return {"format": STATE_FORMAT, "generation": self.generation, "next_key": self.next_key,
                "evaluations": self.evaluations, "seen": sorted(self.seen),
                "robots": [_robot_json(r) for r in self.robots],
                "best": None if self.best is None else {**_robot_json(self.best["genome"]),
                                                        "fitness": self.best["fitness"],
                                                        "best_tags": list(self.best["tags"])}}

    @staticmethod
    def decode_state(data, shape: tuple[int, int], path: str = "search") -> dict:
        """`state`'s data checked field by field (StateError naming the first bad one)."""
        if get(data, "format", path, "str") != STATE_FORMAT:
            raise StateError(f"{path}.format: expected {STATE_FORMAT!r}")
        out = {k: get(data, k, path, "int") for k in ("generation", "next_key", "evaluations")}
        out["seen"] = {check(s, f"{path}.seen", "str") for s in get(data, "seen", path, "list")}
        out["robots"] = [_robot_of(r, f"{path}.robots[{i}]", shape)
                         for i, r in enumerate(get(data, "robots", path, "list"))]
        best = get(data, "best", path, "dict?")
        if best is not None:
            robot = _robot_of(best, f"{path}.best", shape)
            out["best"] = {"fitness": get(best, "fitness", f"{path}.best", "float"), "generation": robot.born,
                           "key": robot.key, "genome": robot, "phenotype": robot,
                           "tags": [check(t, f"{path}.best.best_tags", "str")
                                    for t in get(best, "best_tags", f"{path}.best", "list")]}
        else:
            out["best"] = None
        return out

    def _restore(self, state: dict) -> None:
        self.generation, self.next_key = state["generation"], state["next_key"]
        self.evaluations, self.seen = state["evaluations"], set(state["seen"])
        self.robots, self.best = list(state["robots"]), state["best"]


def _finite(x: float | None) -> float:
    return -math.inf if x is None or not math.isfinite(x) else x


def _b64(a: np.ndarray) -> str:
    return base64.b64encode(np.ascontiguousarray(a, dtype="<f8").tobytes()).decode()


def _robot_json(r: Robot) -> dict:
    c = r.controller
    ctrl = None if c is None else {
        "input_size": c.input_size, "n_actions": c.n_actions,
        "shapes": [list(W.shape) for W in c.weights],
        "weights": [_b64(W) for W in c.weights], "biases": [_b64(b) for b in c.biases]}
    return {"key": r.key, "body": _body_key(r.body), "born": r.born, "total": r.total, "tags": list(r.tags),
            "training": dict(r.training), "controller": ctrl}


def _robot_of(d, path: str, shape: tuple[int, int]) -> Robot:
    body_s = get(d, "body", path, "str")
    if len(body_s) != shape[0] * shape[1] or any(ch not in "01234" for ch in body_s):
        raise StateError(f"{path}.body: not a {shape[0]}x{shape[1]} body")
    body = np.array([int(ch) for ch in body_s], dtype=np.int64).reshape(shape)
    r = Robot(get(d, "key", path, "int"), body, get(d, "born", path, "int"),
              total=get(d, "total", path, "float"),
              tags=[check(t, f"{path}.tags", "str") for t in get(d, "tags", path, "list")],
              training=get(d, "training", path, "dict"))
    c = get(d, "controller", path, "dict?")
    if c is not None:
        p = f"{path}.controller"
        try:
            shapes = [tuple(check(s, f"{p}.shapes", "list")) for s in get(c, "shapes", p, "list")]
            ws = [_unb64(w, s, f"{p}.weights")
                  for w, s in zip(get(c, "weights", p, "list"), shapes, strict=True)]
            bs = [_unb64(b, (s[1],), f"{p}.biases") for b, s in zip(get(c, "biases", p, "list"), shapes,
                                                                      strict=True)]
            r.controller = MlpController(ws, bs, get(c, "input_size", p, "int"),
                                         get(c, "n_actions", p, "int"))
        except (ValueError, TypeError) as exc:
            raise StateError(f"{p}: {exc}") from None
    return r


def _unb64(s, shape, path: str) -> np.ndarray:
    check(s, path, "str")
    if not all(isinstance(n, int) and 0 < n <= 1 << 16 for n in shape):
        raise StateError(f"{path}: bad shape {shape}")
    try:
        raw = base64.b64decode(s, validate=True)
    except ValueError:
        raise StateError(f"{path}: not base64") from None
    if len(raw) != 8 * math.prod(shape):
        raise StateError(f"{path}: {len(raw)} bytes for shape {shape}")
    return np.frombuffer(raw, dtype="<f8").reshape(shape).astype(np.float64)
