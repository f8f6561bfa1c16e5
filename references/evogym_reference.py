"""Record reference data for all 32 Evolution Gym 2.0.0 tasks from evogym itself.

Runs ONLY under the evogym virtual environment built by shared/tools/setup_evogym.sh (Python 3.10,
evogym 2.0.0, numpy 1.26, gymnasium 1.x). sgr never imports this file and never depends on evogym;
it only reads what this script writes (tests/data/evogym32/, described in its README.md).

    /root/.cache/evogym-venv/bin/python references/evogym_reference.py                 # all 32 tasks
    /root/.cache/evogym-venv/bin/python references/evogym_reference.py --tasks Walker-v0 Catcher-v0

Per task it writes:
  returns_<task>.npz   24 random robots (evogym's sample_robot, 5x5) with random open-loop sinusoidal
                       programs, 100 steps: per-step rewards, termination step, return, reset
                       observation, robot COM every step, and evogym's own reruns under +-1e-9 and
                       +-1e-6 action perturbations (the chaos floor).
  trace_<task>_<k>_<name>.npz   3 cases, 50 steps: robot COM, orientation, observation and rewards
                       every step; every point of every object and the robot's point velocities
                       at steps 0..5, 10, 20, 30, 40 and 50 (`state_steps`).
and index.json (task facts + per-task summaries + sha256 of every file) and timing.json (the only
non-deterministic output). Every .npz is byte-reproducible: fixed zip timestamps, fixed key order.

Seeds (see README.md): task k (position in ALL_TASKS, whatever --tasks selects) uses case seeds
s = 3_200_000 + 1000*k + j, j = 0, 1, ..., skipping a seed whose body (cropped to its bounding box)
already occurs among that task's cases. Body: random.seed(s); np.random.seed(s);
sample_robot((5, 5))[0]. Program: rng = np.random.default_rng(s); T = rng.integers(10, 61);
A = rng.uniform(0.2, 0.5); phi = rng.uniform(0, 2*pi, n_act); a_j(t) = clip(1.1 + A*sin(2*pi*t/T +
phi_j), 0.6, 1.6). Reset: random.seed(s); np.random.seed(s); env.reset(seed=s) -- evogym ignores the
seed argument; its only task randomness (Catcher-v0, BidirectionalWalker-v0) comes from Python's
global `random`, which random.seed(s) fixes right before the reset.
"""

from __future__ import annotations

import argparse
import json
import os
import pickle
import random
import sys
import time
import warnings

import evogym.envs  # noqa: F401  (registers the 32 tasks)
import gymnasium as gym
import numpy as np
from evogym import sample_robot
from npz_io import save_npz, state_steps  # references/ (this script's folder) is on sys.path

ALL_TASKS = (
    "Walker-v0", "BridgeWalker-v0", "CaveCrawler-v0", "Jumper-v0", "Flipper-v0", "Balancer-v0",
    "Balancer-v1", "UpStepper-v0", "DownStepper-v0", "ObstacleTraverser-v0", "ObstacleTraverser-v1",
    "Hurdler-v0", "GapJumper-v0", "PlatformJumper-v0", "Traverser-v0", "Lifter-v0", "Carrier-v0",
    "Carrier-v1", "Pusher-v0", "Pusher-v1", "BeamToppler-v0", "BeamSlider-v0", "Thrower-v0",
    "Catcher-v0", "AreaMaximizer-v0", "AreaMinimizer-v0", "WingspanMazimizer-v0",
    "HeightMaximizer-v0", "Climber-v0", "Climber-v1", "Climber-v2", "BidirectionalWalker-v0",
)

# world file each task's constructor loads (checked against the objects the env really holds)
WORLD_FILE = {t: f"{t}.json" for t in ALL_TASKS}
WORLD_FILE.update({t: "ShapeChange.json" for t in (
    "AreaMaximizer-v0", "AreaMinimizer-v0", "WingspanMazimizer-v0", "HeightMaximizer-v0")})
