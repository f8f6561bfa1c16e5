"""Record reference data for `sgr.evogym` (evogym's own API on sgr) from evogym itself.

Runs ONLY under the evogym virtual environment (shared/tools/setup_evogym.sh: Python 3.10,
evogym 2.0.0); sgr never imports this file and never depends on evogym. It writes
tests/data/evogym_api/:

  samples.json     evogym's `sample_robot` after `random.seed(s)`, s = 0..19 (5x5, default pd),
                   one (4, 6) robot with a custom pd after random.seed(3), and 50 `draw`s of
                   [0.2, 0.3, 0.5] after random.seed(5): a seeded script must sample the same robots.
  world_ops.txt    what evogym prints for `world_ops` below (pretty_print, objects, errors) over
                   tutorials/world_data/simple_environment.json (copied here).
  registry.json    evogym's 32 gym ids: max_episode_steps, the env class and its keyword arguments.
  simple_env.npz   evogym's tutorial env (tutorials/envs/simple_env.py over
                   tutorials/world_data/simple_walker_env.json, copied into tests/data/evogym_api/)
                   with the robot of random.seed(11): observation after reset and every step's
                   observation, reward and done over 500 steps of actions
                   a_j(t) = 1.1 + 0.45 sin(2 pi t / 37 + 0.7 j) (some outside [0.6, 1.6]: the env clips).
  multi_world.npz  a world of our own (multi_world.json here, `multi_world_layout`): terrain with a
                   step, a rigid box, a lever held by a fixed voxel, a falling ball, a robot with
                   custom connections and a second robot; 300 EvoSim steps of sinusoids + 0.1
                   sent with set_action unclipped (up to 1.65); every step's pos_at_time,
                   vel_at_time, orientation of each object and unstable flag, and each object's
                   points at step 150.
  second_robot.npz the robot evogym flags unstable at step 37 in Lifter-v0 (evogym32 case 4), as
                   the second robot of a world (`second_robot_world`): unstable flag and time of
                   45 steps, and the points at the end.
  camera.npz       evogym's viewer camera (pos, view_size) tracking the robot and box of the
                   tutorial world with padding (4, 2) and scale (0.3, 0.1), one update a step, 150
                   steps (`camera`).

    /root/.cache/evogym-venv/bin/python references/evogym_api_reference.py --tutorials DIR

where DIR is a copy of evogym's tutorials/ folder (fetch github:EvolutionGym/evogym).
"""

from __future__ import annotations

import argparse
import json
import os
import random
import shutil
import sys
from pathlib import Path

import numpy as np

OUT = Path(__file__).resolve().parents[1] / "tests" / "data" / "evogym_api"


def samples() -> None:
    from evogym import draw, sample_robot
    out = {"seeds": [], "custom": None, "draws": None}
    for seed in range(20):
        random.seed(seed)
        body, conn = sample_robot((5, 5))
        out["seeds"].append({"seed": seed, "body": body.tolist(), "connections": conn.tolist()})
    random.seed(3)
    body, conn = sample_robot((4, 6), np.array([0.1, 0.3, 0.0, 0.5, 0.1]))
    out["custom"] = {"seed": 3, "pd": [0.1, 0.3, 0.0, 0.5, 0.1], "body": body.tolist(),
                     "connections": conn.tolist()}
    random.seed(5)
    out["draws"] = {"seed": 5, "pd": [0.2, 0.3, 0.5], "values": [draw([0.2, 0.3, 0.5]) for _ in range(50)]}
    (OUT / "samples.json").write_text(json.dumps(out) + "\n")


