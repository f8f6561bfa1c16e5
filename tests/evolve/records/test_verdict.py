"""A champion's verdict (evolve/records/verdict.py): holds or knife-edge, by one rule, wherever a
champion is shown. The paper sweep's nominal champions give one of each: Walker-v0 seed 0 keeps about
two thirds of its return under ±1e-3 (results/paper/report.md), seed 3 over 90 %."""

from __future__ import annotations

import math
from pathlib import Path

import pytest

from evolve import load_champion
from evolve.records import verdict
from evolve.records.replay import headline
from evolve.report.report import write_report

PAPER = Path(__file__).resolve().parents[3] / "results" / "paper" / "runs"


@pytest.mark.parametrize("nominal, noisy, holds", [
    (5.0, 4.5, True), (5.0, 4.49, False), (5.0, 6.0, True),  # >= 90 % of a positive return
    (-1.0, -1.1, True), (-1.0, -1.2, False),  # a negative return: within 10 % of its size below
])
def test_the_rule_is_the_noisy_mean_within_ten_percent_below_the_noise_free_return(nominal, noisy, holds):
    v = verdict.Verdict(nominal, noisy, 20, 1e-3)
    assert v.holds is holds and v.label == ("holds" if holds else "knife-edge")
    assert math.isnan(v.share) if nominal <= 0 else v.share == noisy / nominal


def test_load_champion_tells_a_knife_edge_champion_from_one_that_holds():
    edge = load_champion(PAPER / "sgr-Walker-v0-s0").verdict()
    held = load_champion(PAPER / "sgr-Walker-v0-s3").verdict()
    assert edge.label == "knife-edge" and edge.share < 0.8 and edge.replays == verdict.REPLAYS
    assert held.label == "holds" and held.share >= 0.9
    assert edge.nominal == load_champion(PAPER / "sgr-Walker-v0-s0").fitness  # a nominal run's return
    assert edge.line().startswith("knife-edge: ") and "over 20 replays under uniform ±0.001" in edge.line()


def test_the_report_marks_each_champion_with_the_rule_that_decided(tmp_path):
    import shutil

    for name in ("sgr-Walker-v0-s0", "sgr-Walker-v0-s3"):
        shutil.copytree(PAPER / name, tmp_path / "runs" / name)
    out = write_report(tmp_path, tmp_path / "report.md", levels=(1e-3,), replays=4, gallery=False)
    text = Path(out).read_text()
    assert "**1 of 2 champions hold.**" in text and "4 replays with uniform(±0.001)" in text
    summary = next(x for x in text.splitlines() if x.startswith("| sgr | Walker-v0 |"))
    assert summary.endswith("| 1 of 2 |")  # the method x task table: how many hold
    line = {n: next(x for x in text.splitlines() if x.startswith(f"| {n} |")) for n in ("sgr-Walker-v0-s0",
                                                                                         "sgr-Walker-v0-s3")}
    assert line["sgr-Walker-v0-s0"].endswith("**knife-edge** |")
    assert line["sgr-Walker-v0-s3"].endswith("**holds** |")
    assert "knife-edge" in (tmp_path / "report.html").read_text()


def test_a_short_default_run_ends_with_a_champion_that_holds_and_says_so(tmp_path, capsys, repo_root):
    """`sgr evolve`'s packaged default, shortened: evolved under noise and chosen by final selection,
    its champion holds, and the run's last console line says so by the rule: its headline, the
    held-out episodes under the run's noise, recorded in champion.json and shown by its repr."""
    import yaml

    from evolve.cli import main

    raw = yaml.safe_load((repo_root / "configs" / "sgr" / "quick.yaml").read_text())
    assert raw["robust"]["accumulate"] and raw["final_selection"] is not None  # honest by default
    raw.update(generations=3, pop_size=16, episode_steps=100, render_champion=False, workers=1,
               neat_config=str(repo_root / "configs" / "neat" / "sgr.ini"))
    (tmp_path / "c.yaml").write_text(yaml.safe_dump(raw))
    assert main(["evolve", "--config", str(tmp_path / "c.yaml"), "--out", str(tmp_path / "run")]) == 0
    last = capsys.readouterr().out.strip().splitlines()[-1]
    champ = load_champion(tmp_path / "run")
    v = headline(tmp_path / "run")  # simulated again from the file
    assert v.to_headline() == champ.headline.to_headline() and v.holds and last == f"champion {v.line()}"
    assert v.noisy_mean == champ.fitness and v.episodes == "held-out episodes"
    assert f"return={v.noisy_mean:.4g}" in repr(champ) and "holds" in repr(champ)
    assert champ.rollout() == champ.nominal  # its exact episode, as final selection recorded it