WORLD_FILE["Catcher-v0"] = "Walker-v0.json"
# objects the task constructor adds in code (not in the world file), with the file they come from
CODE_OBJECTS = {
    "Traverser-v0": "block_<i>: rigid_<s>x<s>.json (s = 1, 2, 3) placed in code",
    "Catcher-v0": "package: package.json, peg1/peg2: peg.json, placed in code at random offsets",
}
# the non-robot object whose COM (and orientation) the task's reward/observation reads
OTHER_OBJECT = {t: "package" for t in ("Lifter-v0", "Carrier-v0", "Carrier-v1", "Pusher-v0",
                                       "Pusher-v1", "Thrower-v0", "Catcher-v0")}
OTHER_OBJECT.update({"BeamToppler-v0": "beam", "BeamSlider-v0": "beam"})

warnings.filterwarnings("ignore", category=DeprecationWarning)  # gymnasium: "-v0 is out of date"

SEED_BASE = 3_200_000
N_CASES = 24
STEPS = 100
TRACE_STEPS = 50
C = 1.1
PERTURBATIONS = {"p9": 1e-9, "m9": -1e-9, "p6": 1e-6, "m6": -1e-6}
MAX_ACT = 25
WALKER_BODY = np.array([[3, 3, 3, 3, 3], [3, 3, 3, 3, 3], [3, 3, 0, 3, 3], [3, 3, 0, 3, 3],
                        [3, 3, 0, 3, 3]])
FORMAT_VERSION = 2  # 2: trace points at state_steps only, no per-step rewards of the reruns (size)
TRACE_STRIDE = 10  # trace files keep pos and robot_vel at steps 0..5, every 10th and the last


# ---------------------------------------------------------------------------------------------- io


class Quiet:
    """Silence evogym's prints ("SIMULATION UNSTABLE...", the version banner) at the fd level."""

    def __enter__(self):
        sys.stdout.flush()
        self.saved = os.dup(1)
        self.null = os.open(os.devnull, os.O_WRONLY)
        os.dup2(self.null, 1)

    def __exit__(self, *exc):
        sys.stdout.flush()
        os.dup2(self.saved, 1)
        os.close(self.saved)
        os.close(self.null)


def isolated(fn, *args, **kwargs):
    """Run fn in a forked child and return its result. evogym 2.0.0 segfaults when a Traverser-v0
    env is constructed in a process where another Traverser-v0 env has already stepped (heap damage
    in the C++ simulator), so every episode gets a process of its own; episodes are thereby also
    independent of each other by construction."""
    r, w = os.pipe()
    pid = os.fork()
    if pid == 0:  # child
        os.close(r)
        try:
            data = pickle.dumps(("ok", fn(*args, **kwargs)))
        except BaseException as exc:  # noqa: BLE001 - reported by the parent
            data = pickle.dumps(("error", repr(exc)))
        with os.fdopen(w, "wb") as f:
            f.write(data)
        os._exit(0)
    os.close(w)
    with os.fdopen(r, "rb") as f:
        data = f.read()
    _, status = os.waitpid(pid, 0)
    if not data:
        raise RuntimeError(f"evogym child died (wait status {status}) in {fn.__name__}{args[:1]}")
    kind, value = pickle.loads(data)
    if kind != "ok":
        raise RuntimeError(f"evogym child failed: {value}")
    return value


# ------------------------------------------------------------------------------------ cases
def crop(body: np.ndarray) -> bytes:
    rows = np.nonzero(body.any(axis=1))[0]
    cols = np.nonzero(body.any(axis=0))[0]
    b = body[rows[0]:rows[-1] + 1, cols[0]:cols[-1] + 1].astype(np.int64)
    return repr(b.shape).encode() + b.tobytes()


def draw_body(seed: int) -> np.ndarray:
    random.seed(seed)
    np.random.seed(seed)
    return np.asarray(sample_robot((5, 5))[0]).astype(np.int64)


