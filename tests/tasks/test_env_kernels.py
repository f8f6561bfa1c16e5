"""`BatchEnv`'s kernel path (`tasks/kernels.py`, fused=True) against its numpy path (fused=False,
the oracle that the evogym validation tests check): the same observations, rewards, terminations
and truncations, bit for bit, on every task, with random bodies of mixed sizes, random actions,
resets of some worlds, and the state written from outside between steps (which the kernel path
must notice: it reuses its last measurement only while the state is the one it measured)."""

import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from tasks.env import BatchEnv
from tasks.specs import BUILTIN
from tsim.sampling import sample_robots

ROOT = Path(__file__).resolve().parents[2]
SHAPES = ((5, 5), (5, 5), (3, 4), (4, 2), (2, 5), (5, 3))


def bodies(seed: int) -> list[np.ndarray]:
    """Random bodies of evogym's distribution in several shapes (one per entry of SHAPES)."""
    rng = np.random.default_rng(seed)
    return [sample_robots(1, shape, rng)[0] for shape in SHAPES]


def same_bits(a: np.ndarray, b: np.ndarray) -> bool:
    """Equal arrays to the bit (a -0.0 is not a 0.0), of the same dtype and shape."""
    return a.dtype == b.dtype and a.shape == b.shape and a.tobytes() == b.tobytes()


def run_both(task: str, steps: int, seed: int = 0) -> int:
    """Step a kernel-path and a numpy-path env of `task` side by side; assert every step's outputs
    equal to the bit; the number of episode ends seen."""
    envs = [BatchEnv(task, bodies(seed), episode_steps=40, fused=f, seeds=seed) for f in (True, False)]
    B = envs[0].n_worlds
    assert envs[0].fused and not envs[1].fused
    assert same_bits(envs[0].observe(), envs[1].observe())
    rng = np.random.default_rng(seed + 1)
    ends = 0
    for t in range(steps):
        # moves from outside between steps: far right (goals), up (tops of pipes), down (falls)
        for w, col, d, at in ((0, 0, 12.0, 11), (1, 1, 9.0, 23), (2, 1, -0.6, 31), (3, 0, -0.05, 5)):
            if t % 40 == at:
                for e in envs:
                    e.sim.state[w, :e.n_points[w], col] += d
        a = rng.uniform(0.4, 1.8, (B, envs[0].sim.max_actuators))
        out = [e.step(a) for e in envs]
        for k, what in enumerate(("obs", "reward", "terminated", "truncated")):
            assert same_bits(out[0][k], out[1][k]), f"{task} step {t}: {what} differs"
        assert same_bits(out[0][4]["unstable"], out[1][4]["unstable"])
        done = out[0][2] | out[0][3]
        if t % 17 == 16:  # a reset of some worlds that are still running
            done = done | (rng.random(B) < 0.3)
        if done.any():
            ends += int(done.sum())
            obs = [e.reset(done) for e in envs]
            assert same_bits(obs[0], obs[1]), f"{task} reset after step {t}"
        for w in range(B):
            assert same_bits(envs[0].robot_obs(w), envs[1].robot_obs(w))
    return ends


@pytest.mark.slow
@pytest.mark.parametrize("task", sorted(BUILTIN))
def test_kernel_path_equals_numpy_path(task):
    """Every task, 120 steps of 6 robots (5x5 and smaller): kernels and numpy agree to the bit,
    through terminations, truncations, partial resets and outside state edits."""
    assert run_both(task, 120) > 0


@pytest.mark.parametrize("task", ["Walker-v0", "Carrier-v0", "Flipper-v0", "BidirectionalWalker-v0"])
def test_kernel_path_equals_numpy_path_fast(task):
    """A short run of tasks covering each layout: points only after the velocity, a free object's
    blocks, orientation with points read by the reward, a block after the points."""
    assert run_both(task, 45) > 0


