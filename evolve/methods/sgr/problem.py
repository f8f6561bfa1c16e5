"""The SGR method: a CPPN genome decoded into a body and a controller, fitness = episode return."""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from evolve.methods import formats
from evolve.methods.base import Problem
from evolve.methods.packaged import ROBUST_ACCUMULATED, PackagedConfig
from evolve.methods.sgr import record as sgr_record
from evolve.methods.sgr.decoder import DecoderSettings, Phenotype, decode
from evolve.methods.sgr.decoders import DEFAULT as DEFAULT_DECODER
from evolve.methods.sgr.decoders import body_decoder
from evolve.nn.dense import FORMAT as DENSE_FORMAT
from evolve.nn.dense import DenseController
from evolve.rollout.episodes import dense_policy
from evolve.rollout.pool import RolloutPool
from tsim.errors import SgrError


def _dense(record: dict) -> DenseController:
    """SGR's controller recorded in full (dense layers)."""
    return DenseController.from_json(record["controller"])


formats.register(DENSE_FORMAT, _dense)
formats.register(None, _dense)  # an older sgr's, untagged
formats.register(sgr_record.FORMAT, sgr_record.rebuild)  # as its genome's decoding, checked

# configs/sgr/<task>.yaml (tools/gen_configs.py writes one per task; tests check the files)
SGR_CONFIG = PackagedConfig(
    template="""\
# SGR (single genome, HyperNEAT-decoded body + controller) on $task$about
method: sgr
task: $task
generations: 250
pop_size: 128
seed: 0
robot_shape: [5, 5]
$episode
neat_config: ../neat/sgr.ini
cppn_outputs: 1              # 1 as in the paper; 2 = separate body / controller outputs
weight_threshold: 0.2
max_weight: 1.0
body_distance_weight: 0.1    # v of the paper's eq. 1 (our choice, see docs/EVOLVE.md)
body_decoder: substrate      # the paper's; or cppn, fourier, growth (docs/EVOLVE.md "Body decoders")
checkpoint_every: 5
render_champion: true
""" + ROBUST_ACCUMULATED,
    about=(" with the paper's settings.",
           " (not in the SGR paper) with the paper's settings\n"
           "# and evogym's episode length."),
    paper_episode="episode_steps: null          # null = the paper's episode length for the task")


