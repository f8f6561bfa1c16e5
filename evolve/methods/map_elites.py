"""The map-elites method: quality diversity with SGR genomes (docs/QD.md).

Instead of one population converging on one champion, an archive keeps the best robot found in
each cell of a grid over descriptors of the body or of what it does (evolve/methods/descriptors.py:
actuator share, rigid share, gait frequency, ground contact, ...). Its genomes are SGR's (one CPPN
decoded into a body and a controller); its search is MAP-Elites (evolve/search/archive.py:
children bred with NEAT's own operators from parents drawn uniformly, by curiosity or by
tournament, evaluated with the run's `robust` evaluation, each offered to its cell). This module
holds the method: its `qd` config key (`QdSettings`) and its Problem, which makes that search.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from evolve.config import MAX_POP
from evolve.methods.descriptors import DESCRIPTORS, measure, needs_behaviour
from evolve.methods.packaged import PackagedConfig
from evolve.methods.qd_floors import FLOORS
from evolve.methods.sgr import SgrProblem
from evolve.rollout.pool import RolloutPool
from evolve.rollout.robust import check_mapping
from evolve.search.archive import TOURNAMENT, Elite, MapElitesSearch  # noqa: F401 (the method's search)
from evolve.search.state_codec import (
    is_int,
)
from tsim.errors import SgrError

INSTALL_QD = "pip install 'sgr[qd]' (or: pip install ribs)"
QD_KEYS = ("descriptors", "ranges", "resolution", "batch", "initial", "rescore", "score_offset", "selection",
           "exploit")
SELECTIONS = ("uniform", "curiosity")
DEFAULT_DESCRIPTORS = ("actuator", "rigid")
MAX_CELLS = 1_000_000  # the archive's cells at most (pyribs allocates every cell up front)


def require_ribs() -> None:
    """SgrError in one line saying how to install pyribs, when it is missing."""
    try:
        import ribs.archives  # noqa: F401
    except ImportError:
        raise SgrError(f"method 'map-elites' needs pyribs, which is not installed: {INSTALL_QD}") from None


@dataclass(frozen=True)
class QdSettings:
    """The `qd` config key: the descriptors (names in evolve/methods/descriptors.py) and their
    ranges, the archive's cells per descriptor (`resolution`), the valid children per generation
    (`batch`; default the config's pop_size), the valid genomes of the first generation (`initial`;
    default `batch`), the elites re-scored per generation at most (`rescore`; default batch / 4),
    the offset of the QD score (the sum over elites of max(0, fitness - `score_offset`); default
    "auto": the task's floor, evolve/methods/qd_floors.py), how parents are drawn (`selection`:
    uniform, or curiosity: favouring elites whose children entered the archive) and the share of
    children whose parents are instead the fittest of TOURNAMENT elites drawn (`exploit`)."""
    descriptors: tuple[str, ...]
    ranges: tuple[tuple[float, float], ...]
    resolution: tuple[int, ...]
    batch: int
    initial: int
    rescore: int
    score_offset: float
    selection: str = "uniform"
    exploit: float = 0.0

    @classmethod
    def from_config(cls, raw: object, shape: tuple[int, int], pop_size: int,
                    source: str = "config", task: str | None = None) -> QdSettings:
        """The checked `qd` mapping ({} : every default) of a run of `task` (which gives the
        default score_offset); SgrError naming the key otherwise."""
        name = f"{source}: key 'qd"
        check_mapping(raw, QD_KEYS, name)
        names = raw.get("descriptors", list(DEFAULT_DESCRIPTORS))
        if (not isinstance(names, list) or not names or not all(isinstance(n, str) for n in names)
                or len(set(names)) != len(names)):
            raise SgrError(f"{name}.descriptors' must be a list of distinct descriptor names, got {names!r}")
        for n in names:
            if n not in DESCRIPTORS:
                raise SgrError(f"{name}.descriptors': unknown descriptor {n!r}; known descriptors: "
                               f"{', '.join(DESCRIPTORS)}")
        given = raw.get("ranges", {})
        if not isinstance(given, dict):
            raise SgrError(f"{name}.ranges' must be a mapping of descriptor to [low, high], got {given!r}")
        for k, v in given.items():
            if k not in names:
                raise SgrError(f"{name}.ranges': {k!r} is not one of qd.descriptors ({', '.join(names)})")
            ok = (isinstance(v, list) and len(v) == 2
                  and all(isinstance(x, int | float) and not isinstance(x, bool) and math.isfinite(x)
                          for x in v)
                  and v[0] < v[1])
            if not ok:
                raise SgrError(f"{name}.ranges.{k}' must be [low, high] with low < high, got {v!r}")
        ranges = tuple((float(given[n][0]), float(given[n][1])) if n in given
                       else tuple(map(float, DESCRIPTORS[n].range_of(shape))) for n in names)
        res = raw.get("resolution")
        if res is None:
            res = [int(DESCRIPTORS[n].cells_of(shape)) for n in names]
        elif is_int(res):
            res = [res] * len(names)
        if not (isinstance(res, list) and len(res) == len(names) and all(is_int(r) and r >= 1 for r in res)):
            raise SgrError(f"{name}.resolution' must be an int >= 1 or a list of one per descriptor, "
                           f"got {res!r}")
        if math.prod(res) > MAX_CELLS:
            raise SgrError(f"{name}.resolution' makes {math.prod(res):,} cells, more than the {MAX_CELLS:,} "
                           f"an archive may have, got {res!r}")
        counts = {}
        for key, fallback in (("batch", pop_size), ("initial", None), ("rescore", None)):
            v = raw.get(key, fallback)
            if v is None:
                v = counts["batch"] if key == "initial" else max(1, counts["batch"] // 4)
            least = 0 if key == "rescore" else 1
            if not is_int(v) or not least <= v <= MAX_POP:  # more: a typo that fills memory
                raise SgrError(f"{name}.{key}' must be an int from {least} to {MAX_POP:,}, got {v!r}")
            counts[key] = v
        offset = raw.get("score_offset", "auto")
        if offset == "auto":
            offset = FLOORS.get(task, 0.0)
        if isinstance(offset, bool) or not isinstance(offset, int | float) or not math.isfinite(offset):
            raise SgrError(f"{name}.score_offset' must be a number or 'auto', got {offset!r}")
        selection = raw.get("selection", "uniform")
        if selection not in SELECTIONS:
            raise SgrError(f"{name}.selection' must be one of {', '.join(SELECTIONS)}, got {selection!r}")
        exploit = raw.get("exploit", 0.0)
        if (isinstance(exploit, bool) or not isinstance(exploit, int | float)
                or not 0.0 <= exploit <= 1.0):
            raise SgrError(f"{name}.exploit' must be a share from 0 to 1, got {exploit!r}")
        return cls(tuple(names), ranges, tuple(res), counts["batch"], counts["initial"], counts["rescore"],
                   float(offset), selection, float(exploit))

    @property
    def behaviour(self) -> bool:
        """Whether a descriptor describes behaviour (the rollout then records it)."""
        return needs_behaviour(self.descriptors)

    def measure(self, body: np.ndarray, features: np.ndarray | None = None) -> np.ndarray:
        """The descriptors of a (valid) body, in order; `features`: its behaviour features (the
        mean over its scored episodes), which behaviour descriptors read."""
        return measure(self.descriptors, body, features)

# configs/map-elites/<task>.yaml (tools/gen_configs.py writes one per task; tests check the files)
MAP_ELITES_CONFIG = PackagedConfig(
    template="""\