def program(seed: int, n_act: int, steps: int) -> tuple[int, float, np.ndarray, np.ndarray]:
    """The random sinusoid of tests/data/returns: (T, A, phases, actions (steps, n_act))."""
    rng = np.random.default_rng(seed)
    T = int(rng.integers(10, 61))
    A = float(rng.uniform(0.2, 0.5))
    phi = rng.uniform(0, 2 * np.pi, size=n_act)
    t = np.arange(steps)[:, None]
    actions = np.clip(C + A * np.sin(2 * np.pi * t / T + phi[None, :]), 0.6, 1.6)
    return T, A, phi, actions


def task_seeds(task: str, n: int) -> list[tuple[int, np.ndarray]]:
    base = SEED_BASE + 1000 * ALL_TASKS.index(task)
    out, seen, j = [], set(), 0
    while len(out) < n:
        s = base + j
        j += 1
        body = draw_body(s)
        key = crop(body)
        if key in seen:
            continue
        seen.add(key)
        out.append((s, body))
    return out


# ----------------------------------------------------------------------------------- running
def make_env(task: str, body: np.ndarray):
    with Quiet():
        env = gym.make(task, body=body.astype(float))
    return env


def drawn_randomness(task: str, u) -> dict:
    if task == "Catcher-v0":
        return {"offsetx": int(u.offsetx), "offsety": int(u.offsety)}
    if task == "BidirectionalWalker-v0":
        return {"goals_x_voxels": [int(g.x_goal) for g in u.goals]}
    return {}


def reset(env, task: str, seed: int):
    random.seed(seed)
    np.random.seed(seed)
    with Quiet():
        obs, _ = env.reset(seed=seed)
    return np.asarray(obs, dtype=np.float64), drawn_randomness(task, env.unwrapped)


def com(u, t: int, name: str) -> np.ndarray:
    return np.mean(u.object_pos_at_time(t, name), axis=1)


def world_layout(u) -> list[dict]:
    """Objects in evogym's global point order (actuated objects first, then by name) with their
    point ranges, checked against the global position array."""
    sim = u.sim
    names = sorted(sim._object_names, key=lambda n: (0 if n == "robot" else 1, n))
    P = u.pos_at_time(0)
    out, first = [], 0
    for name in names:
        p = u.object_pos_at_time(0, name)
        n = p.shape[1]
        assert np.array_equal(P[:, first:first + n], p), f"point order of {name}"
        obj = u.world.objects[name]
        grid = np.asarray(obj.grid)  # bottom row first
        types = {int(k): int(v) for k, v in zip(*np.unique(grid[grid != 0], return_counts=True), strict=True)}
        n_pairs = sum(len(v) for v in obj.neighbors.values()) // 2
        full = int(np.sum((grid[:, 1:] != 0) & (grid[:, :-1] != 0))
                   + np.sum((grid[1:] != 0) & (grid[:-1] != 0)))
        out.append({"name": name, "first_point": first, "n_points": n,
                    "cell": [int(obj.pos.x), int(obj.pos.y)],
                    "size": [int(obj.grid_size.x), int(obj.grid_size.y)],
                    "voxel_types": types, "n_connections": n_pairs, "n_full_connections": full})
        first += n
    assert first == P.shape[1]
    return out