class SgrProblem(Problem):
    """One CPPN genome, queried HyperNEAT-style over a 3-D substrate: a body network (z > 0) and
    a controller network (z < 0); fitness is the episode return (docs/EVOLVE.md)."""

    name = "sgr"
    packaged = SGR_CONFIG
    config_keys = {"cppn_outputs": (int, 1), "weight_threshold": (float, 0.2), "max_weight": (float, 1.0),
                   "body_distance_weight": (float, 0.1), "body_decoder": (str, DEFAULT_DECODER),
                   "body_decoder_settings": (dict, {})}
    config_docs = {
        "cppn_outputs": "1 (the paper's): one CPPN output feeds the body and the controller network; 2 "
                        "(the authors' code): one output each.",
        "weight_threshold": "A substrate link exists where the CPPN's |w| exceeds this; its weight is "
                            "sign(w)(|w| - threshold)/(1 - threshold) x max_weight.",
        "max_weight": "The largest weight of a substrate link.",
        "body_distance_weight": "How much two genomes' bodies count in their speciation distance, beside "
                                "neat-python's genomic distance (0: the genome alone).",
        "body_decoder": "How a genome draws its body: substrate (the paper's), cppn, fourier or growth "
                        "(docs/EVOLVE.md \"Body decoders\").",
        "body_decoder_settings": "The body decoder's own settings (docs/EVOLVE.md \"Body decoders\").",
    }
    default_files = {"neat_config": "sgr.ini"}
    absent_before = {"body_distance_weight": 0.0}  # an older run speciated by the genome alone
    starts_from_runs = True  # its CPPNs are free of the body's size: a run may start from another's

    def __init__(self, cfg: dict, neat_config, pool: RolloutPool | None = None):
        super().__init__(cfg, neat_config, pool)
        self.genome_config = neat_config.genome_config
        self.settings = settings_of_config(self.cfg, tuple(self.cfg.robot_shape))

    @classmethod
    def validate(cls, cfg: dict, source: str) -> None:
        """`cppn_outputs` must be 1 (one output read by both networks) or 2 (body, controller);
        `max_weight` > 0, `weight_threshold` and `body_distance_weight` >= 0 (finite: every float
        key is);
        `body_decoder` a registered decoder (evolve/methods/sgr/decoders/) and
        `body_decoder_settings` its settings."""
        if cfg.cppn_outputs not in (1, 2):
            raise SgrError(f"{source}: key 'cppn_outputs' must be 1 or 2, got {cfg.cppn_outputs}")
        for key, least, strict in (("max_weight", 0.0, True), ("weight_threshold", 0.0, False),
                                   ("body_distance_weight", 0.0, False)):
            v = getattr(cfg, key, None)  # (a method built on SGR's decoding may have no speciation)
            if v is not None and (v < least or strict and v == least):
                raise SgrError(f"{source}: key {key!r} must be {'>' if strict else '>='} {least:g}, got {v}")
        body_decoder(cfg.body_decoder, source).resolve(cfg.body_decoder_settings, source)

    @classmethod
    def neat_overrides(cls, cfg: dict) -> dict:
        """The CPPN: 7 inputs (x1, y1, z1, x2, y2, z2, bias) and the outputs the body decoder reads
        (1 for the paper's), plus the controller's own one with `cppn_outputs: 2`."""
        outputs = body_decoder(cfg.body_decoder).body_outputs + cfg.cppn_outputs - 1
        return {"DefaultGenome": {"num_inputs": "7", "num_outputs": str(outputs)}}

    def decode(self, genome) -> Phenotype:
        """Body and dense controller from the CPPN (`evolve.methods.sgr.decoder.decode`); an invalid
        body gets no controller."""
        return decode(genome, self.genome_config, self.cfg.task, self.settings)

    def evaluate(self, phenotypes: Sequence[Phenotype],
                 tags: Sequence[str] | None = None) -> tuple[np.ndarray, int]:
        """One episode per phenotype with its dense controller (K with `robust`, `Problem.rollout`);
        fitness = return."""
        return self.rollout([p.body for p in phenotypes], [p.controller for p in phenotypes],
                            dense_policy, tags)

    def champion(self, phenotype: Phenotype) -> dict:
        """The body and the DenseController JSON in full (runnable with numpy alone)."""
        return {"body": phenotype.body.tolist(), "controller": phenotype.controller.to_json()}

    def champion_of(self, genome, phenotype: Phenotype) -> dict:
        """The body and the controller recorded as the genome's decoding (sgr-hyperneat-controller-1,
        `sgr_record`; a few hundred bytes instead of ~0.5 MB at 10x10), in full where decoding the
        genome's record would not give it back bit for bit."""
        body = phenotype.body
        ctrl = sgr_record.recorded(genome, phenotype.controller, self.settings, body, self.cfg.task)
        return {"body": body.tolist(), "controller": ctrl}

    @classmethod
    def compact_controller(cls, record: dict, controller, raw: dict | None) -> dict | None:
        """A dense controller recorded in full, as its genome's decoding (`sgr_record`), with the
        decoder settings of its run's config.yaml (`raw`; the defaults where absent) at its body's
        shape."""
        if record["controller"].get("format") != DENSE_FORMAT or "genome" not in record:
            return None
        keys = {k: default for k, (_, default) in cls.config_keys.items()} | dict(raw or {})
        body = np.asarray(record["body"])
        settings = settings_of_config(keys, (int(body.shape[0]), int(body.shape[1])))
        return sgr_record.to_json(controller, settings)


def settings_of_config(cfg, shape: tuple[int, int]) -> DecoderSettings:
    """The decoder settings of a config (a `RunConfig`, or a mapping of sgr's keys) at `shape`."""
    get = cfg.__getitem__ if isinstance(cfg, dict) else lambda k: getattr(cfg, k)
    decoder = body_decoder(get("body_decoder"))
    return DecoderSettings(shape=shape, cppn_outputs=int(get("cppn_outputs")),
                           threshold=float(get("weight_threshold")), max_weight=float(get("max_weight")),
                           body_decoder=decoder.name,
                           body_settings=decoder.resolve(get("body_decoder_settings")))
