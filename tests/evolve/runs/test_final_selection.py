"""A run's final selection (evolve/runs/final_selection.py): the champion chosen afresh at the end
among the final elites, by many new perturbed episodes, keeping genomes that hold (whose exact
episode is not far better than their perturbed ones).

What must hold: evolution itself is unchanged (same rows, and the best-ever record kept beside);
champion.json alone scores the chosen genome again to the bit; the choice follows its rule from the
recorded scores; choosing again, on one or two workers, or after a kill while choosing, gives the
same file; nested runs are refused with one line.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
import yaml

from evolve.cli import main
from evolve.records.replay import replay_champion, rescore_champion
from evolve.records.rundir import RunDir
from evolve.runs.experiment import Experiment
from evolve.runs.final_selection import BEST_EVER_FILE, FinalSelection, choose

ROBUST = {"episodes": 2, "action_noise": "uniform", "action_scale": 1e-2, "offset": 0.0,
          "statistic": "mean"}
# 12 episodes: numpy's pairwise sum would score one genome alone differently from its column of a batch
SELECT = {"candidates": 4, "episodes": 12, "statistic": "mean", "tolerance": 0.1}
COLUMNS = ["generation", "best", "mean", "median", "n_species", "n_valid", "n_invalid", "episodes"]


def config(**changes) -> dict:
    return {"method": "sgr", "task": "Walker-v0", "generations": 3, "pop_size": 12, "seed": 5,
            "episode_steps": 40, "render_champion": False, "workers": 1, "checkpoint_every": 1,
            "robust": ROBUST, "final_selection": None, **changes}


def evolved(champ: dict) -> dict:
    """A champion record as evolution wrote it: without the headline its run's end adds."""
    return {k: v for k, v in champ.items() if k != "headline"}


def run(tmp: Path, name: str, cfg: dict) -> RunDir:
    exp = Experiment.from_config(cfg, tmp / name, quiet=True)
    exp.run_all()
    exp.close()
    return exp.run


@pytest.fixture(scope="module")
def runs(tmp_path_factory) -> tuple[RunDir, RunDir]:
    tmp = tmp_path_factory.mktemp("final")
    return run(tmp, "plain", config()), run(tmp, "selected", config(final_selection=SELECT))


def test_evolution_is_unchanged_and_the_best_ever_record_is_kept(runs):
    plain, selected = runs
    table = [[[r[c] for c in COLUMNS] for r in run.rows()] for run in runs]
    assert table[1] == table[0]
    assert json.loads((selected.path / BEST_EVER_FILE).read_text()) == evolved(plain.champion())
    assert "selection" not in plain.champion()


def test_the_chosen_champion_rescores_to_the_bit_from_its_json(runs):
    """Its fitness is the held-out figure (12 episodes, as `episodes` when `holdout` is auto), tagged
    apart from the episodes that chose it."""
    champ = runs[1].champion()
    ev = champ["evaluation"]
    assert ev["robust"] == {**ROBUST, "episodes": 12, "reevaluate": False}
    assert ev["tag"] == f"final-holdout/{champ['genome']['key']}" and ev["seed"] == 5
    assert rescore_champion(runs[1].path) == champ["fitness"]
    assert replay_champion(runs[1].path)[0] == champ["selection"]["nominal"]  # its exact episode


def test_the_choice_follows_the_rule_from_the_recorded_scores(runs):
    champ = runs[1].champion()
    sel = champ["selection"]
    cands = sel["candidates"]
    assert 4 <= len(cands) <= 5 and sel["best_ever"]["key"] in [c["key"] for c in cands]
    for c in cands:
        score, nominal = c["score"], c["nominal"]
        assert c["passes"] == (score >= nominal - 0.1 * abs(nominal))
    pool = [c for c in cands if c["passes"]] or cands
    best = max(pool, key=lambda c: min(c["score"], c["nominal"]))
    assert champ["genome"]["key"] == best["key"] and sel["score"] == best["score"]
    assert sel["passes"] == best["passes"] and champ["fitness"] != best["score"]  # the held-out figure


