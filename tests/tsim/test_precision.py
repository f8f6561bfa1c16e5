"""Single precision: one kernel source in f32 or f64, chosen once per process (`tsim.backend.runtime`).

f32 runs in subprocesses (this process runs in f64, evogym's bits). What is checked: an f32
process steps in float32 from the kernels to the tasks' observations and rewards, follows evogym's
recorded Walker-v0 COMs at the start of an episode (which needs evogym's placement kept: a robot a
few f64 ulps above the ground must not start in contact), and names what is wrong in one line.
"""

import json
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from tsim.backend import runtime
from tsim.rounding import to_real

ROOT = Path(__file__).resolve().parents[2]

F32_PROBE = """
import json, sys
import numpy as np
from tsim.backend import runtime
from tasks.env import BatchEnv
out = {"precision": runtime.precision(), "com_err": {}}
for task in sys.argv[2:]:
    z = np.load(f"{sys.argv[1]}/returns_{task}.npz")
    n_act, B = z["n_act"], len(z["n_act"])
    env = BatchEnv(task, list(z["body"]), episode_steps=100)
    obs = env.observe()
    err = np.zeros(B)  # per robot, the largest over 3 steps
    for t in range(3):
        obs, rew, *_ = env.step([z["actions"][i, t, :n_act[i]] for i in range(B)])
        err = np.maximum(err, np.linalg.norm(env.sim.robot_com() - z["com"][:, t + 1], axis=1))
    out["com_err"][task] = err.tolist()
    out.update({"state": str(env.sim.state.dtype), "obs": str(obs.dtype), "reward": str(rew.dtype)})
print(json.dumps(out))
"""


def _clean_env(**extra: str) -> dict:
    base = {k: v for k, v in os.environ.items() if k not in ("SGR_ARCH", "SGR_PRECISION")}
    return {**base, "SGR_THREADS": "1", **extra}


@pytest.mark.slow
@pytest.mark.subprocess
def test_f32_steps_in_float32_and_follows_evogym_at_the_start(data_dir):
    """In an f32 process the state, observations and rewards are float32, and in the first 3 steps
    evogym's 24 recorded robots follow evogym's COMs to float32's rounding (~3e-8; bound 1e-6):
    - Walker-v0 and HeightMaximizer-v0, every robot. Starting the robots in contact with the
      ground, as plain rounding did (Walker-v0: robot 0.10000000000000003 over ground 0.1) or
      rounding the robot but not the terrain (HeightMaximizer-v0: both at 0.09999999999999998),
      gave 3e-4 after one step.
    - Lifter-v0 and PlatformJumper-v0, every robot too. Their robots stand 1.1e-16 from walls and
      terrain corners, and a 7.7e-12 tilt in the first substep decides a contact: with float32
      numbers for coordinates (6e-8 apart there) 5 and 17 of 24 robots followed; the contacts
      now read the positions' pairs (`narrowphase.corner_less`), test a segment's ends by signs
      (`geometry.intersects_ends`), and the pairs drop what float64 drops (`pairs.renormalize`).
    Measured: at most 2.9e-8 on all four; the bound is 1e-7."""
    tasks = ("Walker-v0", "HeightMaximizer-v0", "Lifter-v0", "PlatformJumper-v0")
    out = subprocess.run([sys.executable, "-c", F32_PROBE, str(data_dir / "evogym32"), *tasks],
                         env=_clean_env(SGR_PRECISION="f32"), capture_output=True, text=True, timeout=300)
    assert out.returncode == 0, out.stderr
    r = json.loads(out.stdout.strip().splitlines()[-1])
    assert r["precision"] == "f32"
    assert (r["state"], r["obs"], r["reward"]) == ("float32", "float32", "float32")
    err = {task: np.array(e) for task, e in r["com_err"].items()}
    for task in tasks:
        assert err[task].max() < 1e-7, (task, err[task])


def test_to_real_keeps_each_coordinate_on_its_f64_side_of_the_grid():
    """evogym's placements lie a few f64 ulps off grid lines; float32 would put them on the line."""
    x = np.array([0.10000000000000003, 0.30000000000000004, 0.2, 0.19999999999999998, 0.123])
    r = to_real(x, np.float32)
    assert r.dtype == np.float32
    grid = np.float32(np.array([0.1, 0.3, 0.2, 0.2]))
    assert r[0] > grid[0] and r[1] == grid[1] and r[2] == grid[2] and r[3] < grid[3]
    assert r[4] == np.float32(0.123)  # away from grid lines: plain rounding
    assert to_real(x, np.float64) is x


