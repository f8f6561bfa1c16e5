"""Where an SGR generation's time goes, part by part (not run by CI; issue #48 item 4).

    python bench/generation_breakdown.py --pop 1024 --generations 2 --json out.json

Runs the config (default configs/sgr/Walker-v0.yaml: honest evaluation, robust noise and final
selection) in this process (workers 1, so every part is seen) and times, by wrapping the functions
that do them: batch build (`BatchEnv(...)`), physics (`BatchSim.step`), the env's host work
(`BatchEnv.step` less the physics: observations, rewards, termination), controller inference on
the host (`ControllerBatch`), the rest of the rollout loop (noise, returns), CPPN decoding (compile,
body, validity, controller; one genome at a time), NEAT (reproduction, speciation), and final
selection (its episodes counted in the parts above and also as a whole). Wall and process CPU
seconds per part, per generation; the machine may be shared, so CPU time is the steadier figure.
The kernels are compiled (or loaded from Taichi's cache) before the first generation by a tiny
warm-up rollout. Nothing the run computes changes: the wrappers only read clocks.
"""

from __future__ import annotations

import argparse
import functools
import json
import subprocess
import sys
import tempfile
import time
from collections import defaultdict
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

_ACC: dict[str, list[float]] = defaultdict(lambda: [0.0, 0.0, 0])  # name -> [wall, cpu, calls]


def _timed(name: str, fn):
    """`fn`, its calls' wall and CPU seconds added to part `name`."""
    @functools.wraps(fn)
    def wrapper(*a, **k):
        w0, c0 = time.perf_counter(), time.process_time()
        try:
            return fn(*a, **k)
        finally:
            acc = _ACC[name]
            acc[0] += time.perf_counter() - w0
            acc[1] += time.process_time() - c0
            acc[2] += 1
    return wrapper


def _patch(owner, attr: str, name: str) -> None:
    setattr(owner, attr, _timed(name, getattr(owner, attr)))


def install() -> None:
    """Wrap the functions of every part (module globals and class attributes, where they are
    looked up at call time)."""
    import neat

    from evolve.methods import sgr, sgr_decoder
    from evolve.nn import dense
    from evolve.rollout import episodes, worker
    from evolve.runs import experiment
    from evolve.search import genome
    from tasks import env
    from tsim import sim

    _patch(env.BatchEnv, "__init__", "build")
    _patch(env.BatchEnv, "step", "env_step")
    _patch(sim.BatchSim, "step", "physics")
    _patch(dense.ControllerBatch, "__init__", "controller_setup")
    _patch(dense.ControllerBatch, "act", "controller_act")
    _patch(worker, "rollout_policy", "rollout")
    _patch(episodes, "rollout_policy", "rollout")
    _patch(sgr, "decode", "decode")
    _patch(sgr_decoder, "CompiledCPPN", "decode_cppn_compile")
    _patch(sgr_decoder, "body_from_cppn", "decode_body")
    _patch(sgr_decoder, "is_valid_robot", "decode_validity")
    _patch(sgr_decoder, "controller_from_cppn", "decode_controller")
    _patch(genome.FlexibleReproduction, "reproduce", "neat_reproduce")
    _patch(neat.DefaultSpeciesSet, "speciate", "neat_speciate")
    _patch(experiment.Experiment, "_select_champion", "final_selection")


