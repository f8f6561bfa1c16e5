"""The SGR method: a CPPN genome decoded into a body and a controller, fitness = episode return."""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from evolve.evaluate import dense_policy
from evolve.rollout_pool import RolloutPool
from evolve.sgr_decoder import DecoderSettings, Phenotype, decode


class SgrProblem:
    """Decode and evaluate callables for `NeatSearch`, from a resolved config."""

    def __init__(self, cfg: dict, neat_config, pool: RolloutPool | None = None):
        self.cfg = cfg
        self.pool = pool or RolloutPool(1)
        self.genome_config = neat_config.genome_config
        self.settings = DecoderSettings(shape=tuple(cfg["robot_shape"]), cppn_outputs=cfg["cppn_outputs"],
                                        threshold=cfg["weight_threshold"], max_weight=cfg["max_weight"])

    @staticmethod
    def neat_overrides(cfg: dict) -> dict:
        return {"DefaultGenome": {"num_inputs": "7", "num_outputs": str(cfg["cppn_outputs"])}}

    def decode(self, genome) -> Phenotype:
        return decode(genome, self.genome_config, self.cfg["task"], self.settings)

    def evaluate(self, phenotypes: Sequence[Phenotype]) -> np.ndarray:
        return self.pool.run(self.cfg["task"], [p.body for p in phenotypes],
                             [p.controller for p in phenotypes], dense_policy, self.cfg["episode_steps"])

    def champion(self, phenotype: Phenotype) -> dict:
        return {"body": phenotype.body.tolist(), "controller": phenotype.controller.to_json()}
