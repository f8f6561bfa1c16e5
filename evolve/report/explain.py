"""`sgr explain RUN`: the story of a run's champion in plain words: which figure to quote, how the
champion was chosen and on which episodes, and what every number of its champion.json is.

Why: one run's champion carries up to five figures (its fitness, final selection's score,
confirmation and exact return, the best-ever record) and a verdict; each answers another
question. The console and `sgr report` show one of them, the headline (evolve/records/verdict.py,
"One headline per champion"); this says what the others are, from the record alone (it simulates
nothing, so it is instant and reads any folder as data).
"""

from __future__ import annotations

import math
from pathlib import Path

from evolve.records import verdict as verdict_rule
from evolve.records.rundir import RunDir
from tsim.errors import SgrError


def _noise(robust: dict | None) -> str:
    """A `robust` mapping's perturbation in words."""
    if not robust:
        return "no noise (one exact episode)"
    kind, scale = robust.get("action_noise", "uniform"), float(robust.get("action_scale", 0))
    return verdict_rule.noise_words(kind, scale, float(robust.get("offset", 0) or 0))


def _evolved_under(raw: dict) -> str:
    """How the run scored its genomes, from its config.yaml as written."""
    robust = raw.get("robust")
    if not isinstance(robust, dict):
        return "scored by one exact, noise-free episode each (the paper's nominal evaluation)"
    k = robust.get("episodes", 1)
    words = (f"scored under {_noise(robust)} action noise, {k} episode{'s' if k != 1 else ''} per genome "
             "and generation")
    if robust.get("accumulate"):
        words += "; a survivor's fitness is the mean of its scores over every generation it was scored in"
    return words


def explain_run(run_dir: str | Path) -> str:
    """The story of the champion of `run_dir` (a run folder with champion.json), several short
    paragraphs for a person.

    Raises:
        SgrError: the folder has no champion.json, or it is not a record.
    """
    run = RunDir(run_dir)
    champ = run.champion()
    try:
        raw = run.config() or {}
    except SgrError:  # a folder without a readable config.yaml still has a story to tell
        raw = {}
    raw = raw if isinstance(raw, dict) else {}
    out = []
    gens, pop = raw.get("generations"), raw.get("pop_size")
    size = f", {gens} generations of {pop} genomes" if gens and pop else ""
    out.append(f"{run.path}: {champ.get('task', '?')}, method {champ.get('method', raw.get('method', '?'))}, "
               f"seed {raw.get('seed', '?')}{size}; genomes were {_evolved_under(raw)}.")
    h = verdict_rule.from_headline(champ.get("headline"))
    fitness = float(champ.get("fitness", math.nan))
    if h is not None:
        out.append(
            f"The figure to quote: mean return {h.noisy_mean:.4f} (sd {h.sd:.4f}, worst {h.worst:.4f}) over "
            f"{h.replays} {h.episodes} under {h.noise}. Verdict: {h.label}, because that mean is "
            f"{'at least' if h.holds else 'less than'} {100 * (1 - verdict_rule.TOLERANCE):.0f} % of the "
            f"return of its exact, noise-free episode, {h.nominal:.4f}. The exact episode is one draw "
            "of a chaotic system; the mean under noise is what the robot does.")
    else:
        out.append(f"The figure to quote: its fitness, {fitness:.4f} (this record has no headline: it was "
                   "written before sgr recorded one, or the run has not finished; `sgr select-champion` "
                   "or resuming the run records it).")
    sel = champ.get("selection")
    lines = ["What each number of champion.json is:"]
    if sel is not None:
        from evolve.records.selection import explain, passes, selection_and_verdict, test_words

        conf = sel.get("confirm", 0)
        out.append(
            f"How it was chosen: at the run's end, final selection scored {len(sel['candidates'])} "
            f"candidates (the best final elites and the best-ever genome) by {sel['episodes']} fresh "
            f"perturbed episodes each{f' and {conf} more to confirm' if conf else ''}. A candidate passes "
            f"the selection's test when {test_words(sel)}; "
            f"{'it' if passes(sel) else 'no candidate'} passed. Why this one: "
            f"{explain(champ)[len('why: '):]}.")
        if h is not None and passes(sel) != h.holds:
            why = selection_and_verdict(sel, h)
            out.append(why[0].upper() + why[1:] + ".")
        held = "held-out " if "holdout" in sel else ""
        lines += [
            f"- fitness {fitness:.4f}: the {sel['statistic']} of the {sel.get('holdout', sel['episodes'])} "
            f"{held}episodes (the headline's mean, when the statistic is the mean); "
            "`rescore_champion(run)` reproduces it from the file",
            f"- selection.score {sel['score']:.4f}: its {sel['statistic']} over the {sel['episodes']} "
            "episodes that chose it (biased upward: the best of several noisy scores)"]
        if "confirmed" in sel:
            lines.append(f"- selection.confirmed {sel['confirmed']:.4f}: over the {conf} confirmation "
                         "episodes (it ranked the candidates too, so it is biased as well)")
        lines.append(f"- selection.nominal {sel['nominal']:.4f}: its exact episode, no noise (what "
                     "`load_champion(run).rollout()` returns)")
        b = sel["best_ever"]
        lines.append(f"- best-ever {b['fitness']:.4f} (genome {b['key']}, {b['file']}): the highest "
                     "fitness a genome had during the run, a maximum over many noisy scores")
    else:
        ev = champ.get("evaluation") or {}
        if ev.get("robust") is None:
            out.append("How it was chosen: it is the genome with the best fitness of the run, each genome "
                       "scored by its exact episode.")
            lines.append(f"- fitness {fitness:.4f}: the return of its exact, noise-free episode (what "
                         "`load_champion(run).rollout()` returns)")
        else:
            out.append("How it was chosen: it is the genome with the best fitness of the run (no final "
                       "selection): a maximum over noisy scores, biased upward.")
            lines.append(f"- fitness {fitness:.4f}: its score as evolution recorded it, under "
                         f"{_noise(ev['robust'])}; `rescore_champion(run)` reproduces it")
    if h is not None:
        lines.append(f"- headline.return {h.noisy_mean:.4f}, headline.sd {h.sd:.4f}, headline.worst "
                     f"{h.worst:.4f}: the {h.replays} {h.episodes} above; headline.exact {h.nominal:.4f}: "
                     "its exact episode")
    lines.append(f"- champion.gif and `sgr report`'s ±{verdict_rule.EPS:g} column: {verdict_rule.REPLAYS} "
                 f"replays under uniform ±{verdict_rule.EPS:g}, the GIF showing the median one "
                 "(`sgr render RUN --exact`: the exact episode)")
    out.append("\n".join(lines))
    return "\n\n".join(out)
