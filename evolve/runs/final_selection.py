"""Choosing a run's champion afresh at its end: among the final elites and the best-ever genome, by
many new perturbed episodes, keeping only genomes that pass its test: whose exact episode is not far
better than their perturbed ones.

Why: a run's best-ever record is the maximum of thousands of noisy scores, so under robust
evaluation it keeps a lucky one (docs/RESULTS.md, "Champions that hold": Walker-v0 champions kept
72-94 % of their recorded fitness). Scoring a few candidates once more by K fresh episodes gives a
fitness their replays keep, and a genome whose exact (noise-free) episode is far better than its
perturbed ones is a knife-edge trajectory, not a gait: `tolerance` drops it. Among the rest the
champion must do well both ways, as its recorded fitness says (under noise) and as a user first
sees it (its exact episode, e.g. in gymnasium): the best worse-of-the-two wins.

The rule (`choose`): every candidate gets a score (the `statistic` of K episodes perturbed as the
run's `robust` key says, uniform(+-1e-3) on a nominal run; episode k of genome g is drawn from the
tag "final/<g>") and its nominal return; a candidate *passes* when its score is at least its nominal
return minus `tolerance` x |nominal return| (`verdict.clears`, the verdict's comparison at the
selection's own tolerance). The champion is the candidate that passes with the
highest min(score, nominal return) (`rank: min`; `rank: score`, the highest score; `rank:
pooled`, the highest mean of the score and the confirmation below, weighted by their episodes), or
the highest of all when none passes (champion.json says so). Its `fitness` is the held-out
score below.
Why `pooled` in the packaged configs: a chaotic gait's exact episode is one draw from the noise's
spread, so `min` mixes a one-episode estimate into the choice; on the robust-fast sweep `pooled`
chose champions that return more under the noise they were evolved for (docs/RESULTS.md), at the
price of exact episodes that may return less.

`confirm: N` (0: off) judges the test on episodes that did not choose: every candidate is scored
again by N fresh perturbed episodes (tag "final-confirm/<g>"), and a candidate passes only when both
its score and this confirmation clear the tolerance. Why: the champion is the maximum over
candidates of noisy scores, so its own score is biased upward (the winner's curse) and the test
passes on luck. On the robust-fast sweep (docs/RESULTS.md) 4 of the 12 champions chosen
without it kept under 90 % in 20 replays on other noise; 1 of 12 with it.

The headline (`holdout`): the champion's `fitness` (the figure the console, champion.json and `sgr
report` show) is the `statistic` of `holdout` fresh perturbed episodes of the chosen genome alone
(tag "final-holdout/<g>"), episodes that took no part in choosing it; `rescore_champion`
reproduces it from champion.json. Why: with `rank: pooled` the confirmation also ranks, so it
carries the winner's curse too: on the bigger-bodies study's Climber-v2 champions the recorded
confirmation overstated 20 fresh noisy replays by 19-67 % on 6 of 9. The score and the
confirmation stay in `selection` (`score`, `confirmed`). champion.json's `headline` (`record_headline`)
is these held-out episodes again with their sd and the verdict (evolve/records/verdict.py): the one
figure every place shows.

How many episodes (`sized`): `candidates`, `episodes`, `confirm` and `holdout` may be `auto` (the
default of all but `confirm`, whose default 0 is off). An explicit number is used as it is. The
`auto` ones scale with the run's length: the selection may simulate at most `SHARE` (a fifth) of
the episodes the run itself asks for (generations x pop_size x the robust key's episodes, 1 for a
nominal run), counted as (candidates + 1) x (episodes + 1 + confirm) + holdout (the +1s: the
best-ever genome, the exact episode). Each `auto` count is its maximum (`MAXIMA`: 16 candidates,
32 episodes, 32 confirm episodes; `holdout` follows `episodes`) times one common factor, the
largest multiple of 1/64 that fits the budget, rounded down and never below its floor (`FLOORS`:
2 candidates, 8 episodes), so a long run gets the maxima and a very short one the floors even
past the budget. The packaged `quick` config (20 generations, pop 48, one episode each: 960)
gets 6 candidates, 12 + 12 episodes and 12 held-out ones, 187 episodes. The sizes used are
recorded in champion.json's `selection` (with `sized`: the budget and which keys were `auto`).
Why: a fixed 16 x (32 + 32) took 43 of a 2-generation 10x10 run's 61 s.

The candidates are read from the state after the last generation, which is the last checkpoint, so
the choice made at a run's end and `sgr select-champion` on the finished run
(`evolve.runs.experiment.select_finished_run`) are the same, and making it again changes nothing.
champion.json then records the chosen genome, its held-out score as `fitness` and an `evaluation`
that `rescore_champion` reproduces exactly, plus a `selection` block (every candidate's score and
nominal return); the best-ever record is kept as champion-best-ever.json. `describe` and `explain`
are the console's lines: what was chosen, and why the champion is the one it is (why the
best-ever genome was dropped or ranked below).
"""

from __future__ import annotations

import math

import numpy as np