def test_unknown_precision_names_the_variable_and_the_choices(monkeypatch):
    monkeypatch.setenv("SGR_PRECISION", "f16")
    with pytest.raises(ValueError, match=r"^SGR_PRECISION=f16: unknown precision; use one of f64, f32$"):
        runtime.requested_precision()
    with pytest.raises(ValueError, match="unknown precision 'half'"):
        runtime.requested_precision("half")


def test_precision_cannot_switch_once_taichi_runs(monkeypatch):
    monkeypatch.delenv("SGR_PRECISION", raising=False)
    runtime.init()  # this test process runs in f64
    assert runtime.precision() == "f64"
    with pytest.raises(ValueError, match="already runs in f64; cannot switch to f32"):
        runtime.use_precision("f32")
    with pytest.raises(ValueError, match="already runs in f64; cannot switch to f32"):
        runtime.init(precision="f32")
    assert runtime.init() == runtime.requested_arch()  # None keeps the running precision


def test_metal_in_f64_is_refused_in_one_line():
    """Metal has no 64-bit floats: the refusal says so and what to use (checked once Taichi found
    the arch usable, so where there is no Metal the missing device is what is reported)."""
    with pytest.raises(ValueError) as exc:
        runtime.check_real_type("metal", "f64", arch_from_env=True)
    assert str(exc.value) == ("SGR_ARCH=metal with precision f64: metal has no 64-bit floats; use "
                              "SGR_PRECISION=f32 (or SGR_ARCH=cpu for f64)")
    runtime.check_real_type("metal", "f32")
    runtime.check_real_type("vulkan", "f64")  # whether the device has them is Taichi's to say


def test_cli_choices_are_the_runtime_precisions():
    from tasks.cli import PRECISIONS

    assert PRECISIONS == runtime.PRECISIONS


FALL = """
import json, sys
import numpy as np
from tsim.body import build_body
from tsim.sim import BatchSim
from tsim.world import world_from_matrix


def fall():
    # a 3x3 robot acting while it falls freely at x, y ~ 20 (float32's ulp there: 1.9e-6)
    m = np.zeros((260, 260), dtype=int)
    m[-1, 0] = 5
    body = build_body(np.array([[3, 3, 3], [2, 4, 2], [3, 1, 3]]))
    sim = BatchSim(world_from_matrix(m), [body], (200, 200))
    n = body.n_points
    def position():
        return sim.states64()[0, :n, 0:2]  # f32: each position as its pair hi + lo

    start = position()
    act = np.array([1.5, 0.75, 1.25, 1.0, 1.375, 1.125])  # exact in float32
    for t in range(20):
        sim.set_actions([act if t % 2 else 2.25 - act])
        sim.step()
    end = position()
    sim.state[0, 0, 0] += 0.5  # moved from Python: its low part no longer belongs to it
    moved = [float(sim.states64()[0, 0, 0]), float(sim.state[0, 0, 0])]
    return str(sim.state.dtype), start, end, moved


if __name__ == "__main__":
    dtype, start, pos, moved = fall()
    print(json.dumps({"dtype": dtype, "start": start.tolist(), "pos": pos.tolist(), "moved": moved}))
"""