def test_choose_takes_the_candidate_that_holds_with_the_best_worse_of_score_and_nominal_return():
    # score vs nominal: 5 vs 8 knife-edge; 4 vs 4.1 holds (worse 4); 4.5 vs 1 holds, unlucky exact
    # episode (worse 1); -1.95 vs -2 holds; -2.2 vs -2 does not (5 % of |-2| is 0.1)
    scores = np.array([5.0, 4.0, 4.5, -1.95, -2.2])
    nominal = np.array([8.0, 4.1, 1.0, -2.0, -2.0])
    i, holds = choose(scores, nominal, 0.05)
    assert i == 1 and holds.tolist() == [False, True, True, True, False]
    i, holds = choose(np.array([5.0, 4.0]), np.array([8.0, 7.0]), 0.05)  # none holds: best worse-of
    assert i == 0 and not holds.any()
    assert choose(np.array([4.5, 4.0]), np.array([4.2, 4.1]), 0.05)[0] == 0
    assert choose(scores, nominal, 0.05, "score")[0] == 2  # the best score that holds
    assert choose(np.array([np.nan, 1.0]), np.array([0.5, 2.0]), 0.0)[0] == 1


def test_with_a_confirmation_a_candidate_holds_only_when_fresh_episodes_agree():
    """`confirm`: the hold is judged on episodes that did not choose. The candidate ranked first
    (score 4.0 vs nominal 4.1) whose fresh episodes give 3.0 (73 %) no longer holds; the next
    (3.9 vs 3.9, confirmed 3.8) is chosen."""
    scores, nominal = np.array([4.0, 3.9, 5.0]), np.array([4.1, 3.9, 8.0])
    assert choose(scores, nominal, 0.05)[0] == 0
    i, holds = choose(scores, nominal, 0.05, confirmed=np.array([3.0, 3.8, 7.9]))
    assert i == 1 and holds.tolist() == [False, True, False]


def test_pooled_rank_takes_the_best_mean_of_every_perturbed_episode_among_those_that_hold():
    """`rank: pooled`: among candidates that hold on both samples, the best average of score and
    confirmation weighted by their episode counts. The first is a knife-edge (its fresh episodes
    give 4.0 against a nominal 5.0); the third holds with an unlucky exact episode."""
    scores, nominal = np.array([5.0, 4.0, 4.6]), np.array([5.0, 4.0, 1.0])
    confirmed = np.array([4.0, 4.4, 4.0])
    i, holds = choose(scores, nominal, 0.05, "pooled", confirmed, (32, 32))
    assert holds.tolist() == [False, True, True] and i == 2  # 4.3 against 4.2
    assert choose(scores, nominal, 0.05, "pooled", confirmed, (8, 24))[0] == 1  # 4.3 against 4.15
    assert choose(scores, nominal, 0.05, "min", confirmed)[0] == 1  # min(4.0, 4.0) against min(4.6, 1)
    assert choose(scores, nominal, 0.05, "pooled")[0] == 0  # no confirmation: the score alone


def test_a_confirmed_choice_follows_its_rule_and_its_fitness_rescores_to_the_bit(runs, tmp_path):
    """select-champion --confirm: every candidate gets fresh episodes, the champion holds on both
    sets (or none does), and its fitness is neither its score nor its confirmation but its held-out
    episodes, which champion.json alone gives again."""
    import shutil

    copy = tmp_path / "confirmed"
    shutil.copytree(runs[1].path, copy)
    assert main(["select-champion", str(copy), "--confirm", "12"]) == 0
    champ = RunDir(copy).champion()
    sel = champ["selection"]
    assert sel["confirm"] == 12
    cands = sel["candidates"]
    for c in cands:
        floor = c["nominal"] - 0.1 * abs(c["nominal"])
        assert c["passes"] == (c["score"] >= floor and c["confirmed"] >= floor)
    pool = [c for c in cands if c["passes"]] or cands
    best = max(pool, key=lambda c: min(c["score"], c["nominal"]))
    assert champ["genome"]["key"] == best["key"] and sel["confirmed"] == best["confirmed"]
    assert sel["score"] == best["score"] and champ["fitness"] not in (best["score"], best["confirmed"])
    assert champ["evaluation"]["tag"] == f"final-holdout/{best['key']}"
    assert rescore_champion(copy) == champ["fitness"]


