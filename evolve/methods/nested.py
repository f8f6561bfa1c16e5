"""Nested-loop NEAT baseline: an outer NEAT population of body networks, and for every distinct
body an inner NEAT population of controllers that persists across outer generations.

Body network: (x, y) of a cell -> 5 material outputs, argmax. Controller network: the observation
zero-padded to a k x k grid (k = ceil(sqrt(obs length))) -> one output per cell; actions are the
outputs at actuator cells. Per outer generation every body's inner population runs
`inner_generations` generations; the controllers of all bodies are simulated as one batch per
inner generation. A body's fitness is the best return its inner population has reached.

Inner populations are forgotten once their body has been absent from the outer population for
`inner_keep_generations` outer generations (null: never, the memory and checkpoints then grow with
every body ever seen); a body that comes back later starts a fresh inner population. The body of
the run's champion (the latest `champion()` call) keeps its population, so its controller stays
available however long ago it was found.
"""

from __future__ import annotations

import hashlib
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from evolve.methods import formats
from evolve.methods.base import Problem, positive
from evolve.methods.packaged import PackagedConfig
from evolve.methods.sgr.decoder import is_valid_robot
from evolve.methods.sgr.substrates import N_TYPES, cell_coordinates, controller_side
from evolve.nn.batch import GraphPolicy, NetworkBatch
from evolve.nn.cppn import CompiledCPPN
from evolve.nn.graph import FORMAT as GRAPH_FORMAT
from evolve.nn.graph import GraphController, graph_of_record
from evolve.rollout.pool import RolloutPool
from evolve.search.neat_ini import neat_config_from_text, neat_ini_text
from evolve.search.neat_search import NeatSearch
from evolve.search.state_codec import (
    StateError,
    check,
    decode_search_state,
    encode_search_state,
    get,
    is_int,
    row,
)
from tasks.env import obs_dim
from tsim.body import build_body
from tsim.errors import SgrError


@dataclass
class BodyPhenotype:
    """A decoded body network: the body only; its controllers come from the body's inner population."""
    body: np.ndarray
    valid: bool


@dataclass
class ControllerPhenotype:
    """An inner-search genome with the body it drives; always valid (only valid bodies get an inner
    search)."""
    genome: object
    body: np.ndarray
    valid: bool = True


formats.register(GRAPH_FORMAT, graph_of_record)  # the best inner controller, in full


def nested_policy(env, items: Sequence) -> GraphPolicy:
    """Inner controller networks, items = (genome, genome config), driving the robots of env."""
    nets = NetworkBatch([g for g, _ in items], [c for _, c in items])
    return GraphPolicy(nets, [b.actuator_flat for b in env.sim.bodies], env.sim.max_actuators)


def _tag(body_key: bytes, generation: int, genome_key: int) -> str:
    """A controller's evaluation, named for robust evaluation's noise: its body (hashed), its inner
    population's generation and its genome key."""
    return f"{hashlib.blake2b(body_key, digest_size=8).hexdigest()}/{generation}/{genome_key}"

# configs/nested/<task>.yaml (tools/gen_configs.py writes one per task; tests check the files)
NESTED_CONFIG = PackagedConfig(
    template="""\
# Nested-loop NEAT baseline on $task$about
method: nested
task: $task
generations: 250
pop_size: 12                 # outer population (bodies), as in the paper
inner_pop_size: 12           # controllers per body, as in the paper
inner_generations: 2         # inner generations per outer generation (paper silent; our choice)
inner_keep_generations: 20   # forget a body's inner population after 20 outer generations without it
                             # (the champion's is kept; a body back later starts afresh; null = never
                             # forget: memory and checkpoints grow with every body seen; docs/EVOLVE.md)
seed: 0
robot_shape: [5, 5]
$episode
neat_config: ../neat/nested-body.ini
controller_neat_config: ../neat/nested-controller.ini
checkpoint_every: 5
render_champion: true
# Honest by default (docs/EVOLVE.md "Robust evaluation"): every action carries uniform(±1e-3)
# actuator noise, one fresh episode per controller and evaluation (averaging and final selection are
# not for nested NEAT: a body's fitness is the best its inner search has found). For the paper's
# nominal evaluation set it to null, as configs/sweeps/paper.yaml does.
robust: {episodes: 1, action_noise: uniform, action_scale: 0.001, offset: 0.0, statistic: mean, \
reevaluate: true}
""",
    about=(': outer NEAT over body networks, inner NEAT over controllers per body.',
           ' (not in the SGR paper): outer NEAT over body networks, inner NEAT over\n'
           "# controllers per body; the paper's settings and evogym's episode length."),
    paper_episode="episode_steps: null          # the paper's episode length")


