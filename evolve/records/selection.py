"""The words of a champion record's `selection` block (evolve/runs/final_selection.py writes it):
what chose the champion (`describe`), why it is the one (`explain`), what its test means
(`test_words`) and why that test and the champion's verdict can differ (`selection_and_verdict`).
They read the record alone, so the console, `sgr select-champion` and `sgr explain` say the same."""

from __future__ import annotations

import math

from evolve.records import verdict as verdict_rule


def passes(row: dict) -> bool:
    """Whether a selection record (or one candidate's row) passed the selection's test (`choose`);
    records written before the word kept it as "holds"."""
    return bool(row["passes"] if "passes" in row else row["holds"])


def describe(champ: dict) -> str:
    """One line on a chosen champion (the console's and `sgr select-champion`'s): what chose it, on
    which episodes, and what its figure is; the figures themselves are the headline's line and
    `sgr explain`'s."""
    sel = champ["selection"]
    confirm = sel.get("confirm", 0)
    n = len(sel["candidates"])
    chose = f"{sel['episodes']}{f' + {confirm}' if confirm else ''} perturbed episodes each"
    if "holdout" in sel:  # the fitness is a held-out score (older records: the score or confirmation)
        figure = (f"its figure is the {sel['statistic']} of {sel['holdout']} fresh episodes that took no "
                  "part in choosing it")
    else:
        figure = f"its figure is its score (the {sel['statistic']} of the episodes that chose it)"
    sized = sel.get("sized") or {}
    cost = (f"; {sized['episodes']} episodes in all, sized for the run's {sized['run_episodes']}"
            if sized.get("auto") else "")
    return (f"genome {champ['genome']['key']}, chosen among {n} candidates by {chose}; {figure}"
            f"{'' if passes(sel) else _none_passed(sel)}{cost}; the best-ever genome "
            f"{sel['best_ever']['key']} is kept in {sel['best_ever']['file']}")


def _rank_key(sel: dict, row: dict) -> float:
    """A candidate's value by the selection's rank (`choose`)."""
    if sel.get("rank") == "min":
        return row["score"] if math.isnan(row["nominal"]) else min(row["score"], row["nominal"])
    if sel.get("rank") == "pooled" and "confirmed" in row:
        w, c = sel["episodes"], sel["confirm"]
        return (w * row["score"] + c * row["confirmed"]) / (w + c)
    return row["score"]


def _rank_name(sel: dict) -> str:
    if sel.get("rank") == "min":
        return "the worse of score and exact return"
    if sel.get("rank") == "pooled" and sel.get("confirm"):
        return "the mean of all its perturbed episodes"
    return "score"


def _misses(sel: dict, row: dict) -> str:
    """Why a candidate fails the selection's test, in words: which noisy figure falls outside the
    tolerance."""
    tol, nominal = sel["tolerance"], row["nominal"]
    for name, value in (("", row["score"]), (" (its confirmation)", row.get("confirmed"))):
        if value is not None and not verdict_rule.clears(value, nominal, tol):  # `choose`'s comparison
            return (f"{value:.4g} under noise{name} is outside the {100 * tol:g} % tolerance of its "
                    f"noise-free {nominal:.4g}")
    return f"its noise-free return {nominal} is not finite"


def _none_passed(sel: dict) -> str:
    """describe's words for a selection that no candidate passed."""
    return (f" (no candidate passed the selection's test: each fell more than {100 * sel['tolerance']:g} % "
            "below its exact return on the episodes that chose it)")


def test_words(sel: dict) -> str:
    """The selection's test in words (`choose`): what "passes" means for this record."""
    confirm = sel.get("confirm", 0)
    on = f"{sel['episodes']}{f' + {confirm}' if confirm else ''} perturbed episodes that chose it"
    return (f"its {sel['statistic']} return on the {on} is within {100 * sel['tolerance']:g} % of its "
            "exact return")


def selection_and_verdict(sel: dict, h: verdict_rule.Verdict) -> str:
    """Why final selection's test and the champion's verdict (`h`) differ: comparisons of one kind
    (`verdict.clears`) on different episodes, at their own tolerances."""
    verdict_test = (f"its mean return on {h.replays} {h.episodes} is within "
                    f"{100 * verdict_rule.TOLERANCE:.0f} % of its exact return")
    if passes(sel):
        return (f"why it passed final selection yet is knife-edge: the selection's test ({test_words(sel)}) "
                f"and the verdict ({verdict_test}) judge different episodes; those that chose it "
                "flattered it (the winner's curse), the held-out ones did not")
    stricter = ("is stricter than" if sel["tolerance"] < verdict_rule.TOLERANCE
                else "judges other episodes than")
    return (f"why no candidate passed final selection yet the champion holds: the selection's test "
            f"({test_words(sel)}) {stricter} the verdict ({verdict_test})")


def explain(champ: dict) -> str:
    """One line on why the champion is the one it is: whether it passes the selection's test and
    ranks first, and what became of the best-ever genome (dropped for failing, or ranked below)."""
    sel = champ["selection"]
    rows = {r["key"]: r for r in sel["candidates"]}
    key = champ["genome"]["key"]
    me = rows[key]
    passing = [r for r in sel["candidates"] if passes(r)]
    how = _rank_name(sel)
    if passes(sel):
        why = (f"it passes the selection's test and ranks first among the {len(passing)} of {len(rows)} "
               f"candidates that pass by {how} ({_rank_key(sel, me):.4g})")
    else:
        why = (f"no candidate passes the selection's test, so it ranks first of all {len(rows)} by {how} "
               f"({_rank_key(sel, me):.4g})")
    b = sel["best_ever"]
    if b["key"] == key:
        return f"why: {why}; it is the best-ever genome (recorded {b['fitness']:.4g})"
    row = rows.get(b["key"])
    if row is None:
        return f"why: {why}; best-ever {b['fitness']:.4g} was not a candidate"
    if passes(sel) and not passes(row):
        fate = f"best-ever {b['fitness']:.4g} dropped: {_misses(sel, row)}"
    else:
        fate = f"best-ever {b['fitness']:.4g} ranks below: {_rank_key(sel, row):.4g} by {how}"
        if not passes(row):
            fate += f", and fails the test: {_misses(sel, row)}"
    return f"why: {why}; {fate}"
