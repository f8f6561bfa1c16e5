"""`sgr report` on hand-made runs: every number of its tables, worked out by hand here.

The runs are written by this test (generations.csv, config.yaml, champion.json) and the champion
replays are stubbed at their edge (`replay_champion`, `rescore_champion` return the returns below),
so each expected cell follows from the numbers in this file alone.
"""

from __future__ import annotations

import csv
import json
import math
from pathlib import Path

import numpy as np
import pytest
import yaml

import evolve.records.replay as champion_module
from evolve.records.rundir import COLUMNS
from evolve.report.report import write_report


def best_column(seed: int) -> list[float]:
    """Best fitness of each of 100 generations (index 0 = generation 1).
    Seed 0: 0.2 at generation 1, 5.0 at generation 10, NaN at 20, else 0.1 -> best so far 0.2 at
    1, 5.0 at 30 and 100. Seed 1: 1.0, with 2.0 at generation 50 and 3.0 at 100 -> 1.0, 1.0, 3.0."""
    if seed == 0:
        best = [0.1] * 100
        best[0], best[9], best[19] = 0.2, 5.0, math.nan
    else:
        best = [1.0] * 100
        best[49], best[99] = 2.0, 3.0
    return best


# replay_champion(run, replays, eps) -> [nominal, replay 1, ...], per seed and noise level
REPLAYS = {0: {1e-9: [2.0, 2.0, 1.0, 3.0], 1e-3: [2.0, 0.5, 1.5, 1.0]},
           1: {1e-9: [4.0, 4.0, 4.0, 4.0], 1e-3: [4.0, 2.0, 6.0, 4.0]}}
CHAMPION = {0: 5.0, 1: 3.0}


def make_run(folder: Path, seed: int) -> Path:
    d = folder / "runs" / f"sgr-Walker-v0-s{seed}"
    d.mkdir(parents=True)
    (d / "config.yaml").write_text(yaml.safe_dump({"method": "sgr", "task": "Walker-v0", "seed": seed,
                                                   "generations": 100}))
    lines = [",".join(COLUMNS)]
    for g, b in enumerate(best_column(seed)):
        lines.append(",".join([str(g), repr(b), "0.0", "0.0", "1", "10", "0", "10", "0.1", "0.5", "0.1",
                               str(0.5 + seed)]))
    (d / "generations.csv").write_text("\n".join(lines) + "\n")
    (d / "champion.json").write_text(json.dumps({"fitness": CHAMPION[seed]}))
    return d


@pytest.fixture
def report(tmp_path, monkeypatch):
    seed_of = {}
    for seed in (0, 1):
        seed_of[make_run(tmp_path, seed).name] = seed
    monkeypatch.setattr(champion_module, "rescore_champion",
                        lambda run_dir: CHAMPION[seed_of[Path(run_dir).name]])
    monkeypatch.setattr(champion_module, "replay_champion",
                        lambda run_dir, replays, eps: np.array(REPLAYS[seed_of[Path(run_dir).name]][eps]))
    out = write_report(tmp_path, tmp_path / "out" / "report.md", replays=3, gallery=False)
    rows = {r["run"]: r for r in csv.DictReader((out.parent / "summary.csv").open())}
    return out.read_text(), rows


def test_summary_csv_holds_the_hand_computed_numbers(report):
    _, rows = report
    s0, s1 = rows["sgr-Walker-v0-s0"], rows["sgr-Walker-v0-s1"]
    expect = {
        "sgr-Walker-v0-s0": {"best_gen1": 0.2, "best_gen30": 5.0, "best_gen100": 5.0, "best_final": 5.0,
                             "champion_fitness": 5.0, "replay": 5.0, "nominal": 2.0, "s_per_gen": 0.5,
                             "noise1e-09_mean": 2.0, "noise1e-09_sd": math.sqrt(2 / 3),
                             "noise1e-09_min": 1.0, "noise1e-09_ratio": 1.0, "noise1e-03_mean": 1.0,
                             "noise1e-03_sd": math.sqrt(1 / 6), "noise1e-03_min": 0.5,
                             "noise1e-03_ratio": 0.5},
        "sgr-Walker-v0-s1": {"best_gen1": 1.0, "best_gen30": 1.0, "best_gen100": 3.0, "best_final": 3.0,
                             "champion_fitness": 3.0, "replay": 3.0, "nominal": 4.0, "s_per_gen": 1.5,
                             "noise1e-09_mean": 4.0, "noise1e-09_sd": 0.0, "noise1e-09_min": 4.0,
                             "noise1e-09_ratio": 1.0, "noise1e-03_mean": 4.0,
                             "noise1e-03_sd": math.sqrt(8 / 3), "noise1e-03_min": 2.0,
                             "noise1e-03_ratio": 1.0}}
    for row, want in ((s0, expect["sgr-Walker-v0-s0"]), (s1, expect["sgr-Walker-v0-s1"])):
        for key, value in want.items():
            assert float(row[key]) == pytest.approx(value, rel=1e-12), key
    assert (s0["seed"], s1["generations"]) == ("0", "100")


def test_report_md_cells_are_means_and_sample_sds_over_seeds(report):
    text, _ = report
    line = next(x for x in text.splitlines() if x.startswith("| sgr | Walker-v0 |"))
    cells = [c.strip() for c in line.strip("|").split("|")]
    # gen 1: 0.2, 1.0 -> mean 0.6, sd 0.8 / sqrt 2; gen 30: 5, 1 -> 3, 4 / sqrt 2; gen 100: 5, 3 -> 4, sqrt 2
    assert cells[2:8] == ["2 (seeds 0, 1)", "100", "0.60 ± 0.57", "3.00 ± 2.83", "4.00 ± 1.41", "4.00 ± 1.41"]
    # champion 5, 3; nominal 2, 4; +-1e-9 means 2, 4 (worst 1); +-1e-3 means 1, 4 (worst 0.5)
    assert cells[-7:-1] == ["4.00 ± 1.41", "3.00 ± 1.41", "3.00 ± 1.41", "1.00", "2.50 ± 2.12", "0.50"]
    # the verdict (>= 90 % of the nominal return at ±1e-3): s0 keeps 1 of 2, s1 4 of 4
    assert cells[-1] == "1 of 2"
    assert "do not replay" not in text


def test_report_md_lists_each_champion_under_noise(report):
    text, _ = report
    # share of the nominal return / of the recorded fitness: s0 2/2, 2/5, 1/2, 1/5; s1 4/4, 4/3, 4/4, 4/3
    assert ("| sgr-Walker-v0-s0 | 5.000 | 2.000 | 2.000 / 1.000 | 100 % / 40 % | 1.000 / 0.500 "
            "| 50 % / 20 % |") in text
    assert ("| sgr-Walker-v0-s1 | 3.000 | 4.000 | 4.000 / 4.000 | 100 % / 133 % | 4.000 / 2.000 "
            "| 100 % / 133 % |") in text


def test_report_takes_one_run_directory_as_sgr_render_does(tmp_path):
    """`sgr report RUN`: the run itself, reported in RUN/report.md (no 'holds no run directories')."""
    run = make_run(tmp_path, 0)
    out = write_report(run, robustness=False, gallery=False)
    assert out == run / "report.md"
    rows = list(csv.DictReader((run / "summary.csv").open()))
    assert [r["run"] for r in rows] == [run.name] and float(rows[0]["best_gen30"]) == 5.0