def test_outside_state_write_is_measured_anew():
    """A write to `sim.state` between steps moves the reward's 'before': the kernel path measures
    the state again rather than reuse the COM it measured after the last step."""
    env = BatchEnv("Walker-v0", bodies(3), episode_steps=50, fused=True)
    a = np.ones((env.n_worlds, env.sim.max_actuators))
    env.step(a)
    version = env.sim.state_version
    env.sim.state[0, :env.n_points[0], 0] += 1.0  # one voxel = 0.1; ten of them to the right
    assert env.sim.state_version > version
    _, r, *_ = env.step(a)
    ref = BatchEnv("Walker-v0", bodies(3), episode_steps=50, fused=False)
    ref.step(a)
    ref.sim.state[0, :ref.n_points[0], 0] += 1.0
    _, r_ref, *_ = ref.step(a)
    assert same_bits(r, r_ref)
    assert abs(r[0]) < 0.5  # the move itself is not rewarded (it happened before the step)


def test_default_path_by_batch_size():
    """Small batches take numpy (a kernel launch costs more there), large ones the kernels."""
    from tasks.env import FUSED_MIN
    small = BatchEnv("Walker-v0", bodies(0)[:2], episode_steps=5)
    assert not small.fused
    big = BatchEnv("Walker-v0", list(sample_robots(FUSED_MIN, (5, 5), np.random.default_rng(0))),
                   episode_steps=5)
    assert big.fused


def _subprocess(arch: str, precision: str, tasks: str, steps: int) -> subprocess.CompletedProcess:
    env = {**os.environ, "SGR_ARCH": arch, "SGR_PRECISION": precision, "PYTHONPATH": str(ROOT),
           "LP_NATIVE_VECTOR_WIDTH": "128", "GALLIVM_PERF": "nopt"}
    code = ("import sys; from tests.tasks.test_env_kernels import run_both; "
            "from tsim.backend import runtime; "
            "[run_both(t, int(sys.argv[2])) for t in sys.argv[1].split(',')]; "
            "print('ok', runtime.precision())")
    return subprocess.run([sys.executable, "-c", code, tasks, str(steps)], cwd=ROOT, env=env,
                          capture_output=True, text=True, timeout=540)


@pytest.mark.slow
@pytest.mark.subprocess
def test_kernel_path_equals_numpy_path_in_f32():
    """In an f32 process (float32 state, observations and rewards; COMs in float64 from float32
    sums, as numpy's float32 / int64) the kernels still give numpy's bits."""
    tasks = ("Walker-v0,Carrier-v0,UpStepper-v0,BidirectionalWalker-v0,Catcher-v0,Flipper-v0,CaveCrawler-v0,"
             "Traverser-v0,AreaMaximizer-v0")
    r = _subprocess("cpu", "f32", tasks, 60)
    assert r.returncode == 0, r.stderr[-2000:]
    assert "ok f32" in r.stdout


@pytest.mark.slow
@pytest.mark.subprocess
def test_kernel_path_equals_numpy_path_on_vulkan():
    """The kernels compile and give numpy's bits on Vulkan (lavapipe here), f64 and f32."""
    probe = subprocess.run([sys.executable, "-c", "import tsim.backend.runtime as r; r.init()"], cwd=ROOT,
                           env={**os.environ, "SGR_ARCH": "vulkan", "PYTHONPATH": str(ROOT)},
                           capture_output=True, text=True, timeout=120)
    if probe.returncode:
        pytest.skip("no Vulkan device here; on Debian, apt-get install mesa-vulkan-drivers gives lavapipe")
    for precision in ("f64", "f32"):
        r = _subprocess("vulkan", precision, "Walker-v0,Carrier-v0,UpStepper-v0", 12)
        assert r.returncode == 0, r.stderr[-2000:]
        assert f"ok {precision}" in r.stdout


