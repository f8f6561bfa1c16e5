"""A method is one Problem subclass plus one registry line; runs need nothing else (the config
schema, the INI, the experiment loop and checkpoints come from the contract)."""

from dataclasses import dataclass

import numpy as np
import pytest

from evolve import METHODS, Experiment, Problem
from evolve.nn import CompiledCPPN
from evolve.records.rundir import RunDir

WALKER = np.array([[3, 3, 3, 3, 3], [3, 3, 3, 3, 3], [3, 3, 0, 3, 3], [3, 3, 0, 3, 3], [3, 3, 0, 3, 3]])


@dataclass
class Gait:
    body: np.ndarray
    amplitude: float
    valid: bool = True


class ConstantPolicy:
    """Every actuator at 1.1 + amplitude * sin(t / 4)."""

    def __init__(self, env, amplitudes):
        self.a, self.env = np.asarray(amplitudes)[:, None], env

    def act(self, obs):
        return 1.1 + self.a * np.sin(self.env.t / 4.0) * np.ones((len(obs), self.env.sim.max_actuators))


class GaitProblem(Problem):
    """A toy method: a fixed walker body whose gait amplitude a one-input CPPN decides."""

    name = "gait"
    config_keys = {"max_amplitude": (float, 0.5)}
    default_files = {"neat_config": "sgr.ini"}

    @classmethod
    def neat_overrides(cls, cfg):
        return {"DefaultGenome": {"num_inputs": "1", "num_outputs": "1"}}

    def decode(self, genome):
        y = CompiledCPPN(genome, self.neat_config.genome_config)(np.ones((1, 1)))[0, 0]
        return Gait(WALKER, float(np.clip(y, -1, 1)) * self.cfg.max_amplitude)

    def evaluate(self, phenotypes):
        fit = self.pool.run(self.cfg.task, [p.body for p in phenotypes], [p.amplitude for p in phenotypes],
                            ConstantPolicy, self.cfg.episode_steps)
        return fit, len(phenotypes)

    def champion(self, p):
        return {"body": p.body.tolist(), "controller": {"amplitude": p.amplitude}}


def test_a_registered_toy_method_runs_from_a_config_dict(tmp_path, monkeypatch):
    monkeypatch.setitem(METHODS, GaitProblem.name, GaitProblem)  # the registry line
    exp = Experiment.from_config({"method": "gait", "task": "Walker-v0", "generations": 3, "pop_size": 6,
                                  "episode_steps": 12, "workers": 1, "render_champion": False,
                                  "max_amplitude": 0.4, "robust": None, "final_selection": None},
                                 tmp_path / "run", quiet=True)
    exp.run_all()
    exp.close()
    run = RunDir(tmp_path / "run")
    rows = run.rows()
    assert [int(r["generation"]) for r in rows] == [1, 2, 3]  # counted from 1
    champ = run.champion()
    assert champ["method"] == "gait" and champ["fitness"] == max(float(r["best"]) for r in rows)
    assert abs(champ["controller"]["amplitude"]) <= 0.4
    assert run.config()["max_amplitude"] == 0.4


def test_an_unknown_method_and_a_key_of_another_method_are_named(tmp_path):
    with pytest.raises(ValueError,
                       match="key 'method' must be one of sgr, direct, nested, map-elites, ga-ppo, "
                             "got 'gait'"):
        Experiment.from_config({"method": "gait", "task": "Walker-v0"}, tmp_path / "a")
    with pytest.raises(ValueError, match="unknown key 'inner_pop_size' for method 'sgr'"):
        Experiment.from_config({"method": "sgr", "task": "Walker-v0", "inner_pop_size": 3}, tmp_path / "b")
