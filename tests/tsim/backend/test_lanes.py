"""The lanes kernel (tsim/backend/lanes.py, issue #48 item 1): a world's substep spread over L threads of a
block. On Mesa's lavapipe (Vulkan on the CPU) it gives the CPU's f64 results on all 32 tasks, with
L below and above a world's number of points; on the CPU, where Taichi has no block barrier, it is
refused in one line and the CPU's kernels are untouched. The incidence lists it gathers springs
over add in the CPU scatter's order (checked here in numpy, bit for bit)."""

import json
import math

import numpy as np
import pytest

from tasks.specs import task_spec, task_world
from tests.tsim.backend.test_vulkan import all_tasks, cpu_f64, run, vulkan  # noqa: F401 - vulkan: a fixture
from tsim import kernels as K
from tsim.backend.lanes import check_lanes, incidence_lists
from tsim.kernels.lanes import incidence_sizes
from tsim.sampling import sample_robot, sample_robots
from tsim.sim import BatchSim


def _scatter(n_pts: int, ea, eb, fx, skip_zero: bool, start) -> list[float]:
    """`springs.add_to_ends` in Python floats (IEEE double, one operation at a time)."""
    v = list(start)
    for half in (0, 1):
        for e in range(len(ea)):
            if skip_zero and fx[e] == 0.0:
                continue
            if half == 0:
                v[ea[e]] -= fx[e]
            else:
                v[eb[e]] += fx[e]
    return v


def _gather(lists: np.ndarray, b: int, n_pts: int, pc: int, ec: int, fx, skip_zero: bool,
            start) -> list[float]:
    """`kernels.lanes.gather` in Python floats, from world b's lists as the kernel reads them."""
    sizes = incidence_sizes(pc, ec)
    per = sum(sizes.values())
    w = lists[b * per:(b + 1) * per]
    ist, imid, inc = w[:pc + 1], w[pc + 1:2 * pc + 1], w[2 * pc + 1:]
    out = []
    for p in range(n_pts):
        v = start[p]
        for c in range(ist[p], imid[p]):
            if not (skip_zero and fx[inc[c]] == 0.0):
                v -= fx[inc[c]]
        for c in range(imid[p], ist[p + 1]):
            if not (skip_zero and fx[inc[c]] == 0.0):
                v += fx[inc[c]]
        out.append(v)
    return out


def test_gathering_over_the_incidence_lists_adds_in_the_scatters_order_bit_for_bit():
    """For real bodies' springs (a batch of random 5x5 robots, one 10x10) and per-edge values of
    mixed magnitudes (so that the order of additions shows in the bits), each point's gather gives
    the serial scatter's value exactly, from zero (spring forces) and from positions with zero
    vectors left out (the constraints)."""
    rng = np.random.default_rng(7)
    bodies = list(sample_robots(5, (5, 5), rng)) + [sample_robot((10, 10), rng)]
    sim = BatchSim(task_world("Walker-v0"), bodies, task_spec("Walker-v0").origin)
    pc, ec, _ = K.capacity(sim.capacity_tier)
    n_edges, n_pts = sim.counts[:, K.N_EDGES], sim.counts[:, K.N_PTS]
    lists = incidence_lists(sim.edge_i, n_edges, pc, ec, 64)
    assert lists.dtype == np.int32 and lists.size == 64 * sum(incidence_sizes(pc, ec).values())
    differs = 0
    for b in range(sim.n_worlds):
        ea = sim.edge_i[b, :n_edges[b], 0].tolist()
        eb = sim.edge_i[b, :n_edges[b], 1].tolist()
        fx = (rng.standard_normal(n_edges[b]) * 10.0 ** rng.uniform(-8, 4, n_edges[b])).tolist()
        fx[::7] = [0.0] * len(fx[::7])
        start = rng.uniform(0, 1, n_pts[b]).tolist()
        for skip_zero, s0 in ((False, [0.0] * n_pts[b]), (True, start)):
            want = _scatter(n_pts[b], ea, eb, fx, skip_zero, s0)
            got = _gather(lists, b, n_pts[b], pc, ec, fx, skip_zero, s0)
            assert [math.copysign(1, x) for x in got] == [math.copysign(1, x) for x in want]
            assert got == want, b
            # the test can fail: adding a point's vectors in another order changes some bits
            rev = [sum(reversed([-fx[e] for e in range(len(ea)) if ea[e] == p]
                                + [fx[e] for e in range(len(eb)) if eb[e] == p]), s0[p])
                   for p in range(n_pts[b])]
            differs += sum(x != y for x, y in zip(rev, want, strict=True))
    assert differs > 0