class NestedProblem(Problem):
    """The paper's nested-loop baseline: NEAT over body networks outside, a NEAT population of
    controllers per distinct body inside (module docstring)."""

    name = "nested"
    packaged = NESTED_CONFIG
    config_keys = {"inner_pop_size": (int, 12), "inner_generations": (int, 2),
                   "inner_keep_generations": ((int, type(None)), 20), "controller_neat_config": (str, None)}
    config_docs = {
        "inner_pop_size": "Controllers in each body's inner NEAT population.",
        "inner_generations": "Inner generations each body's controllers evolve per outer generation.",
        "inner_keep_generations": "An inner population is forgotten once its body has been absent this "
                                  "many outer generations (null: never; memory then grows).",
        "controller_neat_config": "The inner (controller) populations' neat-python INI; null: "
                                  "configs/neat/nested-controller.ini.",
    }
    default_files = {"neat_config": "nested-body.ini", "controller_neat_config": "nested-controller.ini"}
    absent_before = {"inner_keep_generations": None}  # an older run never forgot an inner search
    reevaluate_elites = True  # a body's fitness is its inner search's best, which goes on improving


    @classmethod
    def decode_refusal(cls, cfg, shape):
        """A nested run's champion controller is an inner population's genome for one body."""
        return ("a nested run's champion controller is one genome of an inner population evolved for its "
                "body alone; it has no meaning at another size (decode sgr runs)")

    def __init__(self, cfg: dict, neat_config, pool: RolloutPool | None = None):
        super().__init__(cfg, neat_config, pool)
        self.gc = neat_config.genome_config
        self.shape = tuple(self.cfg.robot_shape)
        self.cells = cell_coordinates(self.shape)
        self._configs: dict[int, object] = {}
        self.inner: dict[bytes, NeatSearch] = {}
        self.keep_generations: int | None = self.cfg.inner_keep_generations
        self.generation = 0  # outer generations evaluated
        self.last_seen: dict[bytes, int] = {}  # body -> last outer generation it was in
        self.pinned: bytes | None = None  # body of the latest champion() call

    @classmethod
    def neat_overrides(cls, cfg: dict) -> dict:
        """The outer body network: 2 inputs (a cell's x, y), 5 material outputs."""
        return {"DefaultGenome": {"num_inputs": "2", "num_outputs": str(N_TYPES)}}

    @classmethod
    def validate(cls, cfg: dict, source: str) -> None:
        """Also loads controller_neat_config: a bad one fails before a run starts, rather than at
        the first body of its first generation."""
        positive(cfg, source, "inner_pop_size", "inner_generations")
        keep = cfg.inner_keep_generations
        if keep is not None and keep < 1:
            raise SgrError(f"{source}: key 'inner_keep_generations' must be a positive int or null "
                           f"(never forget), got {keep}")
        cls.controller_config(cfg, 1)

    @staticmethod
    def controller_config(cfg: dict, k: int):
        """neat-python config of the inner controllers for a k x k input grid."""
        n_cells = cfg.robot_shape[0] * cfg.robot_shape[1]
        ini = neat_ini_text(cfg.controller_neat_config, cfg.inner_pop_size,
                            {"DefaultGenome": {"num_inputs": str(k * k), "num_outputs": str(n_cells)}})
        return neat_config_from_text(ini, cfg.controller_neat_config)

    def _controller_config(self, k: int):
        if k not in self._configs:
            self._configs[k] = self.controller_config(self.cfg, k)
        return self._configs[k]

    def decode(self, genome) -> BodyPhenotype:
        """Body = argmax of the body network's 5 outputs at every cell (H, W), possibly invalid; the
        controller is evolved later, in `evaluate`."""
        out = CompiledCPPN(genome, self.gc)(self.cells)
        body = np.argmax(out, axis=1).reshape(self.shape).astype(np.int64)
        return BodyPhenotype(body, is_valid_robot(body))

    def _inner_for(self, body: np.ndarray) -> NeatSearch:
        key = body.tobytes()
        if key not in self.inner:
            k = controller_side(obs_dim(self.cfg.task, build_body(body).n_points))
            self.inner[key] = NeatSearch(self._controller_config(k),
                                         lambda g, b=body: ControllerPhenotype(g, b), None, seed=None)
        return self.inner[key]

    def evaluate(self, phenotypes: Sequence[BodyPhenotype],
                 tags: Sequence[str] | None = None) -> tuple[np.ndarray, int]:
        """Advance every distinct body's inner search `inner_generations` generations (all
        controllers one batch per inner generation); fitness = that search's best ever, episodes =
        controllers simulated. Has side effects: inner populations advance, stale ones are
        forgotten."""
        bodies = {p.body.tobytes(): p.body for p in phenotypes}
        searches = [self._inner_for(b) for b in bodies.values()]
        episodes = 0
        for _ in range(self.cfg.inner_generations):
            asks = [s.ask() for s in searches]
            flat = [p for a in asks for _, p in a]
            tags = [_tag(b, s.generation, k) for b, s, a in zip(bodies, searches, asks, strict=True)
                    for k, _ in a]
            fit, n = self._simulate(flat, searches, asks, tags)
            episodes += n
            start = 0
            for s, a in zip(searches, asks, strict=True):
                s.tell(fit[start:start + len(a)])
                start += len(a)
        best = {key: s.best["fitness"] for key, s in zip(bodies, searches, strict=True)}
        self.last_seen.update(dict.fromkeys(bodies, self.generation))
        self._forget()
        self.generation += 1
        return np.array([best[p.body.tobytes()] for p in phenotypes]), episodes

    def _forget(self) -> None:
        """Drop the inner populations of bodies absent for `keep_generations` outer generations
        (this one included), except the champion's."""
        if self.keep_generations is None:
            return
        for key in [k for k, seen in self.last_seen.items()
                    if self.generation - seen >= self.keep_generations and k != self.pinned]:
            del self.inner[key], self.last_seen[key]

    def _simulate(self, flat: list[ControllerPhenotype], searches, asks,
                  tags: list[str]) -> tuple[np.ndarray, int]:
        configs = [s.config.genome_config for s, a in zip(searches, asks, strict=True) for _ in a]
        items = [(p.genome, c) for p, c in zip(flat, configs, strict=True)]
        return self.rollout([p.body for p in flat], items, nested_policy, tags)

    def champion(self, p: BodyPhenotype) -> dict:
        """The champion's body and the best controller of its inner population, which from now on
        is kept (the Experiment calls this with the best-ever phenotype after every generation)."""
        key = p.body.tobytes()
        s = self.inner.get(key)
        if s is None:  # creating one here would consume random numbers and give an untrained controller
            raise ValueError("the champion's body has no inner population: it was forgotten before "
                             "champion() was called for it")
        self.pinned = key
        b = build_body(p.body)
        ctrl = GraphController.from_genome(s.best["genome"], s.config.genome_config,
                                           obs_dim(self.cfg.task, b.n_points), 0, 0, b.actuator_flat)
        return {"body": p.body.tolist(), "controller": ctrl.to_json(),
                "evaluation": {"tag": _tag(key, s.best["generation"], s.best["key"])}}

    # checkpoint hooks: the inner populations are part of the run's state
    def state(self) -> dict:
        """Every inner search's state (JSON data, evolve/search/state_codec.py) with its body and
        input grid side k, in order, and the forgetting bookkeeping (generation, last_seen, pinned),
        bodies as lists of rows."""
        def body(key: bytes) -> list:
            return np.frombuffer(key, dtype=np.int64).reshape(self.shape).tolist()

        return {"inner": [{"body": body(key), "k": round(len(s.config.genome_config.input_keys) ** 0.5),
                           "search": encode_search_state(s.state())} for key, s in self.inner.items()],
                "generation": self.generation,
                "last_seen": [[body(key), g] for key, g in self.last_seen.items()],
                "pinned": None if self.pinned is None else body(self.pinned)}

    @classmethod
    def decode_state(cls, data, cfg: dict) -> dict:
        """`state`'s data checked and rebuilt: bodies of the run's robot_shape with material codes,
        each inner search decoded with the controller config of its k."""
        shape = tuple(cfg.robot_shape)

        def key(b, path: str) -> bytes:
            arr = np.asarray(check(b, path, "list"), dtype=object)
            if arr.shape != shape or not all(is_int(v) and 0 <= v < N_TYPES for v in arr.flat):
                raise StateError(f"{path}: not a {shape[0]}x{shape[1]} body of material codes")
            return arr.astype(np.int64).tobytes()

        configs: dict[int, object] = {}
        inner = {}
        for i, entry in enumerate(get(data, "inner", "problem", "list")):
            p = f"problem.inner[{i}]"
            k = get(entry, "k", p, "int")
            if not 1 <= k <= 64:
                raise StateError(f"{p}.k: {k} is not an input grid side")
            if k not in configs:
                configs[k] = cls.controller_config(cfg, k)
            inner[key(get(entry, "body", p, "list"), f"{p}.body")] = (
                decode_search_state(get(entry, "search", p, "dict"), configs[k], f"{p}.search"), k)
        last_seen = {}
        for i, item in enumerate(get(data, "last_seen", "problem", "list")):
            b, g = row(item, f"problem.last_seen[{i}]", ("list", "int"))
            last_seen[key(b, f"problem.last_seen[{i}]")] = g
        pinned = get(data, "pinned", "problem", "list?")
        return {"inner": inner, "generation": get(data, "generation", "problem", "int"),
                "last_seen": last_seen, "pinned": None if pinned is None else key(pinned, "problem.pinned")}

    def restore(self, state: dict) -> None:
        """Rebuild the inner searches from `decode_state`'s result (or an older sgr's pickled state,
        being converted: from before forgetting existed, every body counts as just seen)."""
        self.generation = state.get("generation", 0)
        self.last_seen = dict(state.get("last_seen", dict.fromkeys(state["inner"], self.generation)))
        self.pinned = state.get("pinned")
        self.inner = {}
        for key, (st, k) in state["inner"].items():
            body = np.frombuffer(key, dtype=np.int64).reshape(self.shape).copy()
            self.inner[key] = NeatSearch(self._controller_config(k),
                                         lambda g, b=body: ControllerPhenotype(g, b), None, seed=None,
                                         state=st)
