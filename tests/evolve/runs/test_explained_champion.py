"""Champions you can explain (#45): the end-of-run lines say why the champion is the one it is; its
headline fitness comes from episodes that took no part in choosing it; the verdict leads with the
return under noise; champion.gif is the median of the verdict's replays; final selection's episodes
scale with the run's length (at most a fifth of the quick run's) and explicit counts are kept."""

from __future__ import annotations

import json
import shutil
import statistics
from pathlib import Path

import numpy as np
import pytest
import yaml

from evolve.cli import main
from evolve.config import selection_episodes
from evolve.records import verdict
from evolve.records.replay import champion_gif, replay_champion, rescore_champion
from evolve.records.rundir import RunDir
from evolve.rollout.robust import episode_keys
from evolve.runs.final_selection import FinalSelection, explain, passes, run_episodes

ROBUST = {"episodes": 2, "action_noise": "uniform", "action_scale": 1e-2, "offset": 0.0,
          "statistic": "mean"}


@pytest.fixture(scope="module")
def finished(tmp_path_factory) -> tuple[Path, str]:
    """A tiny run chosen by `rank: pooled` with a confirmation, its GIF drawn; and its console."""
    import contextlib
    import io

    folder = tmp_path_factory.mktemp("explained")
    cfg = {"method": "sgr", "task": "Walker-v0", "generations": 3, "pop_size": 12, "seed": 5,
           "episode_steps": 40, "workers": 1, "checkpoint_every": 1, "robust": ROBUST,
           "final_selection": {"candidates": 4, "episodes": 6, "tolerance": 0.1, "rank": "pooled",
                               "confirm": 6, "holdout": 10}}
    (folder / "c.yaml").write_text(yaml.safe_dump(cfg))
    out = io.StringIO()
    with contextlib.redirect_stdout(out):
        assert main(["evolve", "--config", str(folder / "c.yaml"), "--out", str(folder / "run")]) == 0
    return folder / "run", out.getvalue()


def record(rows: list[dict], champion: int, best_ever: int, best_fitness: float, **sel) -> dict:
    """A champion.json of a selection over `rows` (key, score, nominal, holds[, confirmed])."""
    me = next(r for r in rows if r["key"] == champion)
    return {"fitness": 1.0, "genome": {"key": champion},
            "selection": {"episodes": 32, "confirm": 0, "statistic": "mean", "tolerance": 0.05,
                          "rank": "min", "holds": me["holds"], "nominal": me["nominal"],
                          "score": me["score"], "best_ever": {"key": best_ever, "fitness": best_fitness,
                                                              "file": "champion-best-ever.json"},
                          "candidates": rows, **sel}}


def test_a_best_ever_dropped_for_its_noisy_score_is_explained_with_its_numbers():
    """The issue's case: the best-ever (recorded 2.169) scores 2.02 under noise against 2.16 exact,
    more than 5 % below, so a genome scoring 1.137 is the champion; the line says so."""
    rows = [{"key": 3, "score": 1.137, "nominal": 1.15, "holds": True},
            {"key": 9, "score": 2.02, "nominal": 2.16, "holds": False}]
    line = explain(record(rows, 3, 9, 2.169))
    assert "best-ever 2.169 dropped: 2.02 under noise is outside the 5 % tolerance of its noise-free 2.16" \
        in line, line
    assert "it passes the selection's test and ranks first among the 1 of 2 candidates that pass" in line


def test_a_best_ever_that_fails_only_its_confirmation_or_ranks_below_is_explained():
    rows = [{"key": 3, "score": 1.5, "nominal": 1.5, "holds": True, "confirmed": 1.5},
            {"key": 9, "score": 2.0, "nominal": 2.0, "holds": False, "confirmed": 1.7}]
    line = explain(record(rows, 3, 9, 2.4, confirm=32, rank="pooled"))
    assert "best-ever 2.4 dropped: 1.7 under noise (its confirmation) is outside the 5 % tolerance" in line
    rows = [{"key": 3, "score": 1.5, "nominal": 1.5, "holds": True},
            {"key": 9, "score": 1.4, "nominal": 1.4, "holds": True}]
    line = explain(record(rows, 3, 9, 2.4))
    assert "best-ever 2.4 ranks below: 1.4 by the worse of score and exact return" in line, line
    assert "it is the best-ever genome" in explain(record(rows, 9, 9, 2.4))


@pytest.mark.slow
def test_the_end_of_run_lines_say_what_chose_the_champion_and_why(finished):
    run, console = finished
    champ = RunDir(run).champion()
    why = next(x for x in console.splitlines() if x.startswith("final selection why: "))
    assert why == f"final selection {explain(champ)}"
    sel = champ["selection"]
    best = next(c for c in sel["candidates"] if c["key"] == sel["best_ever"]["key"])
    if best["key"] == champ["genome"]["key"]:
        assert "it is the best-ever genome" in why
    else:
        assert ("dropped" if passes(sel) and not passes(best) else "ranks below") in why
    head = next(x for x in console.splitlines() if x.startswith("champion: "))
    assert head.startswith(f"champion: genome {champ['genome']['key']} of generation {champ['generation']}")
    h = verdict.from_headline(champ["headline"])  # the last line: the one figure, of the held-out episodes
    assert console.splitlines()[-1] == f"champion {h.line()}"
    assert h.noisy_mean == champ["fitness"] and h.replays == 10 and h.episodes == "held-out episodes"


