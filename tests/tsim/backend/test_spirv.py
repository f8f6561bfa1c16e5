"""The SPIR-V backends' launch (tsim/backend/spirv.py: the scratch in global arrays, an env step in
several launches where the driver bounds a shader's loop iterations, as lavapipe does) gives the
numbers of one launch of all substeps. Run here on the CPU backend, where both are plain Taichi
kernels: bit for bit, with sweeps and pair lists kept between launches, a substep's contacts in
pieces, and worlds that stop mid-step."""

import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from tasks.specs import task_spec, task_world
from tests.tsim.conftest import drive
from tsim import kernels as K
from tsim.backend import spirv
from tsim.backend.spirv import batch_tier
from tsim.errors import SgrError
from tsim.sampling import sample_robot
from tsim.sim import BatchSim


def _run(task: str, bodies, steps: int, chunk: int | None, blow_up: int | None = None,
         sweep: int | None = None, pair_list: int | None = None, pieces: int = 1) -> BatchSim:
    """chunk: substeps per launch of the SPIR-V launch (0: a substep's contacts in `pieces`
    launches, then the rest in one), None: the CPU's kernel."""
    sim = BatchSim(task_world(task), bodies, task_spec(task).origin)
    sim.choose_kernel(serial=False, spirv_launch=chunk is not None, substeps_per_launch=chunk)
    sim._spirv_launcher.pieces = pieces
    if sweep is not None:
        sim.sweep_mode = sweep
    if pair_list is not None:
        sim.pair_list = pair_list

    def throw(sim: BatchSim, t: int) -> None:
        if t == 3 and blow_up is not None:
            sim.state[blow_up, 0, 1] = 1e4  # a point thrown far up: the world goes unstable

    return drive(sim, steps, throw)


@pytest.mark.parametrize("task, sweep, pair_list, chunk, pieces", [
    ("Walker-v0", None, None, 1, 1), ("Walker-v0", None, None, 7, 1), ("Walker-v0", None, None, 0, 1),
    ("Walker-v0", None, None, 0, 3), ("BeamToppler-v0", K.SWEEP_ALWAYS, K.LIST_ALWAYS, 1, 1),
    ("BeamToppler-v0", K.SWEEP_ALWAYS, K.LIST_ALWAYS, 0, 3)])
def test_launches_of_a_few_substeps_give_the_bits_of_one_launch_per_step(task, sweep, pair_list,
                                                                         chunk, pieces):
    """Launches of 1 or 7 substeps, or of a substep's contacts (in 1 or 3 pieces: voxels split
    between launches) then the rest: with sweeps and pair lists, the bits of one launch."""
    rng = np.random.default_rng(11)
    bodies = [sample_robot((5, 5), rng) for _ in range(3)]
    ref = _run(task, bodies, 20, None, sweep=sweep, pair_list=pair_list)
    sub = _run(task, bodies, 20, chunk, sweep=sweep, pair_list=pair_list, pieces=pieces)
    assert np.array_equal(sub.state, ref.state) and np.array_equal(sub.counts, ref.counts)
    assert np.array_equal(sub.time, ref.time)
    assert np.abs(ref.state[:, :, 0:2] - ref.initial_positions).max() > 0.05  # they moved


@pytest.mark.parametrize("chunk, pieces", [(0, 2), (1, 1), (7, 1)])
def test_a_world_that_stops_mid_step_is_left_where_one_launch_leaves_it(chunk, pieces):
    """A world with a point thrown far up turns unstable in a later substep of its env step
    (its status carried between launches in the global scratch); both launches leave it at the env step's
    start, at rest (pos_last = pos, vel_true = 0), while the others go on."""
    rng = np.random.default_rng(3)
    bodies = [sample_robot((5, 5), rng) for _ in range(3)]
    ref = _run("Walker-v0", bodies, 8, None, blow_up=1)
    sub = _run("Walker-v0", bodies, 8, chunk, blow_up=1, pieces=pieces)
    assert ref.counts[1, K.STATUS] == K.UNSTABLE and ref.time.tolist() == [8, 3, 8]
    assert np.array_equal(sub.counts, ref.counts) and np.array_equal(sub.time, ref.time)
    assert np.array_equal(sub.state, ref.state)


