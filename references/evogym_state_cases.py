"""Record evogym 2.0.0 episodes that start from a moved state, for the task branches the random
robots of `evogym_reference.py` never reach: a robot's COM just past / just short of a goal
(BridgeWalker-v0, CaveCrawler-v0, Climber-v0, Climber-v1, Traverser-v0), a robot standing on
Traverser-v0's loose blocks (floor sight over moving objects), Catcher-v0's package falling through
y = 0.5, a robot left of the start of Walker-v0's ground, on evogym's built-in ground plane (y < 0);
and (issue 28) every other reward and termination branch of every task on both sides of its line:
the goals of 8 more tasks, falls through a height line (Lifter-v0's robot below 0.3, GapJumper-v0
and PlatformJumper-v0 below 0.4, Carrier-v1's package below 0.4), x lines (Flipper-v0 0.1,
Thrower-v0 0, the beams' 0.2, Carrier-v1's package at 2.0), both orientation limits of the five
tasks that end when the robot falls over, BidirectionalWalker-v0's 0.2 to a goal and its "all goals
done" (the robot moved to each goal in turn, before every step), and Pusher's package put into the
ground plane (which throws it above y = 0 within one step).

Run under the evogym venv (sgr never imports evogym):

    /root/.cache/evogym-venv/bin/python references/evogym_state_cases.py

Each case: the body, seed and actions of trace case 1 of the task (tests/data/evogym32), or another
body (BODIES) with the program of that seed, a fresh env, `reset` as in `evogym_reference.py`, then
evogym's own `Sim.translate_object(dx, dy, name)` (the C++ simulator adds (dx, dy) to every point
of the object and re-saves the snapshot of the current time, here time 0) for each listed move,
then `env.step(actions[t])` until termination or the case's step count. A case in REPEATED makes
its moves again before every later step t, from the positions at that time (evogym then re-saves
the snapshot of time t, not that of time 0), and follows every move, the first included, with
evogym's `Sim.revert(now)` (reloads that snapshot and sets every point's last position to its
position and its "true" velocity to its velocity): translate_object alone leaves the last
positions behind, so the first substep's true velocity is the jump over dt (~1e4 for a jump of 1),
which kicks a robot standing on the ground through the contact damping and friction.
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
# of the robot's right edge and its lowest point at bottom_y; ("goal_x", d, d_last) moves it in x
# only, its COM x d right of BidirectionalWalker-v0's current goal (d_last for the last goal).
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
    # goal lines of the other goal tasks (issue 28): COM 0.005 past / short, resting on the terrain
    *[(f"{short}_{side}_goal", task, 20, [("robot", ("on_top", g + d, 0.02))])
      for short, task, g in (("walker", "Walker-v0", 9.9), ("carrier", "Carrier-v0", 9.9),
                             ("pusher", "Pusher-v0", 9.9), ("pusher_v1", "Pusher-v1", 6.9),
                             ("upstepper", "UpStepper-v0", 6.9),
                             ("downstepper", "DownStepper-v0", 7.4),
                             ("obstacle_v0", "ObstacleTraverser-v0", 7.9),
                             ("obstacle_v1", "ObstacleTraverser-v1", 5.9))
      for side, d in (("past", 0.005), ("short_of", -0.005))],
    # a flat robot (FLAT_BODY) dropped from a COM 0.005 above a height line onto evogym's ground
    # plane left or right of the terrain: short of the line for 3 steps, then past it
    ("lifter_robot_falls_low", "Lifter-v0", 20, [("robot", ("com_xy", 1.6, 0.305))]),
    ("gap_jumper_falls_off", "GapJumper-v0", 20, [("robot", ("com_xy", -1.0, 0.405))]),
    ("platform_jumper_falls_off", "PlatformJumper-v0", 20, [("robot", ("com_xy", -1.0, 0.405))]),
    # lines in x: COM 0.005 either side, resting on the terrain (the robot or object overhangs the
    # left end of the ground; the beam tasks' robot is moved out of the way first)
    ("flipper_past_left_end", "Flipper-v0", 20, [("robot", ("on_top", 0.095, 0.02))]),
    ("flipper_short_of_left_end", "Flipper-v0", 20, [("robot", ("on_top", 0.105, 0.02))]),
    ("thrower_left_of_zero", "Thrower-v0", 20, [("robot", ("on_top", -0.005, 0.02))]),
    ("thrower_right_of_zero", "Thrower-v0", 20, [("robot", ("on_top", 0.005, 0.02))]),
    ("beam_toppler_beam_past_left", "BeamToppler-v0", 20,
     [("robot", ("on_top", 5.5, 0.02)), ("beam", ("on_top", 0.195, 0.02))]),
    ("beam_toppler_beam_short_of_left", "BeamToppler-v0", 20,
     [("robot", ("on_top", 5.5, 0.02)), ("beam", ("on_top", 0.205, 0.02))]),
    ("beam_slider_beam_past_left", "BeamSlider-v0", 20,
     [("robot", ("on_top", 6.0, 0.02)), ("beam", ("on_top", 0.195, 0.02))]),
    ("beam_slider_beam_short_of_left", "BeamSlider-v0", 20,
     [("robot", ("on_top", 6.0, 0.02)), ("beam", ("on_top", 0.205, 0.02))]),
    # Carrier-v1's package: either side of x = 2.0 on the 0.4-high ground (COM y 0.5: dropped for
    # x <= 2.0, where the line is 0.6, not for x > 2.0, where it is 0.4), and falling through 0.4
    # right of x = 2.0 (ground 0.2 high there)
    ("carrier_v1_package_right_of_2", "Carrier-v1", 20, [("package", ("on_top", 2.005, 0.02))]),
    ("carrier_v1_package_left_of_2", "Carrier-v1", 20, [("package", ("on_top", 1.995, 0.02))]),
    ("carrier_v1_package_falls_low", "Carrier-v1", 20, [("package", ("com_xy", 3.5, 0.405))]),
    # Pusher's "package below y = 0": only reachable inside evogym's ground plane, left of the ground
    ("pusher_package_in_plane", "Pusher-v0", 20, [("package", ("com_xy", -1.0, -0.005))]),
    ("pusher_v1_package_in_plane", "Pusher-v1", 20, [("package", ("com_xy", -1.0, -0.005))]),
    # falling over: a 2-voxel-wide column (COL_L tips left, COL_R right under its program) on the
    # terrain at x, until its orientation passes the task's interval
    # BidirectionalWalker-v0's first goal: COM 0.195 right of it (done: within 0.2) and 0.205
    ("bidirectional_goal_within", "BidirectionalWalker-v0", 20,
     [("robot", ("near_goal", 0.195, 0.02))]),
    ("bidirectional_goal_beyond", "BidirectionalWalker-v0", 20,
     [("robot", ("near_goal", 0.205, 0.02))]),
    # BidirectionalWalker-v0's "all goals done" (+1, end): the robot moved in x before every step
    # (REPEATED) to 0.195 right of the current goal, which that step finishes, and so on to the
    # last goal, which it finishes too (all done) or leaves 0.205 away (never done)
    ("bidirectional_all_goals_done", "BidirectionalWalker-v0", 14,
     [("robot", ("goal_x", 0.195, 0.195))]),
    ("bidirectional_last_goal_beyond", "BidirectionalWalker-v0", 14,
     [("robot", ("goal_x", 0.195, 0.205))]),
    ("hurdler_tips_right", "Hurdler-v0", 100, [("robot", ("on_top", 1.4, 0.01))]),
    ("upstepper_tips_left", "UpStepper-v0", 60, [("robot", ("on_top", 1.95, 0.01))]),
    ("obstacle_v0_tips_left", "ObstacleTraverser-v0", 60, [("robot", ("on_top", 4.11, 0.01))]),
    ("downstepper_tips_left", "DownStepper-v0", 100, [("robot", ("on_top", 0.3, 0.01))]),
    ("downstepper_tips_right", "DownStepper-v0", 100, [("robot", ("on_top", 2.1, 0.01))]),
    ("platform_jumper_tips_right", "PlatformJumper-v0", 60, [("robot", ("on_top", 3.19, 0.01))]),
    ("platform_jumper_tips_left", "PlatformJumper-v0", 100, [("robot", ("on_top", 2.1, 0.01))]),
    ("upstepper_tips_right", "UpStepper-v0", 100, [("robot", ("on_top", 0.3, 0.15))]),
    ("obstacle_v0_tips_right", "ObstacleTraverser-v0", 100, [("robot", ("on_top", 4.0, 0.01))]),
]
BODIES = {"hurdler_tips_right": "COL_R", "upstepper_tips_left": "COL_L",
          "obstacle_v0_tips_left": "COL_L", "downstepper_tips_left": "COL_L",
          "downstepper_tips_right": "COL_R", "platform_jumper_tips_left": "COL_L",
          "upstepper_tips_right": "COL_R", "obstacle_v0_tips_right": "COL_R",
          "platform_jumper_tips_right": "COL_R"}
REPEATED = {"bidirectional_all_goals_done", "bidirectional_last_goal_beyond"}
BODIES.update({c: "FLAT_BODY" for c in ("lifter_robot_falls_low", "gap_jumper_falls_off",
                                        "platform_jumper_falls_off")})


NARROW_BODY = np.array([[0, 0, 0, 0, 0], [0, 0, 0, 0, 0], [0, 3, 3, 3, 0], [0, 4, 2, 4, 0],
                        [0, 3, 3, 3, 0]])


FLAT_BODY = np.array([[0, 0, 0, 0, 0], [0, 0, 0, 0, 0], [0, 0, 0, 0, 0], [3, 3, 4, 3, 3],
                      [3, 3, 3, 3, 3]])  # COM 0.1 above its bottom: at rest below any line >= 0.2


COL_L = np.array([[0, 3, 4, 0, 0]] * 5)  # tips left under its trace seed's program
COL_R = np.array([[0, 4, 3, 0, 0]] * 5)  # tips right


def trace_case(task: str, name: str, steps: int) -> dict:
    """Body, seed and actions of the task's trace case 1 (= returns case 0); another body (BODIES,
    NARROW_BODY for the climbers' free-fall cases) with the program of the same seed, `steps` long
    (at least 50: its first 50 rows do not depend on the length)."""
    (f,) = sorted(DATA.glob(f"trace_{task}_1_*.npz"))
    z = np.load(f, allow_pickle=False)
    out = {"body": z["body"], "seed": int(z["seed"]), "actions": z["actions"], "file": f.name}
    other = {"NARROW_BODY": NARROW_BODY, "FLAT_BODY": FLAT_BODY, "COL_L": COL_L, "COL_R": COL_R}
    which = ("NARROW_BODY" if task.startswith("Climber") and name != "climber_squeezed"
             else BODIES.get(name))
    if which:
        body = other[which]
        n_act = int(np.isin(body, (3, 4)).sum())
        out.update(body=body, actions=R.program(out["seed"], n_act, max(steps, 50))[3], file=which)
    return out


def move_for(u, name: str, rule: tuple) -> tuple[float, float]:
    """(dx, dy) that puts object `name` where `rule` says (see CASES), from its points now."""
    p = np.asarray(u.object_pos_at_time(u.get_time(), name))
    c = p.mean(axis=1)
    if rule[0] == "com_x":
        return rule[1] - c[0], rule[2] - p[1].min()
    if rule[0] == "com_y":
        return 0.0, rule[1] - c[1]
    if rule[0] == "beside_robot":
        r = np.asarray(u.object_pos_at_time(0, "robot"))
        return r[0].max() + rule[1] - p[0].min(), rule[2] - p[1].min()
    if rule[0] == "com_xy":
        return rule[1] - c[0], rule[2] - c[1]
    if rule[0] == "goal_x":  # BidirectionalWalker-v0
        k = u.current_goal
        return u.goals[k].x_goal * 0.1 + rule[2 if k == len(u.goals) - 1 else 1] - c[0], 0.0
    if rule[0] == "near_goal":  # BidirectionalWalker-v0: on_top at d right of the first goal
        rule = ("on_top", u.goals[0].x_goal * 0.1 + rule[1], rule[2])
    if rule[0] == "on_top":  # COM x at x, lowest point gap above the other objects' points below
        dx = rule[1] - c[0]
        lo, hi = p[0].min() + dx, p[0].max() + dx
        top = 0.0  # evogym's ground plane
        for other in u.world.objects:
            if other != name:
                q = np.asarray(u.object_pos_at_time(u.get_time(), other))
                under = (q[0] >= lo - 1e-9) & (q[0] <= hi + 1e-9)
                if under.any():
                    top = max(top, float(q[1][under].max()))
        return dx, top + rule[2] - p[1].min()
    raise ValueError(rule)


def run_case(case: str, task: str, steps: int, moves: list) -> dict:
    """One moved episode in a fresh env (run in a forked child, see R.isolated)."""
    tc = trace_case(task, case, steps)
    env = R.make_env(task, tc["body"])
    u = env.unwrapped
    R.reset(env, task, tc["seed"])
    applied = []
    for name, rule in moves:
        dx, dy = (float(v) for v in move_for(u, name, rule))
        u.sim.translate_object(dx, dy, name)
        applied.append((name, dx, dy))
    if case in REPEATED:
        u.sim.revert(u.get_time())
    other = R.OTHER_OBJECT.get(task)
    coms, obs, rewards, other_coms = [R.com(u, 0, "robot")], [], [], []
    orts = [u.object_orientation_at_time(0, "robot")]
    if other:
        other_coms.append(R.com(u, 0, other))
    pos0 = {name: np.asarray(u.object_pos_at_time(0, name)) for name, _ in moves}
    drawn = R.drawn_randomness(task, u)
    term_step = unstable_step = -1
    step_moves, moved_coms = [], []
    for t in range(steps):
        if t > 0 and case in REPEATED:
            for name, rule in moves:
                dx, dy = (float(v) for v in move_for(u, name, rule))
                u.sim.translate_object(dx, dy, name)
                step_moves.append((t, name, dx, dy))
            u.sim.revert(u.get_time())
            moved_coms.append(R.com(u, u.get_time(), "robot"))
        before = u.get_time()
        with R.Quiet():
            o, r, term, _, _ = env.step(tc["actions"][t])
        now = u.get_time()
        if now == before and unstable_step < 0:
            unstable_step = t
        rewards.append(float(r))
        obs.append(np.asarray(o, dtype=np.float64))
        coms.append(R.com(u, now, "robot"))
        orts.append(u.object_orientation_at_time(now, "robot"))
        if other:
            other_coms.append(R.com(u, now, other))
        if term:
            term_step = t
            break
    env.close()
    return {"tc": tc, "applied": applied, "rewards": np.array(rewards), "obs": np.array(obs),
            "com": np.array(coms), "ort": np.array(orts), "other_com": np.array(other_coms),
            "pos0": pos0, "drawn": drawn, "step_moves": step_moves,
            "moved_com": np.array(moved_coms),
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
        if name in REPEATED:
            meta[-1]["revert_after_moves"] = True
        if res["step_moves"]:
            meta[-1]["step_moves"] = [list(m) for m in res["step_moves"]]
        pre = name + "/"
        arrays[pre + "body"] = tc["body"].astype(np.int64)
        arrays[pre + "actions"] = tc["actions"][:res["steps_run"]]
        arrays[pre + "rewards"] = res["rewards"]
        arrays[pre + "obs"] = res["obs"]
        arrays[pre + "com"] = res["com"]
        arrays[pre + "ort"] = res["ort"]
        if "goals_x_voxels" in res["drawn"]:
            arrays[pre + "goals_x_voxels"] = np.array(res["drawn"]["goals_x_voxels"])
        for obj, p in res["pos0"].items():
            arrays[pre + "pos0_" + obj] = p
        if res["step_moves"]:
            arrays[pre + "moved_com"] = res["moved_com"]
        if len(res["other_com"]):
            arrays[pre + "other_com"] = res["other_com"]
        print(f"{name:28s} {task:16s} steps_run {res['steps_run']:3d} term {res['term_step']:3d} "
              f"unstable {res['unstable_step']:3d} return {res['rewards'].sum():+.6f} "
              f"com0 {res['com'][0].round(4)} com_end {res['com'][-1].round(4)}")
    arrays["cases"] = np.array(json.dumps(meta))
    print("sha256", R.save_npz(args.out, arrays))


if __name__ == "__main__":
    main()