def run(task: str, body: np.ndarray, actions: np.ndarray, seed: int, delta: float = 0.0,
        trace: bool = False) -> dict:
    """One episode in a fresh env: stop after the first terminated step or after len(actions)."""
    env = make_env(task, body)
    u = env.unwrapped
    obs0, drawn = reset(env, task, seed)
    other = OTHER_OBJECT.get(task)
    S = len(actions)
    rewards = np.full(S, np.nan)
    coms = [com(u, 0, "robot")]
    orts = [u.object_orientation_at_time(0, "robot")]
    other_coms = [com(u, 0, other)] if other else []
    other_orts = [u.object_orientation_at_time(0, other)] if other else []
    obs = [obs0]
    pos, vel = [u.pos_at_time(0)], [u.object_vel_at_time(0, "robot")]
    term_step = unstable_step = -1
    for t in range(S):
        t_before = u.get_time()
        with Quiet():
            o, r, term, _, _ = env.step(actions[t] + delta)
        rewards[t] = r
        now = u.get_time()
        if now == t_before and unstable_step < 0:
            unstable_step = t
        coms.append(com(u, now, "robot"))
        orts.append(u.object_orientation_at_time(now, "robot"))
        if other:
            other_coms.append(com(u, now, other))
            other_orts.append(u.object_orientation_at_time(now, other))
        if trace:
            obs.append(np.asarray(o, dtype=np.float64))
            pos.append(u.pos_at_time(now))
            vel.append(u.object_vel_at_time(now, "robot"))
        if term:
            term_step = t
            break
    out = {"obs0": obs0, "drawn": drawn, "rewards": rewards, "term_step": term_step,
           "unstable_step": unstable_step, "steps_run": t + 1, "com": np.array(coms),
           "ort": np.array(orts),
           "n_points": u.object_pos_at_time(0, "robot").shape[1],
           "actuators": np.asarray(u.get_actuator_indices("robot")).astype(np.int64),
           "max_episode_steps": env.spec.max_episode_steps, "entry_point": env.spec.entry_point,
           "obs_space": int(env.observation_space.shape[0]),
           "act_space": int(env.action_space.shape[0]),
           "robot_cell": [int(u.world.objects["robot"].pos.x), int(u.world.objects["robot"].pos.y)]}
    if other:
        out["other_com"] = np.array(other_coms)
        out["other_ort"] = np.array(other_orts)
    if trace:
        out.update(obs=np.array(obs), pos=np.array(pos), vel=np.array(vel), layout=world_layout(u))
    elif delta == 0.0:
        out["layout"] = world_layout(u)
    env.close()
    return out


def pad(rows: list[np.ndarray], width: int, fill=np.nan, dtype=np.float64) -> np.ndarray:
    out = np.full((len(rows), width), fill, dtype=dtype)
    for i, r in enumerate(rows):
        out[i, :len(r)] = r
    return out


def pad_steps(x: np.ndarray, n: int) -> np.ndarray:
    out = np.full((n,) + x.shape[1:], np.nan)
    out[:len(x)] = x
    return out


