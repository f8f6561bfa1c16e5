"""Direct-encoding NEAT baseline: one NEAT network per genome is both body generator and controller.

Inputs: 2 body coordinates + the observation (zero-padded to the largest robot of the grid).
Body: each cell's (x, y) with the observation inputs at 0, argmax of the 5 material outputs.
Control, config key `layout`:
- "per_output" (default; the paper's description): outputs 5 materials + one per body cell;
  coordinates 0, the observation in the rest; actions are the cell outputs at actuator cells
  (evogym's order), 1.1 + 0.5 * y.
- "per_cell" (ours): outputs 5 materials + 1 action; the network is queried once per actuator
  with its cell's (x, y) and the observation, as SGR's CPPN is queried per substrate node.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from functools import partial

import numpy as np

from evolve.methods import formats
from evolve.methods.base import Problem
from evolve.methods.packaged import ROBUST_ACCUMULATED, PackagedConfig
from evolve.methods.sgr.decoder import is_valid_robot
from evolve.methods.sgr.substrates import N_TYPES, cell_coordinates
from evolve.nn.batch import GraphPolicy, NetworkBatch
from evolve.nn.cppn import CompiledCPPN
from evolve.nn.genome_record import genome_json
from evolve.nn.graph import DERIVED_FORMAT, FORMAT, GraphController, graph_of_record
from evolve.rollout.pool import RolloutPool
from tasks.env import obs_dim
from tsim.body import build_body
from tsim.errors import SgrError

N_COORDS = 2


def n_inputs(task: str, shape: tuple[int, int]) -> int:
    """NEAT input count: 2 cell coordinates + the observation of the largest robot the shape allows
    ((H+1)(W+1) points, every cell filled); smaller robots' observations are zero-padded."""
    return N_COORDS + obs_dim(task, (shape[0] + 1) * (shape[1] + 1))


@dataclass
class DirectPhenotype:
    """A decoded direct genome: its body, whether it is a valid robot, and the genome itself, which
    is also the controller."""
    body: np.ndarray
    valid: bool
    genome: object = None


LAYOUTS = ("per_output", "per_cell")


def direct_policy(env, genomes: Sequence, genome_config, cell_xy: np.ndarray | None = None) -> GraphPolicy:
    """Batched direct-encoding networks driving the robots of env (picklable for `RolloutPool`);
    `cell_xy` (the body cells' coordinates) selects the per_cell layout."""
    cells = [b.actuator_flat for b in env.sim.bodies]
    return GraphPolicy(NetworkBatch(list(genomes), genome_config), cells, env.sim.max_actuators,
                       N_COORDS, N_TYPES, cell_xy=cell_xy)


def _derived(record: dict) -> GraphController:
    """direct's network recorded as its genome's compiled form: compiled again, checked."""
    return GraphController.from_derived_json(record["controller"], record["genome"])


formats.register(FORMAT, graph_of_record)
formats.register(DERIVED_FORMAT, _derived)

# configs/direct/<task>.yaml (tools/gen_configs.py writes one per task; tests check the files)
DIRECT_CONFIG = PackagedConfig(
    template="""\
# Direct-encoding NEAT baseline on $task$about
method: direct
task: $task
generations: 250
pop_size: 128
seed: 0
robot_shape: [5, 5]
$episode
neat_config: ../neat/direct.ini
body_distance_weight: 0.0    # plain NEAT speciation, as in the paper's baseline
checkpoint_every: 5
render_champion: true
""" + ROBUST_ACCUMULATED,
    about=(' (one network: body coordinates + observation -> materials + actions).',
           ' (not in the SGR paper; one network: body coordinates + observation -> materials\n'
           "# + actions) with the paper's settings and evogym's episode length."),
    paper_episode="episode_steps: null          # the paper's episode length")