def test_kernel_com_voxel_units_and_sight_equal_numpys():
    """The sight kernels alone against `tasks.observations`: the COM in voxel units to the bit after
    some steps, and the floor and ceiling sight for COMs anywhere, on lattice lines and half-way
    between them (where evogym's open windows drop terrain points) included, beyond the terrain's
    ends and not finite."""
    from tasks import kernels as EK
    from tasks import observations as O
    env = BatchEnv("UpStepper-v0", bodies(5) * 3, episode_steps=50, fused=True)
    rng = np.random.default_rng(2)
    for _ in range(8):
        env.step(rng.uniform(0.6, 1.6, (env.n_worlds, env.sim.max_actuators)))
    st = env.sim.state
    com = np.empty((env.n_worlds, 2))
    EK.com_voxel_units(st.reshape(-1), env.n_points.astype(np.int32), st.shape[1], 0.1, EK.ti.f64, com, False)
    assert same_bits(com, O.com_voxel_units(st[:, :env.sim.max_robot_points, 0:2], env.n_points))
    terrain = env._terrain
    tv = np.ascontiguousarray(terrain / 0.1)
    cv = np.concatenate([rng.uniform(0, 80, (40, 2)), np.round(rng.uniform(0, 80, (20, 2))),
                         np.round(rng.uniform(0, 80, (20, 2))) + 0.5, rng.uniform(-20, 0, (4, 2)),
                         [[tv[0].max() + 3, 2.0], [tv[0].min() - 0.5, 3.0], [np.nan, 1.0], [5.0, np.nan],
                          [np.inf, 1.0], [-np.inf, 1.0], [5.0, np.inf]]])
    for dist, below in ((5, True), (3, False), (2, True), (0, False)):
        out = np.empty((len(cv), 2 * dist + 1))
        EK.terrain_sight(cv, tv[0], tv[1], dist, below, 5.0, 0.1, out, False)
        assert same_bits(out, O.terrain_sight(cv, terrain, dist, below=below)), (dist, below)


def test_orientation_kernels_give_numpys_bits_bent_turned_and_at_rest():
    """`tasks.kernels.orientation` against `tasks.orientation.orientation` on random bodies of
    4 to 40 points (padded, each world its own count), turned and bent, and undeformed (where
    cosines round above 1 and are clamped), from float64 and float32 points: the same bits."""
    from tasks import kernels as EK
    from tasks.orientation import orientation
    from tsim.backend import runtime

    runtime.init()
    rng = np.random.default_rng(0)
    for dt in (np.float64, np.float32):
        for trial in range(12):
            B, N = 40, int(rng.integers(4, 41))
            n = rng.integers(4, N + 1, size=B)
            mask = np.arange(N)[None, :] < n[:, None]
            pos0 = (rng.normal(size=(B, N, 2)) * mask[:, :, None]).astype(dt)
            turn = rng.uniform(0, 2 * np.pi, size=B)
            c, s = np.cos(turn)[:, None], np.sin(turn)[:, None]
            x, y = pos0[:, :, 0].astype(np.float64), pos0[:, :, 1].astype(np.float64)
            pos = np.stack([c * x - s * y, s * x + c * y], axis=2) + rng.normal(size=(B, 1, 2))
            pos = pos + 1e-3 * rng.normal(size=pos.shape)
            pos = pos0.copy() if trial % 4 == 0 else (pos * mask[:, :, None]).astype(dt)
            rows = (np.arange(B) * N).astype(np.int32)
            got = EK.orientation(pos.reshape(-1), rows, 2, pos0.reshape(-1), rows, 2, n.astype(np.int32), N,
                                 True)
            assert same_bits(got, orientation(pos, pos0, mask)), (dt, trial)


@pytest.mark.parametrize("task", ["Carrier-v0", "BeamToppler-v0", "CaveCrawler-v0", "AreaMaximizer-v0",
                                  "Flipper-v0"])
def test_a_non_finite_point_gives_the_numpy_paths_bits(task):
    """A world whose state holds inf or NaN (a blown-up robot, which the simulator freezes) gets
    the numpy path's observation and reward to the bit on the kernel path: NaN where numpy has NaN
    (a clip keeps it; a sum from +0.0 does not start from the first point), finite where numpy
    is finite (the hull's sort puts a NaN after the padding)."""
    for col, value, row in ((0, np.inf, "object"), (0, np.nan, "object"), (0, np.nan, 3), (1, np.inf, 3)):
        envs = [BatchEnv(task, bodies(0), episode_steps=40, fused=f, seeds=0) for f in (True, False)]
        for e in envs:
            r = row
            if row == "object":
                if not e._obj_index:
                    continue
                r = e._obj_index[next(iter(e._obj_index))][1][0, 0]
            e.sim.state[0, r, col] = value
        assert same_bits(envs[0].observe(), envs[1].observe()), (col, value, row)
        a = np.full((envs[0].n_worlds, envs[0].sim.max_actuators), 1.1)
        outs = [e.step(a) for e in envs]
        for k in range(2):
            assert same_bits(outs[0][k], outs[1][k]), (col, value, row, k)
