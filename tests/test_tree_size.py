"""What travels to a GPU machine fits it (issue 27): the working tree it receives (tracked files
plus untracked ones git does not ignore) and the device wheels (device/device-wheels.json: CI does
not download them, device/device_wheels.sh checks them against it) stay within 56 MiB of the 64 MiB
a device machine takes (issue 34: a margin for run records committed later); and
device/gpu_check.sh's default reference folders are in the tree."""

import json
import re
import shutil
import subprocess
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
BUDGET = 56 * 2**20  # bytes; the device machine takes 64 MiB, the rest is slack for $OUT and notes


def git_files(*args: str) -> list[str]:
    out = subprocess.run(["git", "-C", str(ROOT), "ls-files", "-z", *args], check=True,
                         capture_output=True).stdout
    return [f for f in out.decode().split("\0") if f]


@pytest.fixture(scope="module")
def files() -> dict[str, list[str]]:
    if shutil.which("git") is None or not (ROOT / ".git").exists():
        pytest.skip("not a git checkout: the tracked files are unknown")
    return {"tracked": git_files(), "untracked": git_files("--others", "--exclude-standard")}


def size(paths: list[str]) -> int:
    return sum((ROOT / p).stat().st_size for p in paths if (ROOT / p).is_file())


def test_tree_and_device_wheels_fit_56_mib(files):
    wheels = json.loads((ROOT / "device" / "device-wheels.json").read_text())
    assert wheels["total"] == sum(wheels["files"].values())
    tracked, untracked = size(files["tracked"]), size(files["untracked"])
    data = size([f for f in files["tracked"] if f.startswith("tests/data/")])
    total = tracked + untracked + wheels["total"]
    mib = 2**20
    msg = (f"{total / mib:.2f} MiB travel to the GPU machine, over the {BUDGET / mib:.0f} MiB budget: "
           f"tracked files {tracked / mib:.2f} MiB ({len(files['tracked'])} files; tests/data "
           f"{data / mib:.2f} MiB), untracked files git "
           f"does not ignore {untracked / mib:.2f} MiB ({len(files['untracked'])}), device wheels "
           f"{wheels['total'] / mib:.2f} MiB (device/device-wheels.json)")
    assert total <= BUDGET, msg


def test_gpu_check_default_data_folders_exist():
    text = (ROOT / "device" / "gpu_check.sh").read_text()
    (default,) = re.findall(r"\$\{DATA:-([^}]*)\}", text)
    folders = default.split()
    assert folders, "device/gpu_check.sh names no default DATA folder"
    for d in folders:
        assert (ROOT / d).is_dir(), f"device/gpu_check.sh's default DATA folder {d} is missing"