def world_ops(evogym) -> str:
    """EvoWorld edits and their printed result; run by the tests with sgr.evogym as `evogym`."""
    import contextlib
    import io
    buf = io.StringIO()
    with contextlib.redirect_stdout(buf):
        w = evogym.EvoWorld.from_json(str(OUT / "simple_environment.json"))
        random.seed(1)
        body, conn = evogym.sample_robot((5, 5))
        w.add_from_array("robot", body, 3, 1, connections=conn)
        w.translate_object("box", 1, 1)
        w.move_object("box", 12, 6)
        w.add_from_array("extra", np.array([[5, 5], [0, 5]]), 25, 12)
        w.pretty_print(voxels_per_line=13)
        for name, o in sorted(w.objects.items()):
            print(name, o, o.get_pos(), o.get_structure().tolist(),
                  sorted(map(tuple, o.get_connections().T.tolist())))
        print(w.grid.shape, w.grid_size)
        removed = w.remove_object("extra")
        print(removed, w.grid.shape, int(np.sum(w.grid)))
        for bad in (lambda: w.add_from_array("robot", body, 0, 0), lambda: w.move_object("nope", 1, 1),
                    lambda: w.add_from_array("x", body, 3, 1), lambda: w.translate_object("box", -20, 0)):
            try:
                bad()
            except ValueError as e:
                print("ValueError:", e)
    return buf.getvalue()


def registry() -> None:
    """evogym's gym registration of its 32 ids: episode length and the env's keyword arguments."""
    import inspect

    import evogym
    import evogym.envs  # noqa: F401  (registers)
    import gymnasium as gym
    out = {}
    for name in evogym.BASELINE_ENV_NAMES:
        spec = gym.spec(name)
        cls = gym.envs.registration.load_env_creator(spec.entry_point)
        out[name] = {"max_episode_steps": spec.max_episode_steps, "class": cls.__name__,
                     "kwargs": list(inspect.signature(cls.__init__).parameters)[1:]}
    (OUT / "registry.json").write_text(json.dumps(out, indent=1) + "\n")


def actions(t: int, n: int) -> np.ndarray:
    """The open-loop program both sides drive their robots with."""
    return 1.1 + 0.45 * np.sin(2 * np.pi * t / 37 + 0.7 * np.arange(n))


def simple_env(tutorials: Path) -> None:
    from evogym import sample_robot
    shutil.copy(tutorials / "world_data" / "simple_walker_env.json", OUT / "simple_walker_env.json")
    cwd = os.getcwd()
    os.chdir(tutorials)
    sys.path.insert(0, str(tutorials))
    try:
        from envs.simple_env import SimpleWalkerEnvClass
        random.seed(11)
        body, conn = sample_robot((5, 5))
        env = SimpleWalkerEnvClass(body, conn)
        obs0, _ = env.reset()
        n = env.action_space.shape[0]
        obs, rew, done = [], [], []
        for t in range(500):
            o, r, d, _, _ = env.step(actions(t, n))
            obs.append(o)
            rew.append(r)
            done.append(d)
    finally:
        os.chdir(cwd)
    np.savez(OUT / "simple_env.npz", body=body, connections=conn, obs0=obs0, obs=np.array(obs),
             reward=np.array(rew), done=np.array(done))


def multi_world_layout(EvoWorld):
    """Our world with several objects: fixed terrain with a step, a rigid box, a lever (one fixed
    voxel holding four rigid ones), a falling rigid ball, and a robot added from an array with
    connections that leave one pair of adjacent voxels unglued."""
    world = EvoWorld.from_json(str(OUT / "multi_world.json"))
    walker = np.array([[3, 1, 3, 2], [4, 0, 4, 2]])
    conn = np.array([[0, 1, 2, 0, 2, 3], [1, 2, 3, 4, 6, 7]])  # 6-7 glued, 3-7 glued, 2-3 glued
    world.add_from_array("walker", walker, 3, 1, connections=conn)
    hopper = np.array([[2, 4, 2], [2, 3, 2], [1, 0, 1]])
    world.add_from_array("hopper", hopper, 23, 1)
    return world


def drive(sim, t: int) -> None:
    """Both robots' actions at step t (sent unclipped: up to 1.65)."""
    sim.set_action("walker", actions(t, sim.get_dim_action_space("walker")) + 0.1)
    sim.set_action("hopper", actions(t + 5, sim.get_dim_action_space("hopper")) + 0.1)


