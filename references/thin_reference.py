"""Thin the full evogym recordings of tests/data/traces and tests/data/returns to what travels.

Their recorder (the data authors' make_returns.py, in their own evogym_ref tools) is not in this
repository; the full files are, in git history (FULL_COMMIT). This keeps every value evogym
recorded except the per-step states between strides, and writes byte-reproducible files
(references/npz_io.py):

- traces/caseNN_*.npz: `robot_pos`, `robot_vel`, `box_pos`, `box_vel` and `obs` at steps 0..50
  (what the 50-step checks compare), every 50th and the last (`state_steps`); `com`, `reward`,
  `actions` and every other key unchanged;
- returns/<task>.npz: `com`, `com_plus`, `com_minus` and `package_com` at steps 0..5, every 50th and
  the last (`state_steps`; each case's final COM stays in `com_final`); every other key unchanged.

It updates the sha256 (and size) of each file in traces/index.json and returns/summary.json.

    .venv/bin/python references/thin_reference.py            # rewrites tests/data/{traces,returns}
"""

from __future__ import annotations

import argparse
import io
import json
import os
import subprocess
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from npz_io import save_npz, state_steps  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
FULL_COMMIT = "e1510b9"  # the last commit that holds the full recordings
TRACE_KEYS = ("robot_pos", "robot_vel", "box_pos", "box_vel", "obs")
RETURNS_KEYS = ("com", "com_plus", "com_minus", "package_com")


def full(path: str, commit: str) -> dict:
    """The arrays of the full recording `path` (repository-relative) at `commit`, in file order."""
    raw = subprocess.run(["git", "-C", str(ROOT), "show", f"{commit}:{path}"], check=True,
                         capture_output=True).stdout
    z = np.load(io.BytesIO(raw), allow_pickle=False)
    return {k: z[k] for k in z.files}


def thin(arrays: dict, keys: tuple, keep: np.ndarray) -> dict:
    """`arrays` with `state_steps` = keep added after `steps`/`episode_length` and each of `keys`
    (step axis: axis 0 for a trace, axis 1 for a batch of cases) cut to those rows."""
    out = {}
    for k, v in arrays.items():
        if k in keys:
            v = v[keep] if "steps" in arrays else v[:, keep]
        if k == "format_version":
            v = np.int64(2)  # 2: the state arrays at `state_steps` only
        out[k] = v
        if k in ("steps", "episode_length"):
            out["state_steps"] = keep
    return out


def main() -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--commit", default=FULL_COMMIT, help="git commit holding the full recordings")
    p.add_argument("--data", default=str(ROOT / "tests" / "data"))
    args = p.parse_args()
    data = Path(args.data)
    index = json.loads((data / "traces" / "index.json").read_text())
    for case in index["cases"]:
        z = full(f"tests/data/traces/{case['file']}", args.commit)
        keep = state_steps(int(z["steps"]), 50, first=50)
        case["sha256"] = save_npz(str(data / "traces" / case["file"]), thin(z, TRACE_KEYS, keep))
    (data / "traces" / "index.json").write_text(json.dumps(index, indent=1) + "\n")
    summary = json.loads((data / "returns" / "summary.json").read_text())
    for name, meta in summary["files"].items():
        z = full(f"tests/data/returns/{name}", args.commit)
        keep = state_steps(int(z["episode_length"]), 50)
        path = data / "returns" / name
        meta["sha256"] = save_npz(str(path), thin(z, RETURNS_KEYS, keep))
        meta["bytes"] = os.path.getsize(path)
    (data / "returns" / "summary.json").write_text(json.dumps(summary, indent=2) + "\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())
