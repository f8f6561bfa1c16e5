"""Task branches the random robots of tests/data/evogym32 never reach (goals of BridgeWalker-v0,
CaveCrawler-v0, Climber-v0/-v1 and Traverser-v0, Traverser-v0's floor sight over its blocks,
Catcher-v0's package below y = 0.5, evogym's built-in ground plane y < 0; and since issue 28 every
other reward and termination branch of every task, both sides of its line, listed in
test_evogym_branches.py and docs/VALIDATION.md), against evogym 2.0.0 episodes that start from a
moved state
(`state_cases.npz`, recorded by references/evogym_state_cases.py; README there): evogym's own
`Sim.translate_object` moved the robot (or a package or beam) right after reset, and we move ours
by the same (dx, dy) in `env.sim.state`, then replay the same actions. Two BidirectionalWalker-v0
cases move the robot again before every step (to each goal in turn, evogym's `Sim.revert(now)`
after each move, so its "all goals done" is reached and missed); ours makes the same moves and the
same state edit before the same steps.

Per case: the moved points equal evogym's, and every step's reward, observation (floor and ceiling
sight included), robot COM (and the package's or beam's COM) and the termination step match
evogym. The goal cases
come in pairs, the COM put 0.005 (a twentieth of a voxel) past and short of the goal line, so a goal
or top-of-pipe threshold off by a voxel in either direction fails one of them.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from tasks.env import BatchEnv
from tasks.orientation import PI_EVOGYM
from tasks.specs import task_spec


@pytest.fixture(scope="module")
def data(data_dir):
    return np.load(data_dir / "evogym32" / "state_cases.npz", allow_pickle=False)


def meta(data_dir: Path) -> list[dict]:
    """The recorded cases' descriptions (name, task, steps, seed, moves, termination step)."""
    return json.loads(str(np.load(data_dir / "evogym32" / "state_cases.npz", allow_pickle=False)["cases"]))


CASE_NAMES = [c["name"] for c in meta(Path(__file__).parents[1] / "data")]


def orientation_columns(task: str) -> list[int]:
    """Observation columns of the orientation blocks (all come before the robot's points)."""
    cols, col = [], 0
    for b in task_spec(task).observation:
        if b.width < 0:
            break
        if "orientation" in b.name:
            cols.append(col)
        col += b.width
    return cols


def translate(env: BatchEnv, name: str, dx: float, dy: float) -> None:
    """Move object `name` of world 0 by (dx, dy) as evogym's translate_object does: it adds (dx, dy)
    to the current positions only (not to the last positions: ours stay where reset or the last
    substep put them, as evogym's do, which matters once a moved body touches something in the
    first substep) and re-saves the snapshot of the current time; at time 0 (before the first
    step) that is the reference of the orientation and of a reset (our `_pos0`s)."""
    d = np.array([dx, dy])
    if name == "robot":
        pts = np.arange(env.n_points[0])
        if env.t == 0:
            env._pos0[0, pts] += d
    else:
        pts = env._obj_index[name][1][0]
    env.sim.state[0, pts, 0:2] += d
    if env.t == 0:
        env.sim.initial_positions[0, pts] += d


def revert_now(env: BatchEnv) -> None:
    """evogym's `Sim.revert(now)` right after a move: the snapshot just saved is reloaded, with
    every point's last position set to its position and its true velocity to its velocity
    (our state columns pos 0:2, vel 2:4, pos_last 4:6, vel_true 6:8, tsim/kernels/layout.py)."""
    s = env.sim.state[0]
    s[:, 4:6] = s[:, 0:2]
    s[:, 6:8] = s[:, 2:4]