@pytest.mark.parametrize("bad", [0, 3, 48, 2048, 4.0, True, "32"])
def test_lanes_must_be_a_power_of_two_up_to_1024(bad):
    with pytest.raises(ValueError, match="lanes must be a power of two"):
        check_lanes(bad)


def test_the_cpu_refuses_the_lanes_kernel_in_one_line_and_keeps_its_own():
    """Taichi's CPU backend has no block barrier: lanes > 1 is a one-line ValueError there, and
    lanes = 1 keeps the CPU's own cached launch."""
    sim = BatchSim(task_world("Walker-v0"), sample_robots(2, (5, 5), np.random.default_rng(0)), (1, 1))
    with pytest.raises(ValueError, match="GPU or Vulkan only"):
        sim.choose_kernel(lanes=32)
    sim.choose_kernel(lanes=1)
    sim.step()
    assert sim._launch is not None  # the CPU's cached launch (tsim/backend/launch.py's "host" path)


LANES = (4, 32)  # below and above a 5x5 robot's ~30 points and ~80 edges
TOP_TIER = 3  # the largest capacity tier the 32 tasks need (BridgeWalker-v0, Traverser-v0, ...)


def lanes_states(tasks: list[str], steps: int, robots: int, lanes: list[int]) -> dict:
    """{L: {task: (B, P, 4) positions and velocities}} after `steps` env steps of `robots` random 5x5
    robots per task under alternating actions (as test_vulkan's `run_states`), each task and L
    from a fresh env, on the lanes kernel; and {"shared": {L: tasks}}, those whose substeps ran in
    shared memory. Few compiled variants, so that lavapipe compiles little: sweeps and pair lists
    on where they pay (the same results either way, tests/tsim/test_kernels.py), the top capacity
    tier (global scratch only), except at the last L for the tasks that fit tier 0 (shared memory)."""
    from tasks.env import BatchEnv
    out: dict = {"shared": {}}
    for L in lanes:
        for task in tasks:
            rng = np.random.default_rng(0)
            env = BatchEnv(task, [sample_robot((5, 5), rng) for _ in range(robots)], episode_steps=50)
            sim = env.sim
            sim.sweep_mode, sim.pair_list = K.SWEEP_AUTO, K.LIST_AUTO
            keep = L == lanes[-1] and sim.capacity_tier == 0
            sim.choose_kernel(lanes=L, extra_capacity_tiers=0 if keep else TOP_TIER - sim.capacity_tier)
            env.reset()
            A = sim.max_actuators
            for t in range(steps):
                env.step(np.full((len(sim.bodies), A), 1.3 if t % 2 else 0.7))
            out.setdefault(str(L), {})[task] = sim.states64().tolist()
            if sim._launcher._split.launched_shared:
                out["shared"].setdefault(str(L), []).append(task)
    return out


LANES_STATES = ("import json, sys; from tests.tsim.backend.test_lanes import lanes_states; "
                "print(json.dumps(lanes_states(sys.argv[1].split(','), 2, 2, [4, 32])))")


@pytest.mark.slow
@pytest.mark.subprocess
@pytest.mark.vulkan
def test_the_lanes_kernel_on_lavapipe_gives_the_cpus_f64_results_on_every_task(vulkan):  # noqa: F811
    """All 32 tasks, two random 5x5 robots each, 2 env steps with contacts, with 4 and with 32 lanes
    per world (fewer and more lanes than a world's points), the substeps' arrays in global memory
    (4 lanes) and, where they fit, in shared memory (32): positions and velocities within 1e-9
    of the CPU's f64 (evogym's bits; measured 5.5e-12, the SPIR-V launch's own figure: not bits,
    lavapipe may fuse multiply-adds). A lane that read a point before another lane wrote it, a
    missing barrier or a gather in another order than the scatter's would be ~1e-16 to 1 off."""
    tasks = all_tasks()
    code = f"import sys; sys.argv = ['x', {','.join(tasks)!r}]\n" + LANES_STATES
    r = run(code, "vulkan", SGR_PRECISION="f64")
    assert r.returncode == 0, r.stderr[-2000:]
    got = json.loads(r.stdout.strip().splitlines()[-1])
    shared = got.pop("shared")
    # the 25 tasks of tier 0 ran their substeps in shared memory at the last L, none otherwise
    assert list(shared) == [str(LANES[-1])] and len(shared[str(LANES[-1])]) >= 20, shared
    ref = cpu_f64(tasks, 2, 2)
    assert sorted(got, key=int) == [str(L) for L in LANES]
    bad = {}
    for L, states in got.items():
        for t in tasks:
            d = float(np.abs(np.array(states[t]) - ref[t]).max())
            if not d <= 1e-9:
                bad[(L, t)] = d
    assert not bad, bad
