"""bench/gpu_probe.py, the device probe of issue 48, rehearsed on the CPU; and the GPU block size
override it sets (`BatchSim.choose_kernel(gpu_block=...)`), which must leave the CPU path alone."""

import json
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from tasks.specs import task_world
from tsim.sampling import sample_robots
from tsim.sim import BatchSim

ROOT = Path(__file__).resolve().parents[3]


def _run(sim: BatchSim, steps: int = 5) -> bytes:
    for t in range(steps):
        a = 1.0 + 0.5 * np.sin(0.3 * t + np.arange(sim.max_actuators))[None, :]
        sim.set_actions(np.repeat(a, sim.n_worlds, axis=0))
        sim.step()
    return sim.state.tobytes() + sim.counts.tobytes()


def test_gpu_block_leaves_the_cpu_results_unchanged():
    """The CPU launches one world per block whatever gpu_block says (the kernel's last argument),
    with the same bits."""
    bodies = sample_robots(4, (5, 5), np.random.default_rng(5))
    plain = BatchSim(task_world("Walker-v0"), bodies, (1, 1))
    other = BatchSim(task_world("Walker-v0"), bodies, (1, 1))
    for sim in (plain, other):
        sim.choose_kernel(serial=False)  # the parallel kernel, the one that takes a block size
    other.choose_kernel(gpu_block=128)
    assert other._gpu_block == 128
    assert _run(plain) == _run(other)
    assert plain._launch._args[-1] == 1 and other._launch._args[-1] == 1


@pytest.mark.parametrize("bad", [0, 16, 48, 2048, 64.0, "64"])
def test_gpu_block_must_be_a_multiple_of_32_up_to_1024(bad):
    sim = BatchSim(task_world("Walker-v0"), sample_robots(1, (5, 5), np.random.default_rng(0)), (1, 1))
    with pytest.raises(ValueError, match="gpu_block"):
        sim.choose_kernel(gpu_block=bad)


@pytest.mark.slow
@pytest.mark.subprocess
def test_probe_rehearsal_writes_every_part_and_its_tables(tmp_path):
    """The CPU rehearsal at tiny sizes, in f32: every part runs and says so, the throughput table
    has a measured row per size and a skipped row for a lane count (the lanes kernel needs a
    block barrier, which Taichi's CPU backend has not), the kernel
    attributes say n/a on a CPU, the parity of the CPU with itself is bit-identical, and the
    precision asked for is the one the parts ran in."""
    out = tmp_path / "probe"
    env = {**os.environ, "SGR_ARCH": "cpu", "PYTHONPATH": str(ROOT)}
    r = subprocess.run([sys.executable, str(ROOT / "bench" / "gpu_probe.py"), "--quick", "--out", str(out),
                        "--precision", "f32", "--sizes", "4", "8", "--shapes", "5x5", "--lanes", "1", "32",
                        "--budget", "280", "--limit", "throughput_5x5=120", "--limit", "parity=120"],
                       env=env, capture_output=True, text=True, timeout=300)
    assert r.returncode == 0, r.stdout + r.stderr
    probe = json.loads((out / "probe.json").read_text())
    assert probe["arch"] == "cpu" and probe["precision"] == "f32"
    assert set(probe["parts"]) == {"throughput_5x5", "kernels", "parity"}
    for name, part in probe["parts"].items():
        assert part["status"].startswith("ok"), (name, part["status"])
    tp = probe["parts"]["throughput_5x5"]
    assert tp["precision"] == "f32" and tp["shape"] == [5, 5]
    measured = [row for row in tp["rows"] if "skipped" not in row]
    assert [row["B"] for row in measured] == [4, 8]
    for row in measured:
        assert row["lanes"] == 1 and row["block"] == "1 (cpu)"
        assert row["physics_robot_steps_per_s"] > 0 and row["env_robot_steps_per_s"] > 0
        assert row["build_us_per_robot"] > 0
    skipped = [row for row in tp["rows"] if "skipped" in row]
    assert [(row["B"], row["lanes"]) for row in skipped] == [(4, 32), (8, 32)]
    assert all("GPU or Vulkan only" in row["skipped"] for row in skipped)
    assert probe["parts"]["kernels"]["kernels"] == "n/a (cpu)"
    parity = probe["parts"]["parity"]
    assert parity["tasks"] == ["Walker-v0"] and len(parity["lines"]) == 1
    assert parity["bits_identical"] is True and parity["failures"] == []
    text = (out / "summary.txt").read_text()
    for line in ("throughput_5x5: ok", "physics rs/s", "n/a (cpu)", "bits: identical"):
        assert line in text, line