# MAP-Elites with SGR genomes on $task$about
method: map-elites
task: $task
# The budget of SGR's 100 generations of configs/sgr/<task>.yaml: those runs simulated 8,109 to 9,107
# episodes (mean 8,648; results/robust-fast/runs/sgr-*/generations.csv, column episodes). Here a
# generation simulates its 64 valid children and re-scores at most 24 elites: at most 88 episodes, at
# most 8,800 in 100 generations (fewer while the archive is small).
generations: 100
pop_size: 128                # sizes the final selection alone, as SGR's 128 genomes do
seed: 0
robot_shape: [5, 5]
$episode
neat_config: ../neat/sgr.ini  # NEAT's crossover and mutation; no speciation
cppn_outputs: 1
weight_threshold: 0.2
max_weight: 1.0
checkpoint_every: 5
render_champion: true
qd:
  descriptors: [actuator, rigid]  # the body's voxel shares; or behaviour: [gait_frequency, contact]
  resolution: [10, 10]            # cells per descriptor
  batch: 64                       # valid children per generation
  initial: 64                     # valid random genomes of the first generation
  rescore: 24                     # elites re-scored per generation at most (fewest scores first)
  selection: curiosity            # parents: elites whose children entered the archive drawn more often
  exploit: 0.5                    # half the children: parents the fittest of 4 elites drawn
  score_offset: auto              # the QD score counts fitness above the task's floor (qd_floors.py)
