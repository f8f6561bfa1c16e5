"""One headline per champion (evolve/records/verdict.py): the record's `headline` block reads back
as the verdict it was written from; the console's lines on a champion end with it and never say
"holds" and "knife-edge" of one champion without a line on why; `sgr explain` names every figure."""

import json
import math

import pytest

from evolve.cli import main
from evolve.records import verdict
from evolve.records.rundir import RunDir
from evolve.runs.experiment import champion_lines


def _record(passes: bool, held: verdict.Verdict) -> dict:
    rows = [{"key": 7, "recorded": 1.0, "score": 1.0, "nominal": 1.05, "passes": passes, "confirmed": 0.98},
            {"key": 2, "recorded": 0.5, "score": 0.4, "nominal": 0.9, "passes": False, "confirmed": 0.4}]
    return {"format": "sgr-champion-1", "method": "sgr", "task": "Walker-v0", "episode_steps": 60,
            "fitness": held.noisy_mean, "generation": 3, "genome": {"key": 7},
            "evaluation": {"robust": {"episodes": 8, "action_noise": "uniform", "action_scale": 0.001,
                                      "offset": 0.0, "statistic": "mean", "reevaluate": False},
                           "seed": 0, "tag": "final-holdout/7"},
            "selection": {"candidates": rows, "episodes": 8, "statistic": "mean", "tolerance": 0.05,
                          "rank": "pooled", "confirm": 8, "holdout": 8, "passes": passes, "nominal": 1.05,
                          "score": 1.0, "confirmed": 0.98,
                          "best_ever": {"key": 7, "fitness": 1.0, "file": "champion-best-ever.json"}},
            "headline": held.to_headline()}


def _held(mean: float, exact: float = 1.05) -> verdict.Verdict:
    return verdict.Verdict(exact, mean, 8, 1e-3, 0.01, mean - 0.02, kind="uniform",
                           episodes=verdict.HELD_OUT)


def _folder(tmp_path, record: dict) -> RunDir:
    (tmp_path / "champion.json").write_text(json.dumps(record))
    return RunDir(tmp_path)


def test_the_headline_block_reads_back_as_the_verdict_it_was_written_from():
    v = _held(0.99)
    back = verdict.from_headline(v.to_headline())
    assert back.to_headline() == v.to_headline() and back.line() == v.line() and back.holds
    assert verdict.from_headline(_held(0.9).to_headline()).label == "knife-edge"  # 0.9 < 0.945


@pytest.mark.parametrize("block", [None, "holds", [], {"return": 1.0},
                                   {**_held(1.0).to_headline(), "episodes": 0},
                                   {**_held(1.0).to_headline(), "which": "<script>"},
                                   {**_held(1.0).to_headline(), "noise": "uniform"}])
def test_a_block_that_is_not_a_headline_reads_as_none(block):
    assert verdict.from_headline(block) is None


@pytest.mark.parametrize("passes, mean, why", [
    (False, 1.0, "why no candidate passed final selection yet the champion holds: the selection's test "
                 "(its mean return on the 8 + 8 perturbed episodes that chose it is within 5 % of its "
                 "exact return) is stricter than the verdict"),
    (True, 0.9, "why it passed final selection yet is knife-edge: "),
    (True, 1.0, None),
    (False, 0.9, None),
])
def test_the_console_never_says_holds_and_knife_edge_of_one_champion_without_why(tmp_path, passes, mean, why):
    h = _held(mean)
    lines = champion_lines(_folder(tmp_path, _record(passes, h)))
    assert lines[-1] == f"champion {h.line()}"  # the last line: the one figure
    whys = [x for x in lines if x.startswith("why ")]
    assert whys == ([] if why is None else [whys[0]]) and (why is None or whys[0].startswith(why))
    text = "\n".join(lines)
    if why is None:  # selection and verdict agree: one word of the two
        assert not ("holds" in text and "knife-edge" in text)


def test_sgr_explain_names_every_figure_of_the_record(tmp_path, capsys):
    rec = _record(False, _held(1.0))
    _folder(tmp_path, rec)
    assert main(["explain", str(tmp_path)]) == 0
    out = capsys.readouterr().out
    assert "The figure to quote: mean return 1.0000 (sd 0.0100, worst 0.9800) over 8 held-out episodes " \
           "under uniform ±0.001. Verdict: holds" in out
    for figure in ("fitness 1.0000", "selection.score 1.0000", "selection.confirmed 0.9800",
                   "selection.nominal 1.0500", "best-ever 1.0000", "headline.return 1.0000"):
        assert figure in out, figure
    assert "no candidate passed" in out and "is stricter than the verdict" in out


def test_sgr_explain_of_a_folder_without_a_champion_is_one_line(tmp_path, capsys):
    assert main(["explain", str(tmp_path)]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "has no champion.json yet" in err


def test_an_old_record_without_a_headline_says_so_and_quotes_its_fitness(tmp_path, capsys):
    rec = _record(True, _held(1.0))
    del rec["headline"]
    _folder(tmp_path, rec)
    assert main(["explain", str(tmp_path)]) == 0
    out = capsys.readouterr().out
    assert "The figure to quote: its fitness, 1.0000 (this record has no headline" in out
    assert math.isfinite(rec["fitness"])
