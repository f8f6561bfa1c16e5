"""Static facts of the four tasks (spec section 7): world, robot placement, episode lengths."""

from __future__ import annotations

from dataclasses import dataclass


@dataclass(frozen=True)
class TaskSpec:
    name: str
    origin: tuple[int, int]  # grid cell of the bottom-left of the robot's body matrix
    paper_steps: int  # episode length used by the SGR paper (our default)
    evogym_steps: int  # evogym's registered max_episode_steps


TASKS: dict[str, TaskSpec] = {
    "Walker-v0": TaskSpec("Walker-v0", (1, 1), 500, 500),
    "ObstacleTraverser-v1": TaskSpec("ObstacleTraverser-v1", (2, 4), 600, 1000),
    "Climber-v2": TaskSpec("Climber-v2", (1, 1), 400, 1000),
    "Thrower-v0": TaskSpec("Thrower-v0", (1, 1), 300, 300),
}


def task_spec(name: str) -> TaskSpec:
    try:
        return TASKS[name]
    except KeyError:
        raise ValueError(f"unknown task {name!r}; known tasks: {', '.join(TASKS)}") from None
