"""Backends that say what they are (issue 45, item 4), through the real `sgr` in subprocesses
(Taichi starts once per process): the first line of `evolve`, `bench` and `validate` names the
backend, its device and the precision; a backend that cannot start leaves no run folder, so the
retry is not blocked; `SGR_ARCH=gpu` refuses a software Vulkan device (Mesa's lavapipe) rather
than running ~25x slower than the CPU."""

import os
import shutil
import subprocess
import sys
from pathlib import Path

import pytest
import yaml

from tsim.backend import devices

pytestmark = [pytest.mark.slow, pytest.mark.subprocess]

ROOT = Path(__file__).resolve().parents[3]


def sgr(*args, cwd, **env) -> subprocess.CompletedProcess:
    base = {k: v for k, v in os.environ.items() if k not in ("SGR_ARCH", "SGR_THREADS", "SGR_PRECISION")}
    return subprocess.run([sys.executable, "-m", "evolve.cli", *args], cwd=cwd, capture_output=True,
                          text=True, env={**base, "PYTHONPATH": str(ROOT), **env}, timeout=300)


def tiny(folder: Path) -> Path:
    cfg = {"method": "sgr", "task": "Walker-v0", "generations": 1, "pop_size": 4, "episode_steps": 2,
           "render_champion": False, "workers": 2,
           "neat_config": str(ROOT / "configs/neat/sgr.ini")}
    (folder / "tiny.yaml").write_text(yaml.safe_dump(cfg))
    return folder / "tiny.yaml"


def test_evolve_bench_and_validate_start_by_naming_backend_device_and_precision(tmp_path):
    cpu = devices.cpu_name()
    r = sgr("evolve", "--config", str(tiny(tmp_path)), "--out", "r", "--quiet", cwd=tmp_path)
    assert r.returncode == 0, r.stderr
    lines = r.stdout.splitlines()
    assert lines[0].startswith("backend: cpu (") and cpu in lines[0] and lines[0].endswith(", f64"), lines
    assert lines[1] == "run directory: r"
    r = sgr("evolve", "--resume", "r", "--generations", "2", "--quiet", cwd=tmp_path)
    assert r.returncode == 0, r.stderr
    assert r.stdout.splitlines()[0].startswith("backend: cpu (") and cpu in r.stdout.splitlines()[0]
    r = sgr("bench", "--robots", "2", "--steps", "2", "--precision", "f32", cwd=tmp_path)
    assert r.returncode == 0, r.stderr
    first = r.stdout.splitlines()[0]
    assert first.startswith("backend: cpu (") and cpu in first and first.endswith(", f32"), first
    (tmp_path / "one").mkdir()
    shutil.copy(ROOT / "tests/data/returns/Thrower-v0.npz", tmp_path / "one")  # 40 robots, 300 steps
    r = sgr("validate", "one", cwd=tmp_path)
    assert r.returncode == 0, r.stderr
    lines = r.stdout.splitlines()
    assert lines[0].startswith("backend: cpu (") and lines[0].endswith(", f64")
    assert lines[1].startswith("Thrower-v0 ")


def test_a_backend_that_cannot_start_leaves_no_run_folder_and_the_retry_runs(tmp_path):
    """SGR_ARCH=cuda where there is no CUDA (as here; metal elsewhere): one error line and no
    folder, whether --out is given or not; the same command on the CPU then runs."""
    arch = "metal" if devices.cuda_name() is not None else "cuda"
    if arch == "metal" and sys.platform == "darwin":
        pytest.skip("this machine has both CUDA and Metal: no arch fails to start here")
    cfg = str(tiny(tmp_path))
    r = sgr("evolve", "--config", cfg, "--out", "r", cwd=tmp_path, SGR_ARCH=arch)
    assert r.returncode == 2 and r.stderr.startswith(f"sgr: error: SGR_ARCH={arch}"), r.stderr
    assert len(r.stderr.splitlines()) == 1 and r.stdout == "", (r.stdout, r.stderr)
    r = sgr("evolve", "--config", cfg, cwd=tmp_path, SGR_ARCH=arch)  # the default runs/<name>
    assert r.returncode == 2, r.stderr
    assert not (tmp_path / "r").exists() and not (tmp_path / "runs").exists()
    r = sgr("evolve", "--config", cfg, "--out", "r", "--quiet", cwd=tmp_path)
    assert r.returncode == 0, r.stderr
    assert (tmp_path / "r" / "champion.json").is_file()


def software_vulkan_only() -> bool:
    """Whether the only Vulkan devices here are software ones and there is no CUDA: where
    SGR_ARCH=gpu would land on a software device."""
    found = devices.vulkan_devices()
    return (bool(found) and all(d["type"] == devices.VK_CPU for d in found)
            and devices.cuda_name() is None and sys.platform != "darwin")


@pytest.mark.vulkan
def test_gpu_refuses_a_software_vulkan_device_and_vulkan_names_it(tmp_path):
    if not software_vulkan_only():
        pytest.skip("needs Mesa's lavapipe as the only Vulkan device and no CUDA (Debian: apt-get "
                    "install mesa-vulkan-drivers)")
    r = sgr("evolve", "--config", str(tiny(tmp_path)), "--out", "r", cwd=tmp_path, SGR_ARCH="gpu")
    lines = r.stderr.splitlines()
    assert r.returncode == 2 and len(lines) == 1, r.stderr
    assert lines[0].startswith("sgr: error: SGR_ARCH=gpu: the only GPU here is llvmpipe")
    assert "software Vulkan device" in lines[0] and "slower than SGR_ARCH=cpu" in lines[0]
    assert not (tmp_path / "r").exists()
    code = "import tsim.backend.runtime as r; r.init(); print(r.describe())"
    p = subprocess.run([sys.executable, "-c", code], cwd=ROOT, capture_output=True, text=True, timeout=300,
                       env={**os.environ, "SGR_ARCH": "vulkan", "SGR_PRECISION": "f32"})
    assert p.returncode == 0, p.stderr
    assert p.stdout.strip().startswith("backend: vulkan (llvmpipe")
    assert p.stdout.strip().endswith(": software, on the CPU), f32"), p.stdout