def second_robot_world(EvoWorld, worlds: Path):
    """Lifter-v0's world with the robot of case 4 of tests/data/evogym32/returns_Lifter-v0.npz
    (evogym flags it unstable at step 37) as a second robot: a one-voxel robot 'aaa' sorts
    first and leads."""
    world = EvoWorld.from_json(str(worlds / "Lifter-v0.json"))
    d = np.load(OUT.parent / "evogym32" / "returns_Lifter-v0.npz", allow_pickle=False)
    world.add_from_array("robot", d["body"][4], 2, 3)
    world.add_from_array("aaa", np.array([[3]]), 0, 8)
    return world, d["actions"][4, :, :d["n_act"][4]]


def second_robot() -> None:
    from evogym import EvoSim, EvoWorld
    world, acts = second_robot_world(EvoWorld, Path(__file__).resolve().parents[1] / "tasks" / "worlds")
    sim = EvoSim(world)
    flags, times = [], []
    for t in range(45):
        sim.set_action("aaa", np.array([1.0]))
        sim.set_action("robot", np.clip(acts[t], 0.6, 1.6))
        flags.append(sim.step())
        times.append(sim.get_time())
    np.savez(OUT / "second_robot.npz", unstable=np.array(flags), time=np.array(times),
             pos=sim.pos_at_time(sim.get_time()))


def camera() -> None:
    """evogym's viewer camera tracking the robot and the box of the basic_api tutorial world as
    render('img') after every step would move it, without drawing (no OpenGL here)."""
    from evogym import EvoSim, EvoViewer, EvoWorld
    world = EvoWorld.from_json(str(OUT / "simple_environment.json"))
    random.seed(2)
    from evogym import sample_robot
    body, conn = sample_robot((5, 5))
    world.add_from_array("robot", body, 3, 1, connections=conn)
    sim = EvoSim(world)
    viewer = EvoViewer(sim)
    viewer.track_objects("robot", "box")
    viewer.set_tracking_settings(padding=(4, 2), scale=(0.3, 0.1))
    out = []
    for t in range(150):
        sim.set_action("robot", actions(t, sim.get_dim_action_space("robot")))
        sim.step()
        # what evogym's render does before drawing: one tracking update per step since the last
        while viewer._last_rendered < sim.get_time():
            viewer._update_tracking()
            viewer._last_rendered += 1
        out.append([*viewer.pos, *viewer.view_size])
    np.savez(OUT / "camera.npz", body=body, connections=conn, track=np.array(out))


def multi_world() -> None:
    from evogym import EvoSim, EvoWorld
    world = multi_world_layout(EvoWorld)
    sim = EvoSim(world)
    sim.reset()
    names = sorted(world.objects)
    pos, vel, ort, unstable, times = [], [], [], [], []
    for t in range(300):
        drive(sim, t)
        unstable.append(sim.step())
        now = sim.get_time()
        times.append(now)
        pos.append(sim.pos_at_time(now))
        vel.append(sim.vel_at_time(now))
        ort.append([sim.object_orientation_at_time(now, n) for n in names])
    obj_pos = {f"objpos_{n}": sim.object_pos_at_time(150, n) for n in names}
    np.savez_compressed(OUT / "multi_world.npz", names=np.array(names), pos=np.array(pos), vel=np.array(vel),
             orientation=np.array(ort), unstable=np.array(unstable), time=np.array(times),
             pos0=sim.pos_at_time(0), act_walker=sim.get_actuator_indices("walker"),
             act_hopper=sim.get_actuator_indices("hopper"), **obj_pos)


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--tutorials", type=Path, required=True, help="copy of evogym's tutorials/")
    p.add_argument("--only", nargs="*",
                   default=["samples", "registry", "simple_env", "multi_world", "second_robot", "camera"])
    args = p.parse_args()
    OUT.mkdir(parents=True, exist_ok=True)
    if "samples" in args.only:
        samples()
        import evogym
        shutil.copy(args.tutorials / "world_data" / "simple_environment.json", OUT)
        (OUT / "world_ops.txt").write_text(world_ops(evogym))
    if "registry" in args.only:
        registry()
    if "simple_env" in args.only:
        simple_env(args.tutorials.resolve())
    if "multi_world" in args.only:
        multi_world()
    if "second_robot" in args.only:
        second_robot()
    if "camera" in args.only:
        camera()


if __name__ == "__main__":
    main()
