"""f32 against f64 per core, side by side: robot-steps/s at given body sizes (not run by CI).

    python bench/precision_bench.py [--sizes 5 12] [--robots 16] [--steps 50] [--rounds 3]

A process runs in one precision (tsim.backend.runtime), so each measurement is a `bench/body_size_bench.py`
subprocess on one Taichi thread (Walker-v0, the same random bodies, environment and physics timed
together, compilation excluded), and the two precisions alternate: f64, f32, f64, f32, ... so
that a shared machine's load falls on both alike. Prints each round and the medians, and the CPU
model from /proc/cpuinfo.
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
from pathlib import Path

BENCH = Path(__file__).with_name("body_size_bench.py")


def cpu_model() -> str:
    """The CPU's model name (Linux), else the platform's processor string."""
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                return line.split(":", 1)[1].strip()
    except OSError:
        pass
    import platform

    return platform.processor() or "unknown"


def one_run(precision: str, sizes: list[int], robots: int, steps: int) -> dict[int, float]:
    """Robot-steps/s per body size in a fresh process running in `precision`."""
    env = {**os.environ, "SGR_PRECISION": precision}
    cmd = [sys.executable, str(BENCH), "--sizes", *map(str, sizes), "--robots", str(robots),
           "--steps", str(steps), "--threads", "1", "--evogym-python", "/nonexistent", "--json"]
    out = subprocess.run(cmd, env=env, capture_output=True, text=True, check=True)
    rows = json.loads(out.stdout.strip().splitlines()[-1])
    return {r["size"]: r["sgr"] for r in rows}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--sizes", type=int, nargs="+", default=[5, 12])
    ap.add_argument("--robots", type=int, default=16)
    ap.add_argument("--steps", type=int, default=50)
    ap.add_argument("--rounds", type=int, default=3)
    args = ap.parse_args()
    print(f"CPU: {cpu_model()}; one Taichi thread; Walker-v0, {args.robots} robots x {args.steps} steps")
    got: dict[str, dict[int, list[float]]] = {p: {n: [] for n in args.sizes} for p in ("f64", "f32")}
    for k in range(args.rounds):
        for p in ("f64", "f32"):
            for n, v in one_run(p, args.sizes, args.robots, args.steps).items():
                got[p][n].append(v)
            print(f"round {k + 1} {p}: " + "  ".join(f"{n}x{n} {got[p][n][-1]:7.0f}" for n in args.sizes),
                  flush=True)
    for n in args.sizes:
        a, b = statistics.median(got["f64"][n]), statistics.median(got["f32"][n])
        print(f"{n:2d}x{n:<2d} median robot-steps/s per core: f64 {a:7.0f}  f32 {b:7.0f}  "
              f"f32/f64 {b / a:.2f}")


if __name__ == "__main__":
    sys.exit(main())
