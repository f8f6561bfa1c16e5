"""BidirectionalWalker-v0: walk to a list of goals (voxel x, left and right of the start), one
after the other; +1 and the episode ends when the last is reached.

Task state per world, drawn anew at every reset from the world's random stream (`BatchEnv(...,
seeds=)`, `BatchEnv.seed`): the goals, drawn exactly as evogym draws them from Python's global
`random` (start at 35; draw `randrange(20, 50)` and add its distance from the previous one until
the distances reach 100), so a world seeded with s gets the goals evogym uses after
`random.seed(s); env.reset()`; and the index of the current goal.

Reward: how much the COM's x distance to the current goal shrank. A goal is reached when that
distance is below 0.2 after the step; the next goal is then evaluated at once with the same
positions, and the step's reward is that of the last goal evaluated. The observation shows the
goal as it was before the step's update (as evogym builds it before the reward).
"""

import random

import numpy as np

from tasks import observations as O
from tasks.spec import Block, Measure, TaskSpec

MAX_GOALS = 128  # goals beyond are dropped (the draw would need > 100 steps of distance < 1)


def draw_goals(rng: random.Random) -> dict[str, np.ndarray]:
    """A world's goals, drawn as evogym draws them (``randrange(20, 50)`` until 100 voxels of walking are
    planned), padded to MAX_GOALS; redrawn at every reset of the world."""
    pos, dist, goals = 35, 0, []
    while dist < 100:
        g = rng.randrange(20, 50)
        dist += abs(pos - g)
        pos = g
        goals.append(g)
    goals = goals[:MAX_GOALS]
    padded = np.full(MAX_GOALS, -1, dtype=np.int64)
    padded[:len(goals)] = goals
    return {"goals": padded, "n_goals": np.int64(len(goals)), "goal": np.int64(0),
            "goal_seen": np.int64(0)}


def _goal_x(state: dict, index: np.ndarray) -> np.ndarray:
    g = state["goals"][np.arange(len(index)), np.minimum(index, MAX_GOALS - 1)]
    return g * 0.1


def reward(before: Measure, after: Measure):
    """Progress towards the current goal; a goal within 0.2 of the COM after the step is done and the
    next one counts in the same step (evogym's loop); updates the goal index in the task state."""
    s = after.state
    s["goal_seen"][:] = s["goal"]
    out = np.zeros(len(after.com))
    todo = s["goal"] < s["n_goals"]
    while todo.any():
        gx = _goal_x(s, s["goal"])
        d1 = np.abs(gx - after.com[:, 0])
        out = np.where(todo, np.abs(gx - before.com[:, 0]) - d1, out)
        reached = todo & (d1 < 2 * 0.1)
        s["goal"] += reached
        todo = reached & (s["goal"] < s["n_goals"])
    return out


def all_goals_reached(before: Measure, after: Measure):
    """+1 and the end of the episode once every goal is done (evogym adds 1.0 to that step's
    reward)."""
    return np.ones(len(after.com)), after.state["goal"] >= after.state["n_goals"]


def _goal_block(s: O.Scene) -> np.ndarray:
    k = s.state["goal_seen"]
    gx = _goal_x(s.state, k)
    return np.stack([k.astype(float), gx, gx - s.com[:, 0]], axis=1)


GOAL = Block("current goal: index, x, x minus the robot's COM x", 3, _goal_block)

SPEC = TaskSpec(name="BidirectionalWalker-v0", world="BidirectionalWalker-v0.json", origin=(33, 1),
                paper_steps=1000, evogym_steps=1000, observation=(O.VCOM, O.POINTS, GOAL),
                reward=reward, termination=all_goals_reached, state=draw_goals, reads_points=False)