def table(acc: dict[str, list[float]], total_wall: float, total_cpu: float) -> dict[str, dict]:
    """Exclusive parts (the env's host work without the physics, the rollout loop without build,
    env and controller), each {wall_s, cpu_s, calls}, and `other` (checkpoints, bookkeeping)."""
    g = {k: v for k, v in acc.items()}
    z = [0.0, 0.0, 0]

    def part(k):
        return g.get(k, z)

    def minus(a, *bs):
        return [a[0] - sum(b[0] for b in bs), a[1] - sum(b[1] for b in bs), a[2]]

    rows = {
        "batch build (BatchEnv)": part("build"),
        "physics (BatchSim.step)": part("physics"),
        "env host (obs, rewards, done)": minus(part("env_step"), part("physics")),
        "controller inference (host)": [part("controller_act")[0] + part("controller_setup")[0],
                                        part("controller_act")[1] + part("controller_setup")[1],
                                        part("controller_act")[2]],
        "rollout loop rest (noise, sums)": minus(part("rollout"), part("build"), part("env_step"),
                                                 part("controller_act"), part("controller_setup")),
        "decode: CPPN compile": part("decode_cppn_compile"),
        "decode: body": part("decode_body"),
        "decode: validity": part("decode_validity"),
        "decode: controller": part("decode_controller"),
        "decode: rest": minus(part("decode"), part("decode_cppn_compile"), part("decode_body"),
                              part("decode_validity"), part("decode_controller")),
        "NEAT reproduction": part("neat_reproduce"),
        "NEAT speciation": part("neat_speciate"),
    }
    counted = [sum(v[0] for v in rows.values()), sum(v[1] for v in rows.values())]
    rows["other (checkpoints, records, final-selection bookkeeping)"] = [
        total_wall - counted[0], total_cpu - counted[1], 0]
    out = {k: {"wall_s": round(v[0], 3), "cpu_s": round(v[1], 3), "calls": int(v[2])}
           for k, v in rows.items()}
    fs = part("final_selection")
    out["(of which final selection, all parts)"] = {"wall_s": round(fs[0], 3), "cpu_s": round(fs[1], 3),
                                                    "calls": int(fs[2])}
    return out


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--config", default=str(ROOT / "configs/sgr/Walker-v0.yaml"))
    ap.add_argument("--pop", type=int, default=1024)
    ap.add_argument("--generations", type=int, default=2)
    ap.add_argument("--steps", type=int, help="episode_steps (default: the config's)")
    ap.add_argument("--json", help="write the result here")
    args = ap.parse_args()

    import numpy as np

    from evolve.rollout.episodes import dense_policy, rollout_policy  # noqa: F401
    from evolve.runs.experiment import Experiment
    from tasks.env import BatchEnv
    from tsim.backend import runtime
    from tsim.sampling import sample_robots

    runtime.init()
    warm = BatchEnv("Walker-v0", list(sample_robots(4, (5, 5), np.random.default_rng(0))), episode_steps=3)
    warm.step(np.ones((4, warm.sim.max_actuators)))  # compiles (or loads) the step kernel
    install()
    per_gen = []
    with tempfile.TemporaryDirectory() as tmp:
        flags = {"generations": args.generations, "pop_size": args.pop, "workers": 1}
        if args.steps:
            flags["episode_steps"] = args.steps
        w0, c0 = time.perf_counter(), time.process_time()
        marks = [(w0, c0, {})]
        exp = Experiment.create(args.config, f"{tmp}/run", flags, quiet=True)  # decodes generation 0

        def after(e):
            marks.append((time.perf_counter(), time.process_time(), {k: list(v) for k, v in _ACC.items()}))

        exp.run_all(after_generation=after)
        wall, cpu = time.perf_counter() - w0, time.process_time() - c0
        cfg = exp.cfg
        exp.close()
    for (wa, ca, a), (wb, cb, b) in zip(marks[:-1], marks[1:], strict=True):
        diff = {k: [v[0] - a.get(k, [0, 0, 0])[0], v[1] - a.get(k, [0, 0, 0])[1],
                    v[2] - a.get(k, [0, 0, 0])[2]] for k, v in b.items()}
        per_gen.append({"wall_s": round(wb - wa, 3), "cpu_s": round(cb - ca, 3),
                        "parts": table(diff, wb - wa, cb - ca)})
    commit = subprocess.run(["git", "rev-parse", "--short", "HEAD"], capture_output=True, text=True,
                            cwd=ROOT).stdout.strip()
    out = {"config": args.config, "task": cfg.task, "pop": args.pop, "generations": args.generations,
           "episode_steps": cfg.episode_steps, "threads": runtime.threads(), "commit": commit,
           "wall_s": round(wall, 3), "cpu_s": round(cpu, 3), "total": table(dict(_ACC), wall, cpu),
           "per_generation": per_gen}
    if args.json:
        Path(args.json).write_text(json.dumps(out, indent=1))
    print(f"{cfg.task} pop {args.pop}, {args.generations} generation(s), "
          f"{runtime.threads()} thread(s), commit {commit}: {wall:.1f} s wall, {cpu:.1f} s CPU")
    print(f"{'part':58s} {'wall s':>9s} {'CPU s':>9s} {'% CPU':>6s}")
    for k, v in out["total"].items():
        print(f"{k:58s} {v['wall_s']:9.2f} {v['cpu_s']:9.2f} {100 * v['cpu_s'] / max(cpu, 1e-9):6.1f}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