# Honest by default (docs/EVOLVE.md "Robust evaluation"): every action carries uniform(±1e-3)
# actuator noise; one episode per child, an elite's fitness the mean of its scores so far (re-scored
# until it has 8: settle); the champion chosen at the end among the archive's best elites
# (final_selection; auto: sized to at most a fifth of pop_size x generations episodes).
robust: {episodes: 1, action_noise: uniform, action_scale: 0.001, offset: 0.0, statistic: mean, \
reevaluate: true, accumulate: true, settle: 8}
final_selection: {candidates: auto, episodes: auto, statistic: mean, tolerance: 0.05, rank: pooled, \
confirm: auto, holdout: auto}
""",
    about=(': an archive of the best robot per kind of body (docs/EVOLVE.md).',
           ' (not in the SGR paper): an archive of the best robot per kind of body\n'
           "# (docs/EVOLVE.md); evogym's episode length."),
    paper_episode="episode_steps: null          # the paper's episode length")


class MapElitesProblem(SgrProblem):
    """SGR genomes (one CPPN: body and controller, evolve/methods/sgr/problem.py) searched by MAP-Elites
    (`MapElitesSearch`) instead of NEAT's speciated population."""

    name = "map-elites"
    packaged = MAP_ELITES_CONFIG
    config_keys = {**{k: v for k, v in SgrProblem.config_keys.items() if k != "body_distance_weight"},
                   "qd": (dict, {})}
    config_docs = {**{k: v for k, v in SgrProblem.config_docs.items() if k != "body_distance_weight"},
                   "qd": "The archive: its descriptors and cells, the batch of children, parent choice "
                         "and score_offset (docs/QD.md)."}
    absent_before = {}
    starts_from_runs = False  # (its search is an archive, not a NEAT population)
    keeps_archive = True

    def __init__(self, cfg, neat_config, pool: RolloutPool | None = None):
        super().__init__(cfg, neat_config, pool)
        self.qd = QdSettings.from_config(dict(self.cfg.qd), tuple(self.cfg.robot_shape), self.cfg.pop_size,
                                         task=self.cfg.task)
        self.record_behaviour = self.qd.behaviour

    @classmethod
    def validate(cls, cfg, source: str) -> None:
        """SGR's checks, the `qd` key's, no `start_from` (a NEAT population), and pyribs installed."""
        super().validate(cfg, source)
        QdSettings.from_config(dict(cfg.qd), tuple(cfg.robot_shape), cfg.pop_size, source, cfg.task)
        if cfg.start_from is not None:
            raise SgrError(f"{source}: key 'start_from' is not for method 'map-elites': it continues a "
                           "NEAT population")
        require_ribs()

    def make_search(self, neat_config, seed: int, state: dict | None = None) -> MapElitesSearch:
        """The MAP-Elites search over this problem (`state`: a checkpoint's, decoded)."""
        require_ribs()
        return MapElitesSearch(self, neat_config, seed=seed, state=state)

    @classmethod
    def encode_search(cls, state: dict) -> dict:
        """`MapElitesSearch.state()` is JSON data already."""
        return state

    @classmethod
    def decode_search(cls, data, neat_config, cfg) -> dict:
        """A checkpoint's search data checked field by field (`MapElitesSearch.decode_state`)."""
        return MapElitesSearch.decode_state(data, neat_config)
