"""Genomes and search on top of tasks: evolve the bodies and controllers of robots, and run experiments.

SGR and the paper's baselines behind one contract (`evolve.methods`), NEAT plumbing (`evolve.search`),
networks (`evolve.nn`), batched rollouts (`evolve.rollout`), the run's lifecycle (`evolve.runs`), what a
run leaves on disk (`evolve.records`), sweeps (`evolve.sweeps`), reports (`evolve.report`), and the
`sgr` command line.

    from evolve import Experiment, load_champion
    exp = Experiment.from_config({"method": "sgr", "task": "Walker-v0", "generations": 5,
                                  "pop_size": 16, "episode_steps": 100}, out="runs/notebook")
    exp.run_all(); exp.finish()
    champ = load_champion("runs/notebook")   # body, policy(obs) -> action, episode length, env()
"""

from evolve.own_modules import use_own_modules

use_own_modules()  # tsim and tasks are sgr's, whatever else the path holds (evolve/own_modules.py)

from evolve.methods import METHODS, Problem  # noqa: E402
from evolve.records.replay import Champion, load_champion  # noqa: E402
from evolve.runs import Experiment, RunDir, config_from_dict, load_config  # noqa: E402

__all__ = ["METHODS", "Champion", "Experiment", "Problem", "RunDir", "config_from_dict", "load_champion",
           "load_config"]
