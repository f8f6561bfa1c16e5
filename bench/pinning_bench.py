"""Thread pinning on a shared machine: `sgr bench` and a short `sgr evolve`, pinned and unpinned, side
by side with others.

A process that simulates by itself with as many Taichi threads as it may use CPUs pins each thread
to its own CPU (tsim/backend/runtime.py `pin_threads`; `SGR_PIN=0` turns it off). Pinning helps a lone
process (Linux was slow to spread two freshly woken workers) but a pinned thread cannot move away
from a CPU another process keeps busy. This measures both sides, each case pinned and unpinned in
alternating rounds:

- `bench xN`: N `sgr bench` processes started together (N = 1, 2, 4): robot-steps/s of each (the
  median over the processes and rounds) and of all together;
- `bench beside busy`: one `sgr bench` beside one busy Python loop per CPU (another user's job);
- `evolve xN`: N short `sgr evolve` runs together (N = 1, 2): seconds per generation (the median of
  their generations.csv total_s). Their rollout workers run one thread each and are never pinned;
  the case shows whether the setting matters there at all.

Usage: python bench/pinning_bench.py [--robots 128] [--steps 300] [--rounds 2] [--record PATH]
"""

from __future__ import annotations

import argparse
import csv
import json
import os
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def sgr(*args: str, pin: bool, threads: int | None = None) -> subprocess.Popen:
    env = {**os.environ, "SGR_PIN": "1" if pin else "0"}
    if threads is not None:
        env["SGR_THREADS"] = str(threads)
    return subprocess.Popen([sys.executable, "-m", "evolve.cli", *args], cwd=ROOT, env=env,
                            stdout=subprocess.PIPE, stderr=subprocess.DEVNULL, text=True)


def bench_together(n: int, pin: bool, robots: int, steps: int, busy: int = 0) -> list[float]:
    """Robot-steps/s of each of `n` `sgr bench` processes started together (beside `busy` busy loops)."""
    loops = [subprocess.Popen([sys.executable, "-c", "while True: pass"]) for _ in range(busy)]
    try:
        procs = [sgr("bench", "--task", "Walker-v0", "--robots", str(robots), "--steps", str(steps), "--json",
                     pin=pin) for _ in range(n)]
        out = []
        for p in procs:
            text, _ = p.communicate(timeout=1800)
            if p.returncode != 0:
                raise SystemExit(f"sgr bench failed (exit {p.returncode})")
            out.append(float(json.loads(text.strip().splitlines()[-1])["robot_steps_per_s"]))
        return out
    finally:
        for loop in loops:
            loop.kill()
            loop.wait()


def evolve_together(n: int, pin: bool, generations: int, pop: int, steps: int) -> list[float]:
    """Seconds per generation (generations.csv total_s) of each of `n` short runs started together."""
    with tempfile.TemporaryDirectory() as tmp:
        outs = [Path(tmp) / f"run{i}" for i in range(n)]
        procs = [sgr("evolve", "--generations", str(generations), "--pop", str(pop), "--episode-steps",
                     str(steps), "--workers", "1", "--quiet", "--seed", str(i), "--out", str(out), pin=pin)
                 for i, out in enumerate(outs)]
        for p in procs:
            p.communicate(timeout=3600)
            if p.returncode != 0:
                raise SystemExit(f"sgr evolve failed (exit {p.returncode})")
        return [float(r["total_s"]) for out in outs for r in csv.DictReader((out / "generations.csv").open())]


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--robots", type=int, default=128, help="robots per sgr bench process (128)")
    ap.add_argument("--steps", type=int, default=300, help="steps timed per sgr bench process (300)")
    ap.add_argument("--rounds", type=int, default=2, help="rounds of every case, pinned and unpinned (2)")
    ap.add_argument("--counts", default="1,2,4", help="numbers of concurrent sgr bench processes (1,2,4)")
    ap.add_argument("--evolve-counts", default="1,2", help="numbers of concurrent sgr evolve runs (1,2)")
    ap.add_argument("--generations", type=int, default=4, help="generations of each sgr evolve run (4)")
    ap.add_argument("--pop", type=int, default=24, help="population of each sgr evolve run (24)")
    ap.add_argument("--record", metavar="PATH", help="also write a record (tasks/records.py)")
    args = ap.parse_args()
    cpus = len(os.sched_getaffinity(0))
    cases: dict[str, tuple] = {}
    for n in (int(x) for x in args.counts.split(",")):
        cases[f"bench x{n}"] = ("bench", n, 0)
    cases["bench beside busy"] = ("bench", 1, cpus)
    for n in (int(x) for x in args.evolve_counts.split(",") if x):
        cases[f"evolve x{n}"] = ("evolve", n, 0)
    got: dict[tuple[str, bool], list[float]] = {(c, p): [] for c in cases for p in (True, False)}
    for r in range(args.rounds):
        for case, (kind, n, busy) in cases.items():
            for pin in ((True, False) if r % 2 == 0 else (False, True)):
                t0 = time.perf_counter()
                if kind == "bench":
                    values = bench_together(n, pin, args.robots, args.steps, busy)
                else:
                    values = evolve_together(n, pin, args.generations, args.pop, 100)
                got[(case, pin)] += values
                print(f"round {r + 1} {case:18s} {'pinned  ' if pin else 'unpinned'} "
                      + " ".join(f"{v:.3g}" for v in values) + f"  ({time.perf_counter() - t0:.0f} s)",
                      flush=True)
    print(f"\n{cpus} CPUs; bench: robot-steps/s per process (median; higher is better); evolve: s per "
          "generation (median; lower is better)")
    print(f"{'case':20s} {'pinned':>10s} {'unpinned':>10s} {'pinned/unpinned':>16s}")
    figures = {}
    for case, (kind, _, _) in cases.items():
        pinned = statistics.median(got[(case, True)])
        unpinned = statistics.median(got[(case, False)])
        ratio = pinned / unpinned if kind == "bench" else unpinned / pinned  # > 1: pinning is better
        print(f"{case:20s} {pinned:10.4g} {unpinned:10.4g} {ratio:16.3f}")
        key = case.replace(" ", "_")
        unit = "robot-steps/s per process" if kind == "bench" else "s per generation"
        figures[key] = {"value": [round(pinned, 3), round(unpinned, 3)],
                        "unit": f"{unit}, pinned and unpinned"}
        figures[f"{key}_ratio"] = {"value": round(ratio, 3), "unit": "pinned's speed over unpinned's"}
    if args.record:
        from tasks.records import write_record

        write_record(args.record, None, figures, cpus=cpus)
        print(f"wrote {args.record}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
