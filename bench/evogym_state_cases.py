"""Record evogym 2.0.0 episodes that start from a moved state, for the task branches the random
robots of `evogym_reference.py` never reach: a robot's COM just past / just short of a goal
(BridgeWalker-v0, CaveCrawler-v0, Climber-v0, Climber-v1, Traverser-v0), a robot standing on
Traverser-v0's loose blocks (floor sight over moving objects), Catcher-v0's package falling through
y = 0.5, a robot left of the start of Walker-v0's ground, on evogym's built-in ground plane (y < 0).

Run under the evogym venv (sgr never imports evogym):

    /root/.cache/evogym-venv/bin/python bench/evogym_state_cases.py

Each case: the body, seed and actions of trace case 1 of the task (tests/data/evogym32), a fresh
env, `reset` as in `evogym_reference.py`, then evogym's own `Sim.translate_object(dx, dy, name)`
(the C++ simulator adds (dx, dy) to every point of the object and re-saves the time-0 snapshot)
for each listed move, then `env.step(actions[t])` until termination or the case's step count.
Writes tests/data/evogym32/state_cases.npz (deterministic bytes; README there has the keys).
"""

from __future__ import annotations

import argparse
import json
import os
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import evogym_reference as R  # noqa: E402  (evogym venv only)

DATA = Path(__file__).resolve().parent.parent / "tests" / "data" / "evogym32"

# name, task, steps, moves: (object, rule) where a rule places the object from its reset points
# p (2, n): ("com_x", x, bottom_y) puts its COM x at x and its lowest point at bottom_y;
# ("com_y", y) puts its COM y at y; ("beside_robot", gap, bottom_y) puts its left edge gap right
# of the robot's right edge and its lowest point at bottom_y.
# The climbers' cases but "climber_squeezed" use NARROW_BODY: 3 voxels wide in the 5-wide pipe, it
# touches no wall and falls freely (slowly at first), so a COM put 0.005 above the top stays above
# it for step 0; the trace body fills the pipe's width and is thrown down by the soft wall patches.
CASES: list[tuple[str, str, int, list[tuple[str, tuple]]]] = [
    ("bridge_past_goal", "BridgeWalker-v0", 30, [("robot", ("com_x", 6.005, 0.52))]),
    ("bridge_short_of_goal", "BridgeWalker-v0", 30, [("robot", ("com_x", 5.995, 0.52))]),
    ("cave_past_goal", "CaveCrawler-v0", 30, [("robot", ("com_x", 6.905, 1.02))]),
    ("cave_short_of_goal", "CaveCrawler-v0", 30, [("robot", ("com_x", 6.895, 1.02))]),
    ("climber_past_top", "Climber-v1", 30, [("robot", ("com_y", 6.505))]),
    ("climber_short_of_top", "Climber-v1", 30, [("robot", ("com_y", 6.495))]),
    ("climber_squeezed", "Climber-v1", 30, [("robot", ("com_y", 6.3))]),
    ("climber_v0_past_top", "Climber-v0", 30, [("robot", ("com_y", 8.605))]),
    ("climber_v0_short_of_top", "Climber-v0", 30, [("robot", ("com_y", 8.595))]),
    ("traverser_past_goal", "Traverser-v0", 30, [("robot", ("com_x", 5.905, 0.72))]),
    ("traverser_short_of_goal", "Traverser-v0", 30, [("robot", ("com_x", 5.895, 0.72))]),
    ("traverser_on_blocks", "Traverser-v0", 50, [("robot", ("com_x", 3.2, 0.95))]),
    ("catcher_package_falls_low", "Catcher-v0", 50, [("package", ("beside_robot", 0.3, 0.45))]),
    ("walker_on_ground_plane", "Walker-v0", 25, [("robot", ("com_x", -1.0, 0.02))]),
]


NARROW_BODY = np.array([[0, 0, 0, 0, 0], [0, 0, 0, 0, 0], [0, 3, 3, 3, 0], [0, 4, 2, 4, 0],
                        [0, 3, 3, 3, 0]])