@pytest.mark.slow
@pytest.mark.subprocess
def test_f32_pairs_keep_the_increments_a_float32_coordinate_loses():
    """Far from the origin a float32 coordinate cannot hold a substep's increment (v dt ~1e-6 to
    1e-4 against an ulp of 1.9e-6 at 20) and its springs see lengths rounded at that ulp. f32 keeps
    positions and velocities as pairs hi + lo (tsim/kernels/pairs.py), and its springs start as
    strained as evogym's float64 placement makes them (`BatchSim._length_rounding`): 20 steps of a
    robot acting while falling at x, y ~ 20 move it within 5e-8 of how f64 moves it from evogym's
    own placement (measured 2.0e-8 from the placement's pairs; 3.1e-8 from float32 numbers, 7.7e-7
    when the springs felt the float32 placement's rounding, 1.8e-5 with plain float32
    coordinates)."""
    out = subprocess.run([sys.executable, "-c", FALL], env=_clean_env(SGR_PRECISION="f32"),
                         capture_output=True, text=True, timeout=300)
    assert out.returncode == 0, out.stderr
    r = json.loads(out.stdout.strip().splitlines()[-1])
    assert r["dtype"] == "float32"
    space: dict = {}
    exec(FALL.replace('if __name__ == "__main__":', "if False:"), space)
    dtype, start64, pos64, moved64 = space["fall"]()
    start = np.array(r["start"])
    # the placement's pairs hold evogym's float64 placement (a float32 number alone: 1.9e-6 off)
    assert dtype == "float64" and np.abs(start - start64).max() < 1e-13
    assert np.abs(pos64 - start64).max() > 0.1  # it fell and moved
    err = np.abs((np.array(r["pos"]) - start) - (pos64 - start64)).max()
    assert err < 5e-8, err
    # `states64` drops a low part whose position was changed from Python (the pair no longer holds)
    assert r["moved"][0] == r["moved"][1] and moved64[0] == moved64[1]


CLIMB = """
import json, sys
import numpy as np
from tasks.env import BatchEnv
out = {}
for task, robots in (("Climber-v1", [0, 2, 3, 4]), ("Climber-v2", [0, 1, 2, 3])):
    z = np.load(f"{sys.argv[1]}/returns_{task}.npz")
    env = BatchEnv(task, [z["body"][i] for i in robots], episode_steps=2, passive_ok=True)
    env.step([z["actions"][i, 0, :z["n_act"][i]] for i in robots])
    out[task] = np.linalg.norm(env.sim.robot_com() - z["com"][robots, 1], axis=1).tolist()
print(json.dumps(out))
"""


@pytest.mark.slow
@pytest.mark.subprocess
def test_f32_bodies_flush_against_walls_start_as_evogyms(data_dir):
    """Climber-v1's robot rests 3.4e-16 above its pipe's floor and Climber-v2's 3.4e-16 above the
    terrain, flush between walls: plain float32 (with each coordinate on its float64 side of the
    grid lines) rounds both to one number, the robot starts on the floor's edge, inside it, and
    is pushed up: 1e-3 off evogym's COM after one step. As float32 pairs that keep float64's order
    (`tsim.rounding`), one step follows evogym's recorded COM to float32's rounding (measured
    <= 2e-8)."""
    out = subprocess.run([sys.executable, "-c", CLIMB, str(data_dir / "evogym32")],
                         env=_clean_env(SGR_PRECISION="f32"), capture_output=True, text=True,
                         timeout=300)
    assert out.returncode == 0, out.stderr
    r = json.loads(out.stdout.strip().splitlines()[-1])
    for task, err in r.items():
        assert max(err) < 1e-6, (task, err)