# -------------------------------------------------------------------------------- per task
def record_returns(task: str, outdir: str, n_cases: int) -> tuple[dict, list]:
    cases = task_seeds(task, n_cases)
    res = {"seed": [], "body": [], "n_act": [], "act_idx": [], "T": [], "A": [], "phases": [],
           "actions": [], "ref": [], **{k: [] for k in PERTURBATIONS}}
    for s, body in cases:
        n_act = int(np.sum((body == 3) | (body == 4)))
        T, A, phi, actions = program(s, n_act, STEPS)
        ref = isolated(run, task, body, actions, s)
        assert ref["act_space"] == n_act and len(ref["actuators"]) == n_act
        assert ref["obs_space"] == len(ref["obs0"]), f"{task}: reset obs length != observation_space"
        res["seed"].append(s)
        res["body"].append(body)
        res["n_act"].append(n_act)
        res["act_idx"].append(ref["actuators"])
        res["T"].append(T)
        res["A"].append(A)
        res["phases"].append(phi)
        res["actions"].append(actions)
        res["ref"].append(ref)
        for k, d in PERTURBATIONS.items():
            res[k].append(isolated(run, task, body, actions, s, delta=d))
        print(f"  {task} seed {s}: return {np.nansum(ref['rewards']):+.6f} term {ref['term_step']}"
              f" | dR(+1e-9) {abs(np.nansum(res['p9'][-1]['rewards']) - np.nansum(ref['rewards'])):.2e}",
              flush=True)
    refs = res["ref"]
    N = len(cases)
    amax = max(res["n_act"])
    dmax = max(len(r["obs0"]) for r in refs)
    actions = np.full((N, STEPS, amax), np.nan)
    for i, a in enumerate(res["actions"]):
        actions[i, :, :a.shape[1]] = a
    arrays = {
        "format_version": np.int64(FORMAT_VERSION),
        "task": np.str_(task),
        "steps": np.int64(STEPS),
        "c": np.float64(C),
        "seed": np.array(res["seed"], dtype=np.int64),
        "body": np.array(res["body"], dtype=np.int64),
        "n_act": np.array(res["n_act"], dtype=np.int64),
        "actuator_indices": pad(res["act_idx"], MAX_ACT, -1, np.int64),
        "T": np.array(res["T"], dtype=np.int64),
        "A": np.array(res["A"]),
        "phases": pad(res["phases"], MAX_ACT),
        "actions": actions,
        "n_points": np.array([r["n_points"] for r in refs], dtype=np.int64),
        "obs_dim": np.array([len(r["obs0"]) for r in refs], dtype=np.int64),
        "obs0": pad([r["obs0"] for r in refs], dmax),
        "rewards": np.array([r["rewards"] for r in refs]),
        "returns": np.array([np.nansum(r["rewards"]) for r in refs]),
        "steps_run": np.array([r["steps_run"] for r in refs], dtype=np.int64),
        "term_step": np.array([r["term_step"] for r in refs], dtype=np.int64),
        "unstable_step": np.array([r["unstable_step"] for r in refs], dtype=np.int64),
        "com": np.array([pad_steps(r["com"], STEPS + 1) for r in refs]),
        "ort": np.array([pad_steps(r["ort"], STEPS + 1) for r in refs]),
    }
    if task in OTHER_OBJECT:
        arrays["other_name"] = np.str_(OTHER_OBJECT[task])
        arrays["other_com"] = np.array([pad_steps(r["other_com"], STEPS + 1) for r in refs])
        arrays["other_ort"] = np.array([pad_steps(r["other_ort"], STEPS + 1) for r in refs])
    if task in ("Catcher-v0", "BidirectionalWalker-v0"):
        arrays["reset_seed"] = arrays["seed"].copy()
    if task == "Catcher-v0":
        arrays["offset_xy"] = np.array([[r["drawn"]["offsetx"], r["drawn"]["offsety"]] for r in refs],
                                       dtype=np.int64)
    if task == "BidirectionalWalker-v0":
        arrays["goals_x_voxels"] = pad([r["drawn"]["goals_x_voxels"] for r in refs],
                                       max(len(r["drawn"]["goals_x_voxels"]) for r in refs), -1, np.int64)
    arrays["perturbations"] = np.array(list(PERTURBATIONS.values()))
    for k in PERTURBATIONS:
        runs = res[k]
        for r, ref in zip(runs, refs, strict=True):
            assert r["drawn"] == ref["drawn"], f"{task}: task randomness differs between reruns"
        arrays[f"returns_{k}"] = np.array([np.nansum(r["rewards"]) for r in runs])
        arrays[f"term_step_{k}"] = np.array([r["term_step"] for r in runs], dtype=np.int64)
        arrays[f"unstable_step_{k}"] = np.array([r["unstable_step"] for r in runs], dtype=np.int64)
        dev = []
        for r, ref in zip(runs, refs, strict=True):
            m = min(len(r["com"]), len(ref["com"]))
            dev.append(np.linalg.norm(r["com"][:m] - ref["com"][:m], axis=1).max())
        arrays[f"max_com_dev_{k}"] = np.array(dev)
    fname = f"returns_{task}.npz"
    sha = save_npz(os.path.join(outdir, fname), arrays)
    return {"file": fname, "sha256": sha, "arrays": arrays, "refs": refs}, cases