class DirectProblem(Problem):
    """The paper's direct-encoding baseline: one NEAT network is both body generator and
    controller (layouts in the module docstring)."""

    name = "direct"
    packaged = DIRECT_CONFIG
    config_keys = {"body_distance_weight": (float, 0.0), "layout": (str, "per_output")}
    config_docs = {
        "body_distance_weight": "How much two genomes' bodies count in their speciation distance (0: "
                                "the genome alone).",
        "layout": "per_output (the paper's: one network, an output per cell and material) or per_cell "
                  "(the network queried once per cell with its coordinates).",
    }
    default_files = {"neat_config": "direct.ini"}


    @classmethod
    def decode_refusal(cls, cfg, shape):
        """Direct NEAT's network is sized to its run's body: it decodes at that size only."""
        if tuple(shape) == tuple(cfg.robot_shape):
            return None
        return (f"direct NEAT's network reads the observation of a full {cfg.robot_shape[0]}x"
                f"{cfg.robot_shape[1]} body (and, in its default layout, has one output per cell): its "
                f"controller decodes at that size only, not at {shape[0]}x{shape[1]}")

    def __init__(self, cfg: dict, neat_config, pool: RolloutPool | None = None):
        super().__init__(cfg, neat_config, pool)
        self.gc = neat_config.genome_config
        self.shape = tuple(self.cfg.robot_shape)
        self.cells = cell_coordinates(self.shape)
        self.per_cell = self.cfg.layout == "per_cell"

    @classmethod
    def validate(cls, cfg: dict, source: str) -> None:
        """`layout` must be per_output or per_cell."""
        if cfg.layout not in LAYOUTS:
            raise SgrError(f"{source}: key 'layout' must be 'per_output' or 'per_cell', "
                           f"got {cfg.layout!r}")

    @classmethod
    def neat_overrides(cls, cfg: dict) -> dict:
        """Inputs as `n_inputs`; outputs: 5 materials, then one per body cell (per_output) or one
        action (per_cell)."""
        shape = tuple(cfg.robot_shape)
        n_control = 1 if cfg.layout == "per_cell" else shape[0] * shape[1]
        return {"DefaultGenome": {"num_inputs": str(n_inputs(cfg.task, shape)),
                                  "num_outputs": str(N_TYPES + n_control)}}

    def decode(self, genome) -> DirectPhenotype:
        """Query the network at every cell's (x, y) with the observation inputs at 0; body = argmax
        of the 5 material outputs (H, W), possibly invalid."""
        x = np.zeros((len(self.cells), len(self.gc.input_keys)))
        x[:, :N_COORDS] = self.cells
        out = CompiledCPPN(genome, self.gc)(x)[:, :N_TYPES]
        body = np.argmax(out, axis=1).reshape(self.shape).astype(np.int64)
        return DirectPhenotype(body, is_valid_robot(body), genome)

    def evaluate(self, phenotypes: Sequence[DirectPhenotype],
                 tags: Sequence[str] | None = None) -> tuple[np.ndarray, int]:
        """One episode per phenotype (K with `robust`, `Problem.rollout`), its genome's network as
        controller in the configured layout."""
        return self.rollout([p.body for p in phenotypes], [p.genome for p in phenotypes],
                            partial(direct_policy, genome_config=self.gc,
                                    cell_xy=self.cells if self.per_cell else None), tags)

    def champion(self, p: DirectPhenotype) -> dict:
        """The body and the network as GraphController JSON (inputs from offset 2, actions from
        output 5; per_cell also stores each actuator cell's (x, y))."""
        b = build_body(p.body)
        cell_inputs = self.cells[np.asarray(b.actuator_flat, dtype=np.int64)] if self.per_cell else None
        ctrl = GraphController.from_genome(p.genome, self.gc, obs_dim(self.cfg.task, b.n_points),
                                           N_COORDS, N_TYPES, b.actuator_flat, cell_inputs)
        return {"body": p.body.tolist(), "controller": ctrl.to_json()}

    def champion_of(self, genome, p: DirectPhenotype) -> dict:
        """`champion` with the network recorded as the genome's compiled form (~1 KB instead of ~80
        KB at 10x10; `GraphController.to_derived_json`), in full where compiling the genome's record
        would not give it back exactly."""
        keys = self.champion(p)
        ctrl = GraphController.from_json(keys["controller"])
        derived = ctrl.to_derived_json()
        try:
            again = GraphController.from_derived_json(derived, genome_json(genome))
        except ValueError:
            return keys
        return {**keys, "controller": derived} if again.to_json() == keys["controller"] else keys

    @classmethod
    def compact_controller(cls, record: dict, controller, raw: dict | None) -> dict | None:
        """A network recorded in full, as the compiled form of the record's genome."""
        if record["controller"].get("format") != FORMAT or "genome" not in record:
            return None
        return controller.to_derived_json()