def trace_case(task: str, name: str) -> dict:
    """Body, seed and actions of the task's trace case 1 (= returns case 0); NARROW_BODY with the
    program of the same seed for the climbers' free-fall cases."""
    (f,) = sorted(DATA.glob(f"trace_{task}_1_*.npz"))
    z = np.load(f, allow_pickle=False)
    out = {"body": z["body"], "seed": int(z["seed"]), "actions": z["actions"], "file": f.name}
    if task.startswith("Climber") and name != "climber_squeezed":
        n_act = int(np.isin(NARROW_BODY, (3, 4)).sum())
        out.update(body=NARROW_BODY, actions=R.program(out["seed"], n_act, 50)[3],
                   file="NARROW_BODY")
    return out


def move_for(u, name: str, rule: tuple) -> tuple[float, float]:
    """(dx, dy) that puts object `name` where `rule` says (see CASES)."""
    p = np.asarray(u.object_pos_at_time(0, name))
    c = p.mean(axis=1)
    if rule[0] == "com_x":
        return rule[1] - c[0], rule[2] - p[1].min()
    if rule[0] == "com_y":
        return 0.0, rule[1] - c[1]
    if rule[0] == "beside_robot":
        r = np.asarray(u.object_pos_at_time(0, "robot"))
        return r[0].max() + rule[1] - p[0].min(), rule[2] - p[1].min()
    raise ValueError(rule)


def run_case(name: str, task: str, steps: int, moves: list) -> dict:
    """One moved episode in a fresh env (run in a forked child, see R.isolated)."""
    tc = trace_case(task, name)
    env = R.make_env(task, tc["body"])
    u = env.unwrapped
    R.reset(env, task, tc["seed"])
    applied = []
    for name, rule in moves:
        dx, dy = (float(v) for v in move_for(u, name, rule))
        u.sim.translate_object(dx, dy, name)
        applied.append((name, dx, dy))
    other = "package" if task == "Catcher-v0" else None
    coms, obs, rewards, other_coms = [R.com(u, 0, "robot")], [], [], []
    if other:
        other_coms.append(R.com(u, 0, other))
    pos0 = {name: np.asarray(u.object_pos_at_time(0, name)) for name, _ in moves}
    term_step = unstable_step = -1
    for t in range(steps):
        before = u.get_time()
        with R.Quiet():
            o, r, term, _, _ = env.step(tc["actions"][t])
        now = u.get_time()
        if now == before and unstable_step < 0:
            unstable_step = t
        rewards.append(float(r))
        obs.append(np.asarray(o, dtype=np.float64))
        coms.append(R.com(u, now, "robot"))
        if other:
            other_coms.append(R.com(u, now, other))
        if term:
            term_step = t
            break
    env.close()
    return {"tc": tc, "applied": applied, "rewards": np.array(rewards), "obs": np.array(obs),
            "com": np.array(coms), "other_com": np.array(other_coms), "pos0": pos0,
            "term_step": term_step, "unstable_step": unstable_step, "steps_run": len(rewards)}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", default=str(DATA / "state_cases.npz"))
    args = ap.parse_args()
    arrays: dict[str, np.ndarray] = {"format_version": np.array(1)}
    meta = []
    for name, task, steps, moves in CASES:
        res = R.isolated(run_case, name, task, steps, moves)
        tc = res["tc"]
        meta.append({"name": name, "task": task, "steps": steps, "source": tc["file"],
                     "seed": tc["seed"], "moves": [list(m) for m in res["applied"]],
                     "rules": [[n, list(r)] for n, r in moves],
                     "steps_run": res["steps_run"], "term_step": res["term_step"],
                     "unstable_step": res["unstable_step"]})
        pre = name + "/"
        arrays[pre + "body"] = tc["body"].astype(np.int64)
        arrays[pre + "actions"] = tc["actions"][:res["steps_run"]]
        arrays[pre + "rewards"] = res["rewards"]
        arrays[pre + "obs"] = res["obs"]
        arrays[pre + "com"] = res["com"]
        for obj, p in res["pos0"].items():
            arrays[pre + "pos0_" + obj] = p
        if len(res["other_com"]):
            arrays[pre + "other_com"] = res["other_com"]
        print(f"{name:28s} {task:16s} steps_run {res['steps_run']:3d} term {res['term_step']:3d} "
              f"unstable {res['unstable_step']:3d} return {res['rewards'].sum():+.6f} "
              f"com0 {res['com'][0].round(4)} com_end {res['com'][-1].round(4)}")
    arrays["cases"] = np.array(json.dumps(meta))
    print("sha256", R.save_npz(args.out, arrays))


if __name__ == "__main__":
    main()