F32_STOP = """
import numpy as np
from tasks.specs import task_spec, task_world
from tests.tsim.conftest import drive
from tsim import kernels as K
from tsim.sampling import sample_robot
from tsim.sim import BatchSim

def run(chunk):
    rng = np.random.default_rng(3)
    bodies = [sample_robot((5, 5), rng) for _ in range(3)]
    sim = BatchSim(task_world("Walker-v0"), bodies, task_spec("Walker-v0").origin)
    sim.choose_kernel(serial=False, spirv_launch=chunk is not None, substeps_per_launch=chunk)
    def throw(s, t):
        if t == 3:
            s.state[1, 0, 1] = 1e4
    return drive(sim, 8, throw)

ref, sub = run(None), run(1)
print(ref.state.dtype, ref.state.shape[-1], int(ref.counts[1, K.STATUS] == K.UNSTABLE),
      int(np.array_equal(sub.state, ref.state)), int(np.array_equal(sub.counts, ref.counts)))
"""


@pytest.mark.slow
@pytest.mark.subprocess
def test_in_f32_a_world_that_stops_mid_step_is_left_where_one_launch_leaves_it_low_parts_too():
    """f32's state has more columns (the pairs' low parts, tsim/kernels/pairs.py), and its two-sum
    reads the global scratch's 1.0 in the SPIR-V launch: launches of one substep leave the unstable
    world, low parts too, bit for bit where one launch does (run in f32 in a subprocess; this
    process is f64)."""
    env = {k: v for k, v in os.environ.items() if k not in ("SGR_ARCH", "SGR_PRECISION")}
    out = subprocess.run([sys.executable, "-c", F32_STOP], env={**env, "SGR_PRECISION": "f32"},
                         cwd=Path(__file__).resolve().parents[3], capture_output=True, text=True,
                         timeout=300)
    assert out.returncode == 0, out.stderr[-2000:]
    dtype, columns, unstable, same_state, same_counts = out.stdout.split()[-5:]
    assert dtype == "float32" and int(columns) > 8 and unstable == "1"
    assert same_state == "1" and same_counts == "1"


def test_with_no_loop_bound_a_step_is_one_launch():
    """The CPU has no loop budget: the sentinel never fires, so a step stays one launch."""
    rng = np.random.default_rng(11)
    sim = _run("Walker-v0", [sample_robot((5, 5), rng) for _ in range(2)], 3, 30)
    assert sim._spirv_launcher.chunk == 30 and not sim._spirv_launcher.overrun.any()


def test_batch_tier_is_the_block_doubled_until_the_batch_fits():
    assert [batch_tier(n) for n in (1, 64, 65, 200)] == [64, 64, 128, 256]


def _overrunning(sim: BatchSim, monkeypatch, overruns) -> None:
    """Make the launcher see the driver's loop budget run out where `overruns(phase, n_sub,
    pieces)` says (the CPU has no budget: simulated around the real launches)."""
    launcher = sim._spirv_launcher
    real = launcher._launch

    def launch(phase, args, gf, gi, n_sub, piece=0, pieces=1):
        return real(phase, args, gf, gi, n_sub, piece, pieces) and not overruns(phase, n_sub, pieces)

    monkeypatch.setattr(launcher, "_launch", launch)


def test_the_launcher_halves_then_splits_contacts_until_launches_fit(monkeypatch):
    """Launches of more than one substep and contacts in fewer than 4 pieces overrun: the step
    ends as halves with 4 pieces, remembered, and with one launch's bits."""
    rng = np.random.default_rng(5)
    bodies = [sample_robot((5, 5), rng) for _ in range(2)]
    ref = _run("Walker-v0", bodies, 3, None)
    sim = BatchSim(task_world("Walker-v0"), bodies, task_spec("Walker-v0").origin)
    sim.choose_kernel(serial=False, spirv_launch=True)
    _overrunning(sim, monkeypatch, lambda phase, n_sub, pieces: (
        (phase == spirv.SUBSTEPS and n_sub > 0) or (phase == spirv.CONTACTS and pieces < 4)))
    drive(sim, 3)
    assert sim._spirv_launcher.chunk == 0 and sim._spirv_launcher.pieces == 4
    assert np.array_equal(sim.state, ref.state) and np.array_equal(sim.counts, ref.counts)


def test_a_world_whose_half_substep_overruns_stops_with_one_error_at_once(monkeypatch):
    """Where a substep's integration and constraints alone overrun (MOVE cannot be split), the
    launcher raises its one-line error without trying more pieces of the contacts."""
    rng = np.random.default_rng(5)
    sim = BatchSim(task_world("Walker-v0"), [sample_robot((5, 5), rng)], task_spec("Walker-v0").origin)
    sim.choose_kernel(serial=False, spirv_launch=True, substeps_per_launch=0)
    _overrunning(sim, monkeypatch, lambda phase, n_sub, pieces: phase == spirv.MOVE)
    with pytest.raises(SgrError, match="more loop iterations in one part of a substep"):
        sim.step()
    assert sim._spirv_launcher.pieces == 1