@pytest.mark.slow
def test_the_headline_fitness_comes_from_episodes_that_did_not_choose(finished, tmp_path):
    """champion.json's fitness is scored on its own tag, 10 episodes whose noise keys meet none of
    the choosing episodes' (every candidate's score and confirmation); rescoring the record on the
    choosing tags gives the recorded score and confirmation, so those are the tags that chose."""
    run, _ = finished
    champ = RunDir(run).champion()
    sel, ev = champ["selection"], champ["evaluation"]
    key = champ["genome"]["key"]
    assert ev["tag"] == f"final-holdout/{key}" and ev["robust"]["episodes"] == 10
    assert rescore_champion(run) == champ["fitness"]
    held = set(np.concatenate([episode_keys(5, [ev["tag"]], e) for e in range(10)]).tolist())
    chose = {k for c in sel["candidates"] for tag in (f"final/{c['key']}", f"final-confirm/{c['key']}")
             for e in range(6) for k in episode_keys(5, [tag], e).tolist()}
    assert len(held) == 10 and len(chose) == 12 * len(sel["candidates"]) and not held & chose
    for tag, figure in ((f"final/{key}", sel["score"]), (f"final-confirm/{key}", sel["confirmed"])):
        copy = tmp_path / tag.replace("/", "-")
        shutil.copytree(run, copy)
        other = {**champ, "evaluation": {**ev, "tag": tag, "robust": {**ev["robust"], "episodes": 6}}}
        (copy / "champion.json").write_text(json.dumps(other))
        assert rescore_champion(copy) == figure
    assert champ["fitness"] not in (sel["score"], sel["confirmed"])


def test_the_verdict_line_leads_with_the_return_under_noise_and_puts_the_exact_episode_beside_it():
    returns = np.array([0.044, 0.30, 0.20, 0.26, 0.28])  # the baffling "592 % of 0.044"
    v = verdict.from_returns(returns)
    sd = statistics.stdev([0.30, 0.20, 0.26, 0.28])
    assert v.line() == (f"holds: mean return 0.260, sd {sd:.3f}, worst 0.200 over 4 replays under uniform "
                        "±0.001; exact episode 0.044")
    edge = verdict.from_returns(np.array([2.0, 1.0, 1.2]))
    assert edge.line().startswith("knife-edge: mean return 1.100, sd 0.141, worst 1.000 over 2 replays under")
    assert edge.line().endswith("exact episode 2.000 (the mean is more than 10 % below it)")


def test_the_median_replay_is_the_middle_of_the_noisy_returns():
    assert verdict.median_replay([9.0, 5.0, 1.0, 3.0, 2.0, 4.0]) == 3  # 1 2 [3] 4 5
    assert verdict.median_replay([0.0, 4.0, 1.0, 3.0, 2.0]) == 4  # 1 [2] 3 4: the lower middle
    assert verdict.median_replay([0.0, 5.0, 7.0, 5.0, 1.0]) == 1  # 1 [5 5] 7: of equal ones, the earlier