UNITS = """
import json
from fractions import Fraction
import numpy as np
from tsim.backend import runtime
runtime.init()
ti = runtime.ti
from tsim.kernels.geometry import intersects, intersects_ends
from tsim.kernels.pairs import renormalize


@ti.kernel
def renorm(h: ti.types.ndarray(), l: ti.types.ndarray()):
    for i in range(h.shape[0]):
        renormalize(h, l, i, None)


@ti.kernel
def segments(p: ti.types.ndarray(), out: ti.types.ndarray()):
    for i in range(p.shape[0]):
        a1 = ti.Vector([p[i, 0], p[i, 1]])
        b1 = ti.Vector([p[i, 2], p[i, 3]])
        a2 = ti.Vector([p[i, 4], p[i, 5]])
        b2 = ti.Vector([p[i, 6], p[i, 7]])
        out[i, 0] = 1 if intersects(b1 - a1, b2 - a2, a2 - a1) else 0
        out[i, 1] = 1 if intersects_ends(b1 - a1, b2 - a2, a2 - a1, a2 - b1, b2 - a1) else 0


rng = np.random.default_rng(7)
n = 20000
a = (rng.uniform(0.05, 20, n) * rng.choice([-1, 1], n)).astype(np.float32)
b = (rng.uniform(-0.5, 0.5, n) * np.spacing(np.abs(a)).astype(np.float64)
     * 2.0 ** -rng.integers(0, 32, n)).astype(np.float32)
# powers of two (float64's spacing halves below them) and grid values, increments of either sign
a = np.concatenate([a, np.array([0.5, 1, 2, -2, 4, 0.5, 1, -0.5, 0.25], dtype=np.float32)])
b = np.concatenate([b, np.array([-3 * 2.0**-56, -2.0**-53, 2.0**-52, 2.0**-52, -2.0**-51, 3e-21,
                                 2.0**-29 + 2.0**-52, 1e-20, -1e-22], dtype=np.float32)])
h, l = a.copy(), b.copy()
renorm(h, l)
wrong = sum(Fraction(H) + Fraction(L) != Fraction(float(Fraction(x) + Fraction(y)))
            for x, y, H, L in zip(a.tolist(), b.tolist(), h.tolist(), l.tolist()))
P = rng.integers(-4, 5, (20000, 8)).astype(np.float32) * 0.5  # exact arithmetic throughout
# a side from (0.6 + 1.4e-6, 0.2) to (0.6, 0.1 - 5.5e-7) against a floor's edge from (0.5, 0.1) to
# (0.6 + 1e-15, 0.1), relative to the side's bottom end: they cross 7.7e-12 beyond the edge's end
near = np.array([[1.4e-6, 0.1 + 5.5e-7, 0, 0, -0.1, 5.5e-7, 1e-15, 5.5e-7]], dtype=np.float32)
out = np.zeros((len(P) + 1, 2), dtype=np.int32)
segments(np.concatenate([P, near]), out)
print(json.dumps({"pairs": len(a), "wrong": int(wrong), "agree": int((out[:-1, 0] == out[:-1, 1]).sum()),
                  "hits": int(out[:-1, 0].sum()), "near": out[-1].tolist(), "near_input": near[0].tolist()}))
"""


def test_f32_pairs_sum_as_float64_does_and_segment_ends_resolve_what_quotients_cannot(tmp_path):
    """Two f32 building blocks against exact oracles, in an f32 process:
    - `pairs.renormalize`: a pair hi + lo plus an increment is float64's sum of them (Python's
      Fraction rounded once to float64), on 20,009 cases: increments down to 2^-32 of float32's
      spacing, and powers of two, where float64's spacing halves below (measured: 0 wrong; 16,842
      without rounding the rest to float64's grid, 582 with the first way of rounding it).
    - `geometry.intersects_ends` gives evogym's segment test (`intersects`) on 20,000 segment pairs
      of exact coordinates, and where a crossing lies 7.7e-12 beyond a segment's end (Lifter-v0's
      wall) says "no" as float64 does, where float32's quotient rounds s = 1 + 7.7e-11 to 1."""
    script = tmp_path / "units.py"  # a file: Taichi reads its kernels' source
    script.write_text(UNITS)
    out = subprocess.run([sys.executable, str(script)], env=_clean_env(SGR_PRECISION="f32"),
                         capture_output=True, text=True, timeout=300, cwd=ROOT)
    assert out.returncode == 0, out.stderr
    r = json.loads(out.stdout.strip().splitlines()[-1])
    assert r["wrong"] == 0, r
    assert r["agree"] == 20000 and r["hits"] > 3000, r  # both outcomes occur
    a1x, a1y, b1x, b1y, a2x, a2y, b2x, b2y = np.array(r["near_input"], dtype=np.float64)
    d1, d2, a21 = (b1x - a1x, b1y - a1y), (b2x - a2x, b2y - a2y), (a2x - a1x, a2y - a1y)
    det = -d1[0] * d2[1] + d2[0] * d1[1]
    s = (-d1[1] * a21[0] + d1[0] * a21[1]) / det  # float64 on the same float32 inputs
    assert s > 1.0
    assert r["near"] == [1, 0]  # the quotient in float32 says "crosses"; the ends, as float64, do not