@pytest.mark.slow
@pytest.mark.subprocess
def test_choosing_again_on_one_or_two_workers_changes_nothing(runs, tmp_path, capsys):
    import shutil

    before = (runs[1].path / "champion.json").read_bytes()
    best_ever = (runs[1].path / BEST_EVER_FILE).read_bytes()
    for workers in ("1", "2"):
        copy = tmp_path / f"w{workers}"
        shutil.copytree(runs[1].path, copy)
        assert main(["select-champion", str(copy), "--workers", workers]) == 0
        assert (copy / "champion.json").read_bytes() == before
        assert (copy / BEST_EVER_FILE).read_bytes() == best_ever
    assert "score" in capsys.readouterr().out


def test_selecting_after_the_fact_matches_selecting_at_the_end(runs, tmp_path):
    import shutil

    copy = tmp_path / "after"
    shutil.copytree(runs[0].path, copy)
    assert main(["select-champion", str(copy), "--candidates", "4", "--episodes", "12",
                 "--tolerance", "0.1"]) == 0
    assert json.loads((copy / "champion.json").read_text()) == runs[1].champion()
    assert json.loads((copy / BEST_EVER_FILE).read_text()) == evolved(runs[0].champion())


def test_a_run_killed_while_choosing_resumes_to_the_same_champion(runs, tmp_path):
    import shutil

    copy = tmp_path / "killed"
    shutil.copytree(runs[1].path, copy)
    # the state of a kill during the choice: the last generation's row and checkpoint not written
    (copy / "checkpoints" / "gen-00003.json.gz").unlink()
    (copy / BEST_EVER_FILE).unlink()
    exp = Experiment.resume(copy, quiet=True)
    exp.run_all()
    exp.close()
    assert (copy / "champion.json").read_bytes() == (runs[1].path / "champion.json").read_bytes()
    assert (copy / BEST_EVER_FILE).read_bytes() == (runs[1].path / BEST_EVER_FILE).read_bytes()


def test_an_unfinished_run_or_a_nested_run_is_one_error_line(runs, tmp_path, capsys):
    cfg = {**config(method="nested", pop_size=6, inner_pop_size=6, inner_generations=1),
           "final_selection": SELECT}
    (tmp_path / "n.yaml").write_text(yaml.safe_dump(cfg))
    assert main(["evolve", "--config", str(tmp_path / "n.yaml"), "--out", str(tmp_path / "n")]) == 2
    err = capsys.readouterr().err
    assert "key 'final_selection' does not apply to method 'nested'" in err and err.count("\n") == 1
    exp = Experiment.from_config(config(generations=5), tmp_path / "short", quiet=True)
    exp.search.step()
    exp.run.save_checkpoint(1, exp.state())
    exp.close()
    assert main(["select-champion", str(tmp_path / "short")]) == 2
    err = capsys.readouterr().err
    assert "is not finished (1 of 5 generations)" in err and err.count("\n") == 1


@pytest.mark.parametrize("raw, message", [
    ({"candidates": 0}, "key 'final_selection.candidates' must be an int from 1 to 100,000"),
    ({"tolerance": 1.5}, "key 'final_selection.tolerance' must be a number in [0, 1]"),
    ({"statistic": "best"}, "key 'final_selection.statistic' must be one of mean"),
    ({"episode": 3}, "key 'final_selection': unknown key 'episode'"),
    ({"rank": "max"}, "key 'final_selection.rank' must be one of min, score, pooled"),
])
def test_a_bad_final_selection_key_names_it(raw, message):
    with pytest.raises(ValueError, match=None) as exc:
        FinalSelection.from_config(raw, "c.yaml")
    assert message in str(exc.value)