def replay(z, case: dict) -> dict:
    """Our episode of one recorded case: the env, then the moves, then the recorded actions, with
    the moves recorded before later steps (`step_moves`) made before those steps."""
    pre = case["name"] + "/"
    env = BatchEnv(case["task"], [z[pre + "body"]], episode_steps=case["steps"],
                   seeds=[case["seed"]])
    revert = case.get("revert_after_moves", False)
    for name, dx, dy in case["moves"]:
        translate(env, name, dx, dy)
    if revert:
        revert_now(env)
    env.observe()
    moved = {name: (env.sim.robot_pos(0) if name == "robot" else env.sim.object_pos(0, name))
             for name, _, _ in case["moves"]}
    tracked = env.spec.tracked[0] if env.spec.tracked else None  # the package or the beam
    rewards, obs, coms = [], [], [env.sim.robot_com()[0]]
    other = [env.sim.object_pos(0, tracked).mean(axis=1)] if tracked else []
    term_step = -1
    later = {}
    for t, name, dx, dy in case.get("step_moves", []):
        later.setdefault(t, []).append((name, dx, dy))
    moved_coms = []
    for t, a in enumerate(z[pre + "actions"]):
        if t in later:
            for name, dx, dy in later[t]:
                translate(env, name, dx, dy)
            if revert:
                revert_now(env)
            moved_coms.append(env.sim.robot_com()[0])
        o, r, term, _, _ = env.step([a])
        rewards.append(r[0])
        obs.append(o[0, :env.obs_dims[0]])
        coms.append(env.sim.robot_com()[0])
        if tracked:
            other.append(env.sim.object_pos(0, tracked).mean(axis=1))
        if term[0]:
            term_step = t
            break
    return {"moved": moved, "rewards": np.array(rewards), "obs": np.array(obs),
            "com": np.array(coms), "other_com": np.array(other), "term_step": term_step,
            "moved_com": np.array(moved_coms)}


@pytest.mark.parametrize("name", CASE_NAMES)
def test_moved_state_matches_evogym(data, data_dir, name):
    (case,) = [c for c in meta(data_dir) if c["name"] == name]
    pre = name + "/"
    ours = replay(data, case)
    for obj, p in ours["moved"].items():
        assert np.abs(p - data[pre + "pos0_" + obj]).max() <= 1e-15, obj
    assert ours["term_step"] == case["term_step"]
    assert len(ours["rewards"]) == case["steps_run"]
    assert np.abs(ours["rewards"] - data[pre + "rewards"]).max() <= 1e-12
    assert np.abs(ours["com"] - data[pre + "com"]).max() <= 1e-12
    if pre + "moved_com" in data:  # the robot's COM right after each move between steps
        assert np.abs(ours["moved_com"] - data[pre + "moved_com"]).max() <= 1e-12
    if pre + "other_com" in data:
        assert np.abs(ours["other_com"] - data[pre + "other_com"]).max() <= 1e-12
    ref = data[pre + "obs"]
    diff = np.abs(ours["obs"] - ref)
    for c in orientation_columns(case["task"]):
        # evogym's sign is that of a sum of cross products; for a body turned by next to nothing
        # (Catcher-v0's package lying on the ground) that sum is rounding noise, and the angle
        # comes out as a or 2 pi - a (pi = 3.1415926) by chance: accept either, near 0 only
        flipped = np.abs(ours["obs"][:, c] + ref[:, c] - 2 * PI_EVOGYM)
        near_zero = np.minimum(ref[:, c], 2 * PI_EVOGYM - ref[:, c]) < 0.01
        diff[:, c] = np.where(near_zero, np.minimum(diff[:, c], flipped), diff[:, c])
    assert diff.max() <= 1e-11


def test_cases_reach_the_branches(data, data_dir):
    """The recordings do reach what they are for (so the comparisons above test those branches)."""
    cases = {c["name"]: c for c in meta(data_dir)}
    for name in ("bridge_past_goal", "cave_past_goal", "climber_past_top", "climber_v0_past_top",
                 "traverser_past_goal"):
        assert cases[name]["term_step"] == 0
    assert cases["climber_short_of_top"]["term_step"] == -1
    assert cases["climber_v0_short_of_top"]["term_step"] == -1
    for name in ("bridge_short_of_goal", "cave_short_of_goal", "traverser_short_of_goal"):
        assert cases[name]["term_step"] > 0  # walks or tips over the line later
    # Catcher-v0: the package falls through y = 0.5 mid-episode, so both reward branches run
    y = data["catcher_package_falls_low/other_com"][:, 1]
    assert y[0] > 0.5 and y[-1] < 0.5
    # Traverser-v0: the blocks under the robot are in its floor sight and move
    obs = data["traverser_on_blocks/obs"]
    sight = obs[:, -11:]
    assert np.ptp(sight, axis=0).max() > 0.01
    # Walker-v0 left of its ground: points sink below y = 0 (the ground plane acts) and slide
    # (its friction acts); Walker's observation is the COM velocity, then all x, then all y
    obs = data["walker_on_ground_plane/obs"]
    com = data["walker_on_ground_plane/com"]
    n = (obs.shape[1] - 2) // 2
    y = obs[:, 2 + n:] + com[1:, 1:2]
    assert (y < 0).any(axis=1)[5:].all()
    assert np.ptp(com[:, 0]) > 0.005