RANDOM = """
import json, sys
import numpy as np
from tasks.env import BatchEnv
from tsim.sampling import sample_robot


def positions(task):
    # two random 5x5 robots (seed 0), 2 steps of actions 0.7 then 1.3; f32: each pair hi + lo
    rng = np.random.default_rng(0)
    env = BatchEnv(task, [sample_robot((5, 5), rng) for _ in range(2)], episode_steps=50)
    env.reset()
    for t in range(2):
        env.step(np.full((2, env.sim.max_actuators), 1.3 if t % 2 else 0.7))
    return env.sim.states64()[:, :, 0:2]


if __name__ == "__main__":
    print(json.dumps({t: positions(t).tolist() for t in sys.argv[1:]}))
"""
# random robots that f32 moved 1e-3 to 6e-3 away from f64 in 2 steps, before its pairs held
# the placement and dropped what float64 drops
AGAINST_WALLS = ("Climber-v0", "Climber-v1", "Climber-v2", "GapJumper-v0", "PlatformJumper-v0",
                 "Pusher-v0", "Pusher-v1")


def test_f32_follows_f64_where_random_robots_touch_walls_and_objects():
    """Two random 5x5 robots per task (the Vulkan set's), placed flush against walls, terrain and
    objects: f32 follows f64 (evogym's bits) within float32's rounding after 2 steps (measured
    <= 4.8e-9; bound 2e-8). Before: 1e-3 to 6e-3 on these 7 tasks, from two causes. A coordinate
    1e-16 from a wall, which float32 numbers cannot hold (now pairs, `tsim.rounding`). A point at
    x = 0.5 that float64 holds still to the bit, since its increments lie below half of float64's
    spacing there, while the pair kept 3e-21 of them and put the point 3e-21 off a terrain
    voxel's side, out of a contact evogym makes (now the pairs' rests are rounded to float64's
    spacing, `pairs.renormalize`). Carrier-v0 and Traverser-v0 still part after 2 steps
    (docs/VALIDATION.md): a package resting exactly on a robot, ties that float32 pairs (48 bits
    to float64's 53) cannot always keep."""
    out = subprocess.run([sys.executable, "-c", RANDOM, *AGAINST_WALLS],
                         env=_clean_env(SGR_PRECISION="f32"), capture_output=True, text=True,
                         timeout=300)
    assert out.returncode == 0, out.stderr
    r = json.loads(out.stdout.strip().splitlines()[-1])
    space: dict = {}
    exec(RANDOM.replace('if __name__ == "__main__":', "if False:"), space)
    for task in AGAINST_WALLS:
        err = float(np.abs(np.array(r[task]) - space["positions"](task)).max())
        assert err < 2e-8, (task, err)


REWRITE = """
import json
import numpy as np
from tasks.specs import task_world
from tsim.sampling import sample_robot
from tsim.sim import BatchSim

rng = np.random.default_rng(5)
bodies = [sample_robot((5, 5), rng) for _ in range(3)]
acts = [np.full((3, 25), 0.6 + 0.1 * (t % 10)) for t in range(30)]


def run(sim, steps):
    for t in steps:
        sim.set_actions([a[:b] for a, b in zip(acts[t], sim.n_actuators, strict=True)])
        sim.step()


a = BatchSim(task_world("Walker-v0"), bodies, (1, 1))
run(a, range(10))
saved = a.state[:, :, 0:8].copy()  # what evogym's revert restores: positions, velocities
run(a, range(10, 20))
a.state[:, :, 0:8] = saved
b = BatchSim(task_world("Walker-v0"), bodies, (1, 1))
b.state[:] = 0.0
b.state[:, :, 0:8] = saved  # the same state with no low parts
run(a, range(20, 30))
run(b, range(20, 30))
print(json.dumps({"cols": a.state.shape[2], "same": a.state.tobytes() == b.state.tobytes(),
                  "moved": float(np.abs(a.state[:, :, 0:2] - saved[:, :, 0:2]).max())}))
"""


@pytest.mark.slow
@pytest.mark.subprocess
def test_f32_state_written_from_outside_drops_stale_low_parts():
    """f32's low parts (state columns 8:14) hold only for the positions they were stored with: a
    state whose positions are rewritten from outside (a reset, evogym's `revert`) steps exactly as
    the same state with no low parts at all, not with the low parts of the positions it replaced."""
    out = subprocess.run([sys.executable, "-c", REWRITE], env=_clean_env(SGR_PRECISION="f32"),
                         capture_output=True, text=True, timeout=300)
    assert out.returncode == 0, out.stderr
    r = json.loads(out.stdout.strip().splitlines()[-1])
    assert r["cols"] == 14 and r["moved"] > 1e-3
    assert r["same"]