def record_traces(task: str, outdir: str, cases: list, returns_arrays: dict) -> list[dict]:
    base = SEED_BASE + 1000 * ALL_TASKS.index(task)
    specs = [("walker", base + 999, WALKER_BODY)]
    specs += [(f"seed{s}", s, body) for s, body in cases[:2]]
    files = []
    for k, (name, s, body) in enumerate(specs):
        n_act = int(np.sum((body == 3) | (body == 4)))
        T, A, phi, actions = program(s, n_act, TRACE_STEPS)
        r = isolated(run, task, body, actions, s, trace=True)
        if k > 0:  # same run as returns case k-1: evogym must repeat itself bit for bit
            i = k - 1
            m = len(r["com"])
            assert np.array_equal(r["com"], returns_arrays["com"][i, :m]), f"{task}: nondeterministic COM"
            assert np.array_equal(r["rewards"][:r["steps_run"]],
                                  returns_arrays["rewards"][i, :r["steps_run"]]), f"{task}: rewards"
        S1 = len(r["pos"])
        keep = state_steps(S1 - 1, TRACE_STRIDE)
        arrays = {
            "format_version": np.int64(FORMAT_VERSION),
            "task": np.str_(task),
            "case": np.str_(name),
            "seed": np.int64(s),
            "steps": np.int64(TRACE_STEPS),
            "steps_run": np.int64(r["steps_run"]),
            "body": body.astype(np.int64),
            "robot_cell": np.array(r["robot_cell"], dtype=np.int64),
            "actuator_indices": r["actuators"],
            "T": np.int64(T), "A": np.float64(A), "phases": phi,
            "actions": actions,
            "world_objects": np.str_(json.dumps(r["layout"])),
            "state_steps": keep,
            "pos": r["pos"][keep],
            "robot_vel": r["vel"][keep],
            "com": r["com"],
            "ort": r["ort"],
            "obs": r["obs"],
            "reward": r["rewards"][:S1 - 1],
            "term_step": np.int64(r["term_step"]),
            "unstable_step": np.int64(r["unstable_step"]),
        }
        if task in OTHER_OBJECT:
            arrays["other_name"] = np.str_(OTHER_OBJECT[task])
            arrays["other_com"] = r["other_com"]
            arrays["other_ort"] = r["other_ort"]
        if r["drawn"]:
            arrays["reset_seed"] = np.int64(s)
            arrays["drawn"] = np.str_(json.dumps(r["drawn"]))
        fname = f"trace_{task}_{k}_{name}.npz"
        sha = save_npz(os.path.join(outdir, fname), arrays)
        files.append({"file": fname, "sha256": sha, "case": name, "seed": s, "body": body.tolist(),
                      "steps_run": r["steps_run"], "term_step": r["term_step"],
                      "n_points_total": int(r["pos"].shape[2]), "drawn": r["drawn"]})
    return files