@pytest.mark.slow
def test_champion_gif_shows_the_median_replay_and_the_exact_episode_is_one_flag_away(finished, capsys):
    run, console = finished
    returns = replay_champion(run, verdict.REPLAYS, verdict.EPS)
    noisy = returns[1:]
    i = int(np.flatnonzero(noisy == sorted(noisy)[(len(noisy) - 1) // 2])[0]) + 1
    median = champion_gif(run, run / "median.gif", replay=i)
    assert (run / "champion.gif").read_bytes() == median.read_bytes()  # the run's own GIF
    assert "champion.gif: a typical perturbed episode (the median of 20 replays)" in console
    assert main(["render", str(run), "--exact"]) == 0
    assert f"wrote {run / 'champion-exact.gif'}: the exact episode" in capsys.readouterr().out
    exact = champion_gif(run, run / "exact.gif", replay=0)
    assert (run / "champion-exact.gif").read_bytes() == exact.read_bytes() != median.read_bytes()
    assert main(["render", str(run), "--out", str(run / "again.gif")]) == 0
    line = capsys.readouterr().out
    assert (run / "again.gif").read_bytes() == median.read_bytes()
    assert "the median of 20 replays" in line and f"replay {i}: return {returns[i]:.4f}" in line, line


def test_the_quick_run_spends_at_most_a_fifth_of_its_episodes_choosing(repo_root):
    """configs/sgr/quick.yaml asks for 20 x 48 one-episode evaluations; its final selection's
    (candidates + 1) x (episodes + 1 + confirm) + holdout fits in 192."""
    raw = yaml.safe_load((repo_root / "configs" / "sgr" / "quick.yaml").read_text())
    assert raw["generations"] * raw["pop_size"] * raw["robust"]["episodes"] == run_episodes(raw) == 960
    sized = FinalSelection.from_config(raw["final_selection"]).sized(run_episodes(raw))
    counts = sized.to_json()
    total = (counts["candidates"] + 1) * (counts["episodes"] + 1 + counts["confirm"]) + counts["holdout"]
    assert total == selection_episodes(counts) <= 960 / 5
    assert counts["candidates"] >= 2 and counts["episodes"] >= 8 and counts["confirm"] >= 8
    assert counts["holdout"] == counts["episodes"]


def test_auto_counts_grow_with_the_run_and_explicit_ones_are_kept():
    auto = FinalSelection.from_config({"confirm": "auto", "rank": "pooled"})
    long = auto.sized(250 * 128).to_json()  # a packaged paper-length run: the maxima
    assert (long["candidates"], long["episodes"], long["confirm"], long["holdout"]) == (16, 32, 32, 32)
    tiny = auto.sized(2 * 10).to_json()  # the floors, even past the budget
    assert (tiny["candidates"], tiny["episodes"], tiny["confirm"], tiny["holdout"]) == (2, 8, 8, 8)
    sizes = [auto.sized(n).to_json()["episodes"] for n in (500, 1000, 2000, 4000, 8000)]
    assert sizes == sorted(sizes) and sizes[0] < sizes[-1]
    mine = FinalSelection.from_config({"candidates": 8, "episodes": 24, "confirm": 24}).sized(20)
    assert (mine.candidates, mine.episodes, mine.confirm, mine.holdout) == (8, 24, 24, 24)
    assert FinalSelection.from_config({"holdout": 5}).sized(20).holdout == 5


def test_a_bad_auto_count_names_its_key():
    with pytest.raises(ValueError) as exc:
        FinalSelection.from_config({"holdout": "some"}, "c.yaml")
    assert ("key 'final_selection.holdout' must be an int from 1 to 100,000 or auto, got 'some'"
            in str(exc.value))


def test_a_selection_record_from_before_the_holdout_still_describes():
    """Older champion.json files (fitness = the score or the confirmation, no `holdout`; "holds" for
    "passes") still read: the line says the figure is the score, and no candidate is said to fail."""
    from evolve.runs.final_selection import describe

    rows = [{"key": 3, "score": 1.5, "nominal": 1.5, "holds": True}]
    old = record(rows, 3, 3, 2.0)
    line = describe(old)
    assert "genome 3, chosen among 1 candidates by 32 perturbed episodes each" in line, line
    assert "its figure is its score (the mean of the episodes that chose it)" in line
    assert "no candidate passed" not in line


@pytest.mark.slow
def test_an_auto_sized_run_killed_while_choosing_resumes_to_the_same_champion(tmp_path):
    """The sizes come from the config alone (generations x pop_size x robust episodes), so a run
    killed while choosing, resumed, sizes and chooses exactly as the uninterrupted run did."""
    from evolve.runs.experiment import Experiment
    from evolve.runs.final_selection import BEST_EVER_FILE

    cfg = {"method": "sgr", "task": "Walker-v0", "generations": 3, "pop_size": 12, "seed": 2,
           "episode_steps": 30, "workers": 1, "checkpoint_every": 1, "render_champion": False,
           "robust": ROBUST, "final_selection": {"rank": "pooled", "confirm": "auto"}}
    exp = Experiment.from_config(cfg, tmp_path / "whole", quiet=True)
    exp.run_all()
    exp.close()
    whole = RunDir(tmp_path / "whole").champion()
    assert whole["selection"]["sized"]["auto"] == ["candidates", "episodes", "confirm", "holdout"]
    assert whole["selection"]["sized"]["run_episodes"] == 3 * 12 * 2
    from evolve.runs.final_selection import describe
    assert "episodes in all, sized for the run's 72;" in describe(whole)
    sel = whole["selection"]  # episodes the problem counted: scores, exact ones, confirmations, holdout
    assert sel["sized"]["episodes"] == (len(sel["candidates"]) * (sel["episodes"] + 1 + sel["confirm"])
                                        + sel["holdout"])
    copy = tmp_path / "killed"
    shutil.copytree(tmp_path / "whole", copy)
    (copy / "checkpoints" / "gen-00003.json.gz").unlink()  # killed while choosing: no last checkpoint
    (copy / BEST_EVER_FILE).unlink()
    exp = Experiment.resume(copy, quiet=True)
    exp.run_all()
    exp.close()
    assert (copy / "champion.json").read_bytes() == (tmp_path / "whole" / "champion.json").read_bytes()
