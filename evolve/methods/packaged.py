"""The configs sgr ships for its methods, configs/<method>/<task>.yaml: each method declares its
own `PackagedConfig` (`Problem.packaged`) and tools/gen_configs.py writes one file per task from it.

Every packaged config evolves under the honest evaluation of docs/EVOLVE.md "Robust evaluation".
The episode length: the SGR paper's four tasks keep `episode_steps: null` (the paper's length)
where the method says so; the other 28 get evogym's registered max_episode_steps, written out.
"""

from __future__ import annotations

from dataclasses import dataclass
from string import Template

from tasks.specs import TASKS

PAPER_TASKS = ("Walker-v0", "ObstacleTraverser-v1", "Climber-v2", "Thrower-v0")  # the SGR paper's

# the honest evaluation of docs/EVOLVE.md "Robust evaluation", as the NEAT methods' configs have it
ROBUST_ACCUMULATED = """\
# Honest by default (docs/EVOLVE.md "Robust evaluation"): every action carries uniform(±1e-3)
# actuator noise; one fresh episode per genome and generation, a survivor's fitness the mean of its
# scores so far (8 at most, then it is not simulated again: settle); the champion chosen at the end \
among the final elites (final_selection; auto: sized to at most a fifth of the run's episodes). For the
# paper's nominal evaluation (knife-edge champions) set both to null, as configs/sweeps/paper.yaml does.
robust: {episodes: 1, action_noise: uniform, action_scale: 0.001, offset: 0.0, statistic: mean, \
reevaluate: true, accumulate: true, settle: 8}
final_selection: {candidates: auto, episodes: auto, statistic: mean, tolerance: 0.05, rank: pooled, \
confirm: auto, holdout: auto}
"""


@dataclass(frozen=True)
class PackagedConfig:
    """A method's packaged config: one commented YAML template, filled in per task.

    Attributes:
        template: the YAML text, with `$task`, `$about` (the first line's end) and `$episode` (the
            `episode_steps` line).
        about: the first line's end for the SGR paper's four tasks, and for the other 28.
        paper_episode: the `episode_steps` line of the paper's tasks; None: evogym's length for
            every task.
    """

    template: str
    about: tuple[str, str]
    paper_episode: str | None = None

    def render(self, task: str) -> str:
        """The text of the config for `task` (one of sgr's 32)."""
        paper = task in PAPER_TASKS
        episode = (self.paper_episode if paper and self.paper_episode is not None else
                   f"episode_steps: {TASKS[task].evogym_steps:<19}# evogym's max_episode_steps for {task}")
        return Template(self.template).substitute(task=task, about=self.about[0 if paper else 1],
                                                  episode=episode)
