"""Robot-steps/s by body size, sgr on one thread beside evogym on one core (not run by CI).

    python bench/body_size_bench.py [--sizes 5 8 12 16] [--robots 16] [--steps 50]
                                    [--evogym-python ~/.cache/evogym-venv/bin/python]

For each n, `--robots` random n x n bodies (evogym's distribution, `tsim.sampling`, seed 0) walk
Walker-v0 with sinusoidal open-loop actions in one BatchEnv on `--threads` Taichi threads (default
1); evogym simulates the same bodies one after another on one core (`bench/evogym_body_speed.py`,
skipped when its venv is missing). "per core" divides sgr's figure by its threads. At 16 x 16 a
draw from evogym's distribution (3/7 empty) is almost never connected: there the empty weight is
lowered in steps of 0.05 until 100,000 draws give a body (printed).

The 5x5 figure at 128 robots on all cores is `sgr bench`'s case beside evogym's:
`python bench/body_size_bench.py --sizes 5 --robots 128 --steps 200 --threads 2`.
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
from pathlib import Path


def _threads_arg() -> str:
    # before Taichi starts (at the imports below): --threads N, default one core
    argv = sys.argv[1:]
    return argv[argv.index("--threads") + 1] if "--threads" in argv[:-1] else "1"


os.environ["SGR_THREADS"] = _threads_arg()

import numpy as np  # noqa: E402

from tasks.bench import bench_bodies  # noqa: E402
from tsim.sampling import sample_robots  # noqa: E402

EVOGYM_PY = Path.home() / ".cache/evogym-venv/bin/python"


def bodies_of_size(n: int, count: int, seed: int = 0) -> tuple[list[np.ndarray], float]:
    """`count` random n x n bodies and the empty-voxel weight they were drawn with."""
    empty = 3 / 7  # evogym's default: empty 0.6, each material 0.2, normalised
    while True:
        rng = np.random.default_rng(seed)
        try:
            pd = (empty, *[(1 - empty) / 4] * 4)
            return list(sample_robots(count, (n, n), rng, pd=pd, max_tries=100_000)), empty
        except RuntimeError:
            empty -= 0.05


def evogym_speed(bodies: list[np.ndarray], task: str, steps: int, python: Path) -> float | None:
    """evogym's robot-steps/s on the same bodies, or None without its venv."""
    if not python.exists():
        return None
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / "bodies.npy"
        np.save(path, np.stack(bodies))
        script = Path(__file__).with_name("evogym_body_speed.py")
        out = subprocess.run([str(python), str(script), str(path), task, str(steps)],
                             capture_output=True, text=True, check=True)
    return float(out.stdout.strip().splitlines()[-1])


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--sizes", type=int, nargs="+", default=[5, 8, 12, 16])
    ap.add_argument("--robots", type=int, default=16)
    ap.add_argument("--steps", type=int, default=50)
    ap.add_argument("--task", default="Walker-v0")
    ap.add_argument("--evogym-python", type=Path, default=EVOGYM_PY)
    ap.add_argument("--threads", type=int, default=1, help="sgr's Taichi threads")
    ap.add_argument("--json", action="store_true")
    ap.add_argument("--record", metavar="PATH", help="also write a record (tasks/records.py)")
    args = ap.parse_args()
    rows = []
    for n in args.sizes:
        bodies, empty = bodies_of_size(n, args.robots)
        ours = bench_bodies(args.task, bodies, args.steps, physics=False)["robot_steps_per_s"]
        theirs = evogym_speed(bodies, args.task, args.steps, args.evogym_python)
        per_core = ours / args.threads
        rows.append({"size": n, "robots": args.robots, "empty_weight": empty,
                     "voxels": float(np.mean([np.count_nonzero(b) for b in bodies])),
                     "sgr": ours, "sgr_threads": args.threads, "evogym": theirs,
                     "per_core_ratio": per_core / theirs if theirs else None})
        if not args.json:
            r = rows[-1]
            ev = (f"evogym {theirs:6.0f}  per core {r['per_core_ratio']:5.1f}x" if theirs
                  else "evogym (no venv)")
            print(f"{n:2d}x{n:<2d} {args.robots} robots ({r['voxels']:5.1f} voxels, empty "
                  f"{empty:.2f})  sgr {ours:7.0f} on {args.threads} thread(s)  {ev}", flush=True)
    if args.json:
        print(json.dumps(rows))
    if args.record:
        from tasks.records import figure, write_record

        figures = {f"sgr-{r['size']}x{r['size']}": figure(round(r["sgr"]), "robot-steps/s") for r in rows}
        figures.update({f"per-core-{r['size']}x{r['size']}": figure(round(r["per_core_ratio"], 1), "x evogym")
                        for r in rows if r["per_core_ratio"]})
        write_record(args.record, None, figures, task=args.task, robots=args.robots, steps=args.steps,
                     threads=args.threads)


if __name__ == "__main__":
    sys.exit(main())
