"""Issue 23's next step, measured: choose a finished robust run's champion afresh among its final
elites (and the best-ever genome) by a K-episode mean under new noise tags, and check the choice
with another K episodes under other tags, beside each candidate's nominal (noise-free) return.

The run's last checkpoint holds the next generation's population, in which the elites keep their
recorded fitness; they are the candidates (the top 16 by it), with the search's best-ever genome.
Noise is the run's own `robust` setting with `episodes: K` and the mean, drawn from the tags
"final/<key>" (selection) and "check/<key>" (the check), so every figure is reproducible. Prints
one line per candidate and the chosen one. Works on a copy of the run folder (nothing is written).

    SGR_THREADS=1 .venv/bin/python bench/robust_final_selection.py RUN_DIR [K]
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np

from evolve.runs.checkpoint import load_checkpoint
from evolve.runs.experiment import Experiment
from evolve.runs.rundir import RunDir


def main(run_dir: Path, k: int = 32, top: int = 16) -> None:
    run = RunDir(run_dir)
    cfg = run.config()
    if not cfg.get("robust"):
        sys.exit(f"{run_dir} was not scored by robust evaluation (its config has no robust key)")
    state = load_checkpoint(run, cfg)
    if state is None:
        sys.exit(f"{run_dir} has no checkpoint")
    exp = Experiment(run, cfg, state=state, quiet=True, workers=1)
    try:
        search, problem = exp.search, exp.problem
        elites = sorted(((key, g) for key, g in search.population.items() if g.fitness is not None),
                        key=lambda kv: -kv[1].fitness)[:top]
        best = search.best
        cands = [(str(key), g, g.fitness) for key, g in elites]
        cands.append((f"best-ever/{best['key']}", best["genome"], best["fitness"]))
        phenotypes = [search.decode(g) for _, g, _ in cands]

        def score(robust: dict | None, prefix: str) -> np.ndarray:
            problem.cfg = {**cfg, "robust": robust}
            return np.asarray(problem.evaluate(phenotypes, [f"{prefix}/{name}" for name, _, _ in cands])[0])

        robust = {**cfg["robust"], "episodes": k, "statistic": "mean"}
        sel, chk, nom = score(robust, "final"), score(robust, "check"), score(None, "nominal")
        for (name, _, recorded), s, c, n in zip(cands, sel, chk, nom, strict=True):
            print(f"{name:>16}  recorded {recorded:7.3f}  selection {s:7.3f}  check {c:7.3f}  "
                  f"nominal {n:7.3f}")
        i = int(np.argmax(sel))
        print(f"chosen {cands[i][0]}: selection {sel[i]:.3f}, check {chk[i]:.3f} "
              f"({chk[i] / sel[i]:.0%} of it), nominal {nom[i]:.3f}")
    finally:
        exp.close()


if __name__ == "__main__":
    if len(sys.argv) < 2:
        sys.exit("usage: robust_final_selection.py RUN_DIR [K]")
    main(Path(sys.argv[1]), int(sys.argv[2]) if len(sys.argv) > 2 else 32)
