"""Choosing a run's champion afresh at its end: among the final elites and the best-ever genome, by
many new perturbed episodes, keeping only genomes that hold: whose exact episode is not far better
than their perturbed ones.

Why: a run's best-ever record is the maximum of thousands of noisy scores, so under robust
evaluation it keeps a lucky one (docs/RESULTS.md, "Champions that hold": Walker-v0 champions kept
72-94 % of their recorded fitness). Scoring a few candidates once more by K fresh episodes gives a
fitness their replays keep, and a genome whose exact (noise-free) episode is far better than its
perturbed ones is a knife-edge trajectory, not a gait: `tolerance` drops it. Among the rest the
champion must do well both ways, as its recorded fitness says (under noise) and as a user first
sees it (its exact episode, e.g. in gymnasium): the best worse-of-the-two wins.

The rule (`choose`): every candidate gets a score (the `statistic` of K episodes perturbed as the
run's `robust` key says, uniform(+-1e-3) on a nominal run; episode k of genome g is drawn from the
tag "final/<g>") and its nominal return; a candidate holds when its score is at least its nominal
return minus `tolerance` x |nominal return|. The champion is the candidate that holds with the
highest min(score, nominal return) (`rank: min`; `rank: score`, the highest score; `rank:
pooled`, the highest mean of the score and the confirmation below, weighted by their episodes), or
the highest of all when none holds (champion.json says so). Its `fitness` is its score.
Why `pooled` in the packaged configs: a chaotic gait's exact episode is one draw from the noise's
spread, so `min` mixes a one-episode estimate into the choice; on the robust-fast sweep `pooled`
chose champions that return more under the noise they were evolved for (docs/RESULTS.md), at the
price of exact episodes that may return less.

`confirm: N` (0: off) judges the hold on episodes that did not choose: every candidate is scored
again by N fresh perturbed episodes (tag "final-confirm/<g>"), a candidate holds only when both its
score and this confirmation clear the tolerance, and the champion's `fitness` is its confirmation
(evaluation tag "final-confirm/<g>", which `rescore_champion` reproduces). Why: the champion is the
maximum over candidates of noisy scores, so its own score is biased upward (the winner's curse) and
the hold test passes on luck. On the robust-fast sweep (docs/RESULTS.md) 4 of the 12 champions
chosen without it kept under 90 % in 20 replays on other noise; 1 of 12 with it.

The candidates are read from the state after the last generation, which is the last checkpoint, so
the choice made at a run's end and `sgr select-champion` on the finished run
(`evolve.runs.experiment.select_finished_run`) are the same, and making it again changes nothing.
champion.json then records the chosen genome, its score as `fitness` and an `evaluation` that
`rescore_champion` reproduces exactly, plus a `selection` block (every candidate's score and
nominal return); the best-ever record is kept as champion-best-ever.json.
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass

import numpy as np

from evolve.rollout.robust import STATISTICS, Robust, config_dataclass
from evolve.runs.champion import best_ever_record, champion_record
from evolve.runs.files import atomic_write, record_json
from tsim.errors import SgrError

BEST_EVER_FILE = "champion-best-ever.json"
TAG = "final"
RANKS = ("min", "score", "pooled")


@dataclass(frozen=True)
class FinalSelection:
    """The `final_selection` config key (null: the champion is the best-ever genome)."""
    candidates: int = 16  # the top final elites by recorded fitness, plus the best-ever genome
    episodes: int = 32
    statistic: str = "mean"
    tolerance: float = 0.05  # holds: score >= nominal return - tolerance x |nominal return|
    rank: str = "min"  # among those that hold: min(score, nominal return), "score" alone, or "pooled"
    confirm: int = 0  # > 0: the hold judged again, and the fitness taken, on this many fresh episodes

    def to_json(self) -> dict:
        """The config mapping (every key)."""
        return asdict(self)

    def robust(self, run_robust: dict | None, episodes: int | None = None) -> Robust:
        """How candidates are scored: the run's perturbation (uniform(+-1e-3) on a nominal run),
        this selection's episodes (or `episodes`: the confirmation's) and statistic, no
        re-evaluation."""
        base = Robust.from_config(run_robust) or Robust()
        return Robust(episodes or self.episodes, base.action_noise, base.action_scale, base.offset,
                      self.statistic)

    @classmethod
    def from_config(cls, raw: object, source: str = "config") -> FinalSelection | None:
        """The checked mapping; None stays None. ValueError naming `source` and the key."""
        if raw is None:
            return None
        name = f"{source}: key 'final_selection"
        sel = config_dataclass(cls, raw, name)
        if not isinstance(sel.confirm, int) or isinstance(sel.confirm, bool) or sel.confirm < 0:
            raise SgrError(f"{name}.confirm' must be an int >= 0, got {sel.confirm!r}")
        for key in ("candidates", "episodes"):
            v = getattr(sel, key)
            if not isinstance(v, int) or isinstance(v, bool) or v < 1:
                raise SgrError(f"{name}.{key}' must be an int >= 1, got {v!r}")
        try:
            Robust.from_config({"statistic": sel.statistic}, source)
        except ValueError:
            raise SgrError(f"{name}.statistic' must be one of {', '.join(STATISTICS)}, "
                           f"got {sel.statistic!r}") from None
        h = sel.tolerance
        if isinstance(h, bool) or not isinstance(h, int | float) or not (0 <= h <= 1):
            raise SgrError(f"{name}.tolerance' must be a number in [0, 1], got {h!r}")
        if sel.rank not in RANKS:
            raise SgrError(f"{name}.rank' must be one of {', '.join(RANKS)}, got {sel.rank!r}")
        return cls(sel.candidates, sel.episodes, sel.statistic, float(h), sel.rank, sel.confirm)


def not_for(method: str) -> str:
    """Why a method whose evaluation changes state (`Problem.reevaluate_elites`) has no final
    selection."""
    return (f"does not apply to method {method!r}: its evaluation evolves each body's controllers "
            "again, so a candidate has no fixed robot to score")


def candidates(search, n: int) -> list[tuple[int, object]]:
    """(key, genome) of the `n` best elites of the search's current population (genomes carrying a
    fitness: the elites kept from the last generation; ties by key) and of the best-ever genome
    when it is not among them, in that order."""
    elites = sorted(((k, g) for k, g in search.population.items()
                     if g.fitness is not None and math.isfinite(g.fitness)),
                    key=lambda kv: (-kv[1].fitness, kv[0]))[:n]
    best = search.best
    if best is not None and all(k != best["key"] for k, _ in elites):
        elites.append((best["key"], best["genome"]))
    return elites


def choose(scores: np.ndarray, nominal: np.ndarray, tolerance: float,
           rank: str = "min", confirmed: np.ndarray | None = None,
           weights: tuple[int, int] = (1, 1)) -> tuple[int, np.ndarray]:
    """The chosen candidate's index and which candidates hold (module docstring); with `confirmed`
    (the confirmation's scores) a candidate holds when both its score and its confirmation do.
    `rank: pooled` ranks by the score and the confirmation averaged with `weights` (their episode
    counts): every perturbed episode a candidate got."""
    def clears(x: np.ndarray) -> np.ndarray:
        with np.errstate(invalid="ignore"):
            return (x >= nominal - tolerance * np.abs(nominal)) & np.isfinite(x)

    holds = clears(scores) & np.isfinite(nominal)
    if confirmed is not None:
        holds &= clears(confirmed)
    pool = np.flatnonzero(holds) if holds.any() else np.flatnonzero(np.isfinite(scores))
    if len(pool) == 0:
        raise SgrError("no candidate has a finite score")
    if rank == "min":
        key = np.fmin(scores, nominal)  # fmin: a nan nominal leaves the score
    elif rank == "pooled" and confirmed is not None:
        key = (weights[0] * scores + weights[1] * confirmed) / (weights[0] + weights[1])
    else:
        key = scores
    return int(pool[np.argmax(key[pool])]), holds


def select_champion(exp, settings: FinalSelection) -> dict:
    """Score the candidates of `exp` (an `Experiment` at its run's end), write champion.json and
    champion-best-ever.json, and return the new champion record."""
    cfg, search, problem = exp.cfg, exp.search, exp.problem
    if type(problem).reevaluate_elites:
        raise SgrError(f"final_selection {not_for(cfg['method'])}")
    if search.best is None:
        raise SgrError(f"{exp.run.path} has no champion to choose from yet")
    cands = candidates(search, settings.candidates)
    phenotypes = [search.decode(g) for _, g in cands]
    robust = settings.robust(cfg.get("robust"))
    tags = [f"{TAG}/{k}" for k, _ in cands]
    with problem.scored_with(robust.to_json()):
        scores = np.asarray(problem.evaluate(phenotypes, tags)[0], dtype=float)
    with problem.scored_with(None):
        nominal = np.asarray(problem.evaluate(phenotypes, tags)[0], dtype=float)
    confirmed = None
    fit_robust, fit_tags, fit = robust, tags, scores  # the champion's fitness and how it is scored again
    if settings.confirm:
        fit_robust = settings.robust(cfg.get("robust"), settings.confirm)
        fit_tags = [f"{TAG}-confirm/{k}" for k, _ in cands]
        with problem.scored_with(fit_robust.to_json()):
            fit = confirmed = np.asarray(problem.evaluate(phenotypes, fit_tags)[0], dtype=float)
    i, holds = choose(scores, nominal, settings.tolerance, settings.rank, confirmed,
                      (settings.episodes, settings.confirm))
    best = search.best
    best_ever = best_ever_record(cfg, problem, best)
    genome = cands[i][1]
    champ = champion_record(cfg, problem, genome, phenotypes[i], float(fit[i]), search.generation,
                            {"robust": fit_robust.to_json(), "seed": cfg["seed"], "tag": fit_tags[i]})
    rows = [{"key": k, "recorded": float(g.fitness) if g.fitness is not None else None,
             "score": float(s), "nominal": float(n), "holds": bool(h)}
            for (k, g), s, n, h in zip(cands, scores, nominal, holds, strict=True)]
    if confirmed is not None:
        for row, c in zip(rows, confirmed, strict=True):
            row["confirmed"] = float(c)
    champ["selection"] = {
        **settings.to_json(), "holds": bool(holds[i]), "nominal": float(nominal[i]),
        "score": float(scores[i]),
        "best_ever": {"key": best["key"], "fitness": best["fitness"], "file": BEST_EVER_FILE},
        "candidates": rows}
    atomic_write(exp.run.path / BEST_EVER_FILE, record_json(best_ever).encode())
    exp.run.write_champion(champ)
    return champ


def describe(champ: dict) -> str:
    """One line on a chosen champion (the console's and `sgr select-champion`'s)."""
    sel = champ["selection"]
    confirm = sel.get("confirm", 0)
    scored = (f"score {sel.get('score', champ['fitness']):.4f} ({sel['statistic']} of {sel['episodes']} "
              "perturbed episodes)")
    if confirm:
        scored += f", confirmed {champ['fitness']:.4f} by {confirm} fresh ones"
    return (f"champion genome {champ['genome']['key']} of {len(sel['candidates'])} candidates, "
            f"{scored}, nominal {sel['nominal']:.4f}"
            f"{'' if sel['holds'] else ' (no candidate held: each lost over tolerance x its nominal return)'}"
            "; best-ever "
            f"{sel['best_ever']['fitness']:.4f} kept in {sel['best_ever']['file']}")
