"""Checkpoint size and save time: today's gzipped JSON against the pickles sgr wrote before.

For each run the state is restored into an Experiment, then saved both ways (best of --repeat, the
state taken and serialised; then again with the file written by atomic_write, fsync included):
  pickle: {**search.state(), "problem": the method's state as objects} -> pickle.dumps (the old format)
  json:   Experiment.state() -> checkpoint_bytes (encode, json.dumps, gzip level 1)
Runs: any run directories given (their newest checkpoint; an older sgr's .pkl ones are unpickled,
so give only your own), plus fresh runs made here: direct and nested on Walker-v0 with the paper's
populations, a few generations of short episodes (the checkpoint's size does not depend on the
episode length).

    python bench/checkpoint_format.py [RUN_DIR ...] [--generations 8] [--repeat 5]
"""

from __future__ import annotations

import argparse
import pickle
import sys
import tempfile
import time
from pathlib import Path

import yaml

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from evolve.config import RunConfig  # noqa: E402
from evolve.records.files import atomic_write  # noqa: E402
from evolve.records.legacy import load_trusted_pickle  # noqa: E402
from evolve.records.rundir import RunDir, checkpoint_bytes  # noqa: E402
from evolve.runs.checkpoint import load_checkpoint  # noqa: E402
from evolve.runs.experiment import Experiment  # noqa: E402


def old_state(exp: Experiment) -> dict:
    """What an older sgr pickled: the search's objects and the method's state as objects."""
    problem = {}
    if exp.cfg.method == "nested":
        p = exp.problem
        problem = {"inner": {k: (s.state(), round(len(s.config.genome_config.input_keys) ** 0.5))
                             for k, s in p.inner.items()},
                   "generation": p.generation, "last_seen": dict(p.last_seen), "pinned": p.pinned}
    return {**exp.search.state(), "problem": problem}


def best_time(fn, repeat: int) -> tuple[float, bytes]:
    best, out = float("inf"), b""
    for _ in range(repeat):
        t = time.perf_counter()
        out = fn()
        best = min(best, time.perf_counter() - t)
    return best, out


def measure(run: RunDir, repeat: int) -> dict:
    cfg = RunConfig.of(run.config())
    pickles = run.pickled_checkpoints()
    if pickles and not run.checkpoints():
        state = load_trusted_pickle(pickles[-1])
    else:
        state = load_checkpoint(run, cfg)
    exp = Experiment(run, cfg, state=state, quiet=True, workers=1)
    try:
        t_old, b_old = best_time(lambda: pickle.dumps(old_state(exp), protocol=pickle.HIGHEST_PROTOCOL),
                                 repeat)
        g = exp.search.generation
        t_new, b_new = best_time(lambda: checkpoint_bytes({"generation": g, **exp.state()}), repeat)
        with tempfile.TemporaryDirectory(dir=run.path) as tmp:  # the whole save: + atomic_write (fsync)
            t_old_w, _ = best_time(lambda: atomic_write(Path(tmp) / "a.pkl", pickle.dumps(
                old_state(exp), protocol=pickle.HIGHEST_PROTOCOL)), repeat)
            t_new_w, _ = best_time(lambda: atomic_write(Path(tmp) / "a.json.gz", checkpoint_bytes(
                {"generation": g, **exp.state()})), repeat)
    finally:
        exp.pool.close()
    genomes = len(exp.search.population) + sum(len(s.population) for s in
                                               getattr(exp.problem, "inner", {}).values())
    return {"run": f"{cfg.method} {cfg.task} pop {cfg.pop_size} gen {g}", "genomes": genomes,
            "pickle_kib": len(b_old) / 1024, "json_kib": len(b_new) / 1024,
            "pickle_ms": 1e3 * t_old, "json_ms": 1e3 * t_new, "pickle_save_ms": 1e3 * t_old_w,
            "json_save_ms": 1e3 * t_new_w}


def fresh_runs(tmp: Path, generations: int) -> list[RunDir]:
    root = Path(__file__).resolve().parents[1] / "configs"
    runs = []
    for method in ("direct", "nested"):
        raw = yaml.safe_load((root / method / "Walker-v0.yaml").read_text())
        for key in ("neat_config", "controller_neat_config"):
            if key in raw:
                raw[key] = str((root / method / raw[key]).resolve())
        raw.update(generations=generations, episode_steps=20, render_champion=False, workers=2)
        p = tmp / f"{method}.yaml"
        p.write_text(yaml.safe_dump(raw))
        exp = Experiment.create(str(p), str(tmp / method), {}, quiet=True)
        exp.run_all()
        exp.close()
        runs.append(exp.run)
    return runs


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("runs", nargs="*")
    ap.add_argument("--generations", type=int, default=8)
    ap.add_argument("--repeat", type=int, default=5)
    args = ap.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        runs = [RunDir(r) for r in args.runs] + fresh_runs(Path(tmp), args.generations)
        print(f"{'run':<36} {'genomes':>7} {'pickle KiB':>10} {'json.gz KiB':>11} {'size x':>6} "
              f"{'pickle ms':>9} {'json ms':>8} {'time x':>6} {'saved: pickle ms':>16} {'json ms':>8}")
        for run in runs:
            m = measure(run, args.repeat)
            print(f"{m['run']:<36} {m['genomes']:>7} {m['pickle_kib']:>10.1f} {m['json_kib']:>11.1f} "
                  f"{m['json_kib'] / m['pickle_kib']:>6.2f} {m['pickle_ms']:>9.1f} {m['json_ms']:>8.1f} "
                  f"{m['json_ms'] / m['pickle_ms']:>6.2f} {m['pickle_save_ms']:>16.1f} "
                  f"{m['json_save_ms']:>8.1f}", flush=True)


if __name__ == "__main__":
    main()