from evolve.config import (
    AUTO,
    COUNTS,
    SHARE,
    FinalSelection,
    not_for,
    run_episodes,
)
from evolve.records import verdict as verdict_rule
from evolve.records.champion import archive_place, best_ever_record, champion_record
from evolve.records.files import atomic_write, record_json
from evolve.records.replay import record_headline
from evolve.records.selection import describe, explain, passes  # noqa: F401  (the console's words)
from tsim.errors import SgrError

BEST_EVER_FILE = "champion-best-ever.json"
TAG = "final"


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
    """The chosen candidate's index and which candidates pass (module docstring); with `confirmed`
    (the confirmation's scores) a candidate passes when both its score and its confirmation do.
    `rank: pooled` ranks by the score and the confirmation averaged with `weights` (their episode
    counts): every perturbed episode a candidate got."""
    passing = verdict_rule.clears(scores, nominal, tolerance) & np.isfinite(nominal)
    if confirmed is not None:
        passing &= verdict_rule.clears(confirmed, nominal, tolerance)
    pool = np.flatnonzero(passing) if passing.any() else np.flatnonzero(np.isfinite(scores))
    if len(pool) == 0:
        raise SgrError("no candidate has a finite score")
    if rank == "min":
        key = np.fmin(scores, nominal)  # fmin: a nan nominal leaves the score
    elif rank == "pooled" and confirmed is not None:
        key = (weights[0] * scores + weights[1] * confirmed) / (weights[0] + weights[1])
    else:
        key = scores
    return int(pool[np.argmax(key[pool])]), passing


def select_champion(exp, settings: FinalSelection) -> dict:
    """Score the candidates of `exp` (an `Experiment` at its run's end), write champion.json and
    champion-best-ever.json, and return the new champion record. "auto" counts are sized by the
    run's length first (`FinalSelection.sized`)."""
    cfg, search, problem = exp.cfg, exp.search, exp.problem
    if type(problem).reevaluate_elites:
        raise SgrError(f"final_selection {not_for(cfg.method)}")
    if search.best is None:
        raise SgrError(f"{exp.run.path} has no champion to choose from yet")
    asked = settings
    settings = settings.sized(run_episodes(cfg))
    cands = candidates(search, settings.candidates)
    phenotypes = [search.decode(g) for _, g in cands]
    robust = settings.robust(cfg.robust)
    tags = [f"{TAG}/{k}" for k, _ in cands]
    simulated = 0  # episodes, as the problem counts them (fewer elites than asked may exist)

    def scored(scoring: dict | None, which: list, which_tags: list[str]) -> np.ndarray:
        nonlocal simulated
        with problem.scored_with(scoring):
            returns, episodes = problem.evaluate(which, which_tags)
        simulated += int(episodes)
        return np.asarray(returns, dtype=float)

    scores = scored(robust.to_json(), phenotypes, tags)
    nominal = scored(None, phenotypes, tags)
    confirmed = None
    if settings.confirm:
        confirm_tags = [f"{TAG}-confirm/{k}" for k, _ in cands]
        confirmed = scored(settings.robust(cfg.robust, settings.confirm).to_json(), phenotypes, confirm_tags)
    i, passing = choose(scores, nominal, settings.tolerance, settings.rank, confirmed,
                      (settings.episodes, settings.confirm))
    # the headline: the chosen genome alone, on fresh episodes that took no part in the choice
    fit_robust = settings.robust(cfg.robust, settings.holdout)
    fit_tag = f"{TAG}-holdout/{cands[i][0]}"
    fit = float(scored(fit_robust.to_json(), [phenotypes[i]], [fit_tag])[0])
    best = search.best
    best_ever = best_ever_record(cfg, problem, best)
    genome = cands[i][1]
    champ = champion_record(cfg, problem, genome, phenotypes[i], fit, search.generation,
                            {"robust": fit_robust.to_json(), "seed": cfg.seed, "tag": fit_tag})
    entry_of_key = getattr(search, "entry_of_key", None)  # an archive's: the champion's cell
    champ.update(archive_place(entry_of_key(cands[i][0]) if entry_of_key else None))
    rows = [{"key": k, "recorded": float(g.fitness) if g.fitness is not None else None,
             "score": float(s), "nominal": float(n), "passes": bool(h)}
            for (k, g), s, n, h in zip(cands, scores, nominal, passing, strict=True)]
    if confirmed is not None:
        for row, c in zip(rows, confirmed, strict=True):
            row["confirmed"] = float(c)
    champ["selection"] = {
        **settings.to_json(), "passes": bool(passing[i]), "nominal": float(nominal[i]),
        "score": float(scores[i]),
        **({"confirmed": float(confirmed[i])} if confirmed is not None else {}),
        "sized": {"share": SHARE, "run_episodes": run_episodes(cfg),
                  "auto": [k for k in COUNTS if getattr(asked, k) == AUTO],
                  "episodes": simulated},
        "best_ever": {"key": best["key"], "fitness": best["fitness"], "file": BEST_EVER_FILE},
        "candidates": rows}
    atomic_write(exp.run.path / BEST_EVER_FILE, record_json(best_ever).encode(), inside=exp.run.path)
    exp.run.write_champion(champ)
    return record_headline(exp.run)