def summarize(task: str, ret: dict, traces: list[dict]) -> dict:
    a = ret["arrays"]
    ref0 = ret["refs"][0]
    extra = sorted({int(d - 2 * n) for d, n in zip(a["obs_dim"], a["n_points"], strict=True)})
    assert len(extra) == 1, f"{task}: obs length is not const + 2n: {extra}"
    chaos = {}
    for k, d in PERTURBATIONS.items():
        diff = np.abs(a[f"returns_{k}"] - a["returns"])
        chaos[k] = {"perturbation": d, "median_abs_return_diff": float(np.median(diff)),
                    "max_abs_return_diff": float(diff.max()),
                    "n_return_diff_gt_1e-6": int(np.sum(diff > 1e-6)),
                    "n_term_step_differs": int(np.sum(a[f"term_step_{k}"] != a["term_step"])),
                    "median_max_com_dev": float(np.median(a[f"max_com_dev_{k}"]))}
    layout = [o for o in ref0["layout"] if o["name"] != "robot"]
    facts = {
        "entry_point": ref0["entry_point"],
        "max_episode_steps": ref0["max_episode_steps"],
        "world_file": WORLD_FILE[task],
        "robot_cell": ref0["robot_cell"],
        "obs_dim": f"{extra[0]} + 2n" if extra[0] else "2n",
        "obs_extra": extra[0],
        "action_dim": "number of actuator voxels",
        "objects": layout,
        "objects_added_in_code": CODE_OBJECTS.get(task),
        "other_object": OTHER_OBJECT.get(task),
    }
    if task == "Catcher-v0":
        facts["randomness"] = ("gym.make and every reset() draw offsetx = random.randint(-6, 4) then "
                               "offsety = random.randint(0, 5) from Python's global random module and "
                               "rebuild the world: package at cell (21+offsetx, 41+offsety), peg1 at "
                               "(17+offsetx, 39+offsety), peg2 at (19+offsetx, 25+offsety); the "
                               "robot at (22, 1). reset(seed=...) does not seed anything.")
    if task == "BidirectionalWalker-v0":
        facts["randomness"] = ("gym.make and every reset() draw goals from Python's global random "
                               "module: pos = 35, dist = 0; while dist < 100: g = random.randrange(20, 50); "
                               "dist += |pos - g|; pos = g; append g (voxel x). reset(seed=...) does not "
                               "seed anything.")
    summary = {
        "n_cases": int(len(a["seed"])),
        "seeds": [int(a["seed"].min()), int(a["seed"].max())],
        "n_points": [int(a["n_points"].min()), int(a["n_points"].max())],
        "n_act": [int(a["n_act"].min()), int(a["n_act"].max())],
        "returns": {"median": float(np.median(a["returns"])), "min": float(a["returns"].min()),
                    "max": float(a["returns"].max())},
        "n_terminated": int(np.sum(a["term_step"] >= 0)),
        "term_steps": [int(x) for x in a["term_step"] if x >= 0],
        "n_unstable": int(np.sum(a["unstable_step"] >= 0)),
        "chaos": chaos,
    }
    return {"facts": facts, "returns_file": {"file": ret["file"], "sha256": ret["sha256"]},
            "summary": summary, "traces": traces}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--tasks", nargs="+", default=list(ALL_TASKS), choices=ALL_TASKS)
    ap.add_argument("--out", default="tests/data/evogym32")
    ap.add_argument("--cases", type=int, default=N_CASES, help="random robots per task (the data set: 24)")
    args = ap.parse_args()
    os.makedirs(args.out, exist_ok=True)
    index_path = os.path.join(args.out, "index.json")
    timing_path = os.path.join(args.out, "timing.json")
    index = json.load(open(index_path)) if os.path.exists(index_path) else {}
    timing = json.load(open(timing_path)) if os.path.exists(timing_path) else {}
    index.update({
        "format_version": FORMAT_VERSION,
        "generator": "references/evogym_reference.py",
        "evogym_version": "2.0.0",
        "python": sys.version.split()[0], "numpy": np.__version__, "gymnasium": gym.__version__,
        "n_cases": args.cases, "steps": STEPS, "trace_steps": TRACE_STEPS,
        "seed_rule": (f"task k (position in the 32-task list) uses seeds {SEED_BASE} + 1000*k + j, "
                      "j = 0, 1, ..., skipping seeds whose body (cropped to its bounding box) already "
                      "occurs in that task; trace case 'walker' uses seed 3_200_000 + 1000*k + 999"),
        "body_rule": "random.seed(s); np.random.seed(s); sample_robot((5, 5))[0]",
        "program": "rng = np.random.default_rng(s); T = rng.integers(10, 61); A = rng.uniform(0.2, 0.5); "
                   "phi = rng.uniform(0, 2*pi, n_act); "
                   "a_j(t) = clip(1.1 + A*sin(2*pi*t/T + phi_j), 0.6, 1.6)",
        "reset_rule": "fresh env per run: gym.make(task, body=body); random.seed(s); np.random.seed(s); "
                      "env.reset(seed=s)",
        "perturbations": PERTURBATIONS,
        "all_tasks": list(ALL_TASKS),
    })
    index.setdefault("tasks", {})
    t_all = time.perf_counter()
    for task in args.tasks:
        t0 = time.perf_counter()
        print(f"{task}", flush=True)
        ret, cases = record_returns(task, args.out, args.cases)
        traces = record_traces(task, args.out, cases, ret["arrays"])
        index["tasks"][task] = summarize(task, ret, traces)
        timing[task] = round(time.perf_counter() - t0, 1)
        print(f"{task}: {timing[task]} s", flush=True)
        index["tasks"] = {t: index["tasks"][t] for t in ALL_TASKS if t in index["tasks"]}
        with open(index_path, "w") as f:
            json.dump(index, f, indent=1)
            f.write("\n")
        with open(timing_path, "w") as f:
            json.dump({t: timing[t] for t in ALL_TASKS if t in timing}, f, indent=1)
            f.write("\n")
    print(f"total {time.perf_counter() - t_all:.0f} s", flush=True)


if __name__ == "__main__":
    main()
