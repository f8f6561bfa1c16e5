"""A map-elites run is a run like the others (evolve/methods/map_elites.py): killed with SIGKILL and
resumed it is the run it would have been, archive included; 1 and 2 rollout workers give the same
archive; and every elite of elites.json replays to its recorded fitness, bit for bit, from the file
alone (`load_champion(run, cell=...)`, `rescore_champion(run, cell=...)`)."""

from __future__ import annotations

import gzip
import json
from pathlib import Path

import numpy as np
import pytest
import yaml

from evolve.methods.qd_floors import FLOORS
from evolve.records.replay import champion_behaviour, load_champion, rescore_champion
from evolve.records.rundir import RunDir
from evolve.runs.checkpoint import load_checkpoint
from evolve.runs.experiment import Experiment
from tests.evolve.runs.test_resume import kill_when, sgr
from tsim.errors import SgrError

pytest.importorskip("ribs", reason="method map-elites needs pyribs: pip install 'sgr[qd]'")
pytestmark = [pytest.mark.slow]

# honest evaluation (noise, accumulated scores, settle) on a tiny archive; no final selection
TINY = {"method": "map-elites", "task": "Walker-v0", "generations": 4, "pop_size": 8, "seed": 3,
        "episode_steps": 20, "workers": 1, "render_champion": False, "final_selection": None,
        "robust": {"episodes": 1, "action_noise": "uniform", "action_scale": 0.001, "reevaluate": True,
                   "accumulate": True, "settle": 3},
        "qd": {"descriptors": ["actuator", "rigid"], "resolution": [3, 3], "batch": 8, "rescore": 4}}
COLUMNS = ["generation", "best", "mean", "median", "n_valid", "n_invalid", "episodes", "coverage", "qd_score"]


def run_tiny(folder: Path, **changes) -> RunDir:
    with Experiment.from_config({**TINY, **changes}, folder, quiet=True) as exp:
        exp.run_all()
    return RunDir(folder)


def rows(run: RunDir) -> list[list[str]]:
    return [[r[c] for c in COLUMNS] for r in run.rows()]


def checkpoint(path: Path) -> dict:
    """A checkpoint's data (gzipped JSON) as read, its generation included."""
    with gzip.open(path, "rt") as f:
        return json.load(f)


def elites(run: RunDir) -> dict:
    return json.loads((run.path / "elites.json").read_text())


@pytest.fixture(scope="module")
def tiny(tmp_path_factory) -> RunDir:
    return run_tiny(tmp_path_factory.mktemp("me") / "run")


def test_a_run_writes_its_archive_rows_and_champion(tiny):
    """generations.csv has coverage and the QD score, which agree with elites.json's archive; the
    champion is the best elite; elites were re-scored (some hold several scores)."""
    data = elites(tiny)
    last = tiny.rows()[-1]
    assert len(tiny.rows()) == 4 and float(last["coverage"]) == len(data["elites"]) / 9 == data["coverage"]
    fits = [e["champion"]["fitness"] for e in data["elites"]]
    offset = data["score_offset"]
    assert offset == FLOORS["Walker-v0"]  # the default: the task's floor
    assert float(last["qd_score"]) == data["qd_score"]
    assert data["qd_score"] == pytest.approx(sum(max(0.0, f - offset) for f in fits))
    assert float(last["best"]) == max(fits)
    assert tiny.champion()["fitness"] == max(fits) and tiny.champion()["method"] == "map-elites"
    assert max(len(e["champion"]["evaluation"]["tags"]) for e in data["elites"]) > 1


def test_every_elite_replays_its_recorded_fitness_to_the_bit(tiny):
    """Each elite's recorded fitness (the mean of its noisy episodes, re-scored as they accumulated) is
    what its record in elites.json gives again; `load_champion(run, cell=...)` is that elite."""
    data = elites(tiny)
    for e in data["elites"]:
        cell = tuple(e["cell"])
        assert rescore_champion(tiny.path, cell=cell) == e["champion"]["fitness"]
        champ = load_champion(tiny.path, cell=cell)
        assert champ.fitness == e["champion"]["fitness"] and champ.body.tolist() == e["champion"]["body"]
    assert load_champion(tiny.path, cell=",".join(map(str, data["elites"][0]["cell"]))).fitness == \
        data["elites"][0]["champion"]["fitness"]
    filled = {tuple(e["cell"]) for e in data["elites"]}
    empty = next((i, j) for i in range(3) for j in range(3) if (i, j) not in filled)
    with pytest.raises(SgrError, match=f"no elite in cell {empty[0]},{empty[1]}"):
        load_champion(tiny.path, cell=empty)


@pytest.mark.subprocess
def test_one_and_two_workers_give_the_same_archive(tmp_path, tiny):
    two = run_tiny(tmp_path / "two", workers=2)
    assert elites(two) == elites(tiny) and rows(two) == rows(tiny)


# an archive over what the robots do, parents by curiosity and tournaments: the state grows by each
# elite's behaviour features and every elite's curiosity
BEHAVIOUR_QD = {"descriptors": ["gait_frequency", "contact"], "resolution": [4, 3], "batch": 8, "rescore": 4,
                "selection": "curiosity", "exploit": 0.25}


@pytest.mark.subprocess
@pytest.mark.parametrize("qd", [pytest.param(TINY["qd"], marks=pytest.mark.long), BEHAVIOUR_QD],
                         ids=["body", "behaviour"])
def test_a_sigkilled_run_resumes_in_a_new_process_to_the_same_run(tmp_path, qd):
    """Killed after generation 5 or later, resumed from its newest checkpoint by a new process: the
    rows, the archive, the champion and the last checkpoint are the uninterrupted run's."""
    raw = {**TINY, "generations": 10, "checkpoint_every": 2, "episode_steps": 60, "qd": qd}
    cfg = tmp_path / "me.yaml"
    cfg.write_text(yaml.safe_dump(raw))
    crashed = RunDir(tmp_path / "crashed")
    proc = sgr("evolve", "--config", str(cfg), "--out", str(crashed.path), "--quiet")
    kill_when(proc, crashed, 5)
    full = Experiment.create(str(cfg), str(tmp_path / "full"), {}, quiet=True)  # the reference
    full.run_all()
    full.close()
    resume_from = load_checkpoint(crashed)["generation"]
    assert 2 <= resume_from < 10
    resumed = sgr("evolve", "--resume", str(crashed.path), "--quiet")
    _, err = resumed.communicate(timeout=300)
    assert resumed.returncode == 0, err
    ref = RunDir(tmp_path / "full")
    assert rows(crashed) == rows(ref) and len(crashed.rows()) == 10
    assert elites(crashed) == elites(ref)
    assert crashed.champion() == ref.champion()
    assert checkpoint(crashed.checkpoints()[0]) == checkpoint(ref.checkpoints()[0])


def test_archive_png_heatmap_holds_each_cells_elite_fitness(tiny):
    """archive.png is written with the last generation; its grid is each cell's elite fitness from
    elites.json (NaN where empty)."""
    from evolve.report.archive import archive_grid

    assert (tiny.path / "archive.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    data = elites(tiny)
    grid, shown = archive_grid(data)
    assert grid.shape == (3, 3) and int(np.isfinite(grid).sum()) == len(data["elites"])
    for e in data["elites"]:
        assert grid[tuple(e["cell"])] == e["champion"]["fitness"] and shown[tuple(e["cell"])] is e


def test_sgr_render_cell_renders_that_elite(tiny, tmp_path, capsys):
    """`sgr render RUN --cell I,J --exact`: that elite's exact episode, its nominal return printed;
    an empty cell is one error line."""
    from evolve.cli import main

    data = elites(tiny)
    e = data["elites"][-1]
    cell = ",".join(map(str, e["cell"]))
    gif = tmp_path / "elite.gif"
    assert main(["render", str(tiny.path), "--cell", cell, "--exact", "--width", "64", "--height", "32",
                 "--out", str(gif)]) == 0
    out = capsys.readouterr().out
    nominal = load_champion(tiny.path, cell=e["cell"]).rollout()
    assert gif.read_bytes()[:3] == b"GIF" and f"the elite of cell {cell}" in out and f"{nominal:.4f}" in out
    filled = {tuple(x["cell"]) for x in data["elites"]}
    empty = next(f"{i},{j}" for i in range(3) for j in range(3) if (i, j) not in filled)
    assert main(["render", str(tiny.path), "--cell", empty]) == 2
    assert len(capsys.readouterr().err.strip().splitlines()) == 1


def test_the_report_shows_the_archive_and_elites_across_the_map(tiny, tmp_path):
    """`sgr report`'s archives/: the run's archive picture and the bodies of distinct elites, the best
    first, named in report.md and inlined in report.html."""
    from evolve.report.archive import spread_elites
    from evolve.report.report import write_report

    out = write_report([tiny.path], tmp_path / "rep" / "report.md", robustness=False, gallery=False)
    text = out.read_text()
    assert "## Archives (map-elites)" in text and "archives/run-archive.png" in text
    chosen = spread_elites(tiny.path, 3)
    best = max(elites(tiny)["elites"], key=lambda e: e["champion"]["fitness"])
    assert chosen[0]["cell"] == best["cell"] and len({tuple(c["cell"]) for c in chosen}) == len(chosen)
    for c in chosen:
        assert (out.parent / "archives" / f"run-elite-{c['cell'][0]}-{c['cell'][1]}.png").is_file()
    page = (out.parent / "report.html").read_text()
    assert "archive of run" in page
    assert page.count("Archives (map-elites)") == 1 and "![archive" not in page  # once, as HTML


def test_the_report_states_coverage_qd_score_and_best_elite(tiny, tmp_path):
    """report.md's "Quality diversity" row and summary.csv's columns are the run's last generation's
    coverage and QD score and its archive's best elite; qd-curves.png is drawn and inlined."""
    import csv

    from evolve.report.report import write_report

    out = write_report([tiny.path], tmp_path / "rep" / "report.md", robustness=False, gallery=False)
    last, data = tiny.rows()[-1], elites(tiny)
    best = max(e["champion"]["fitness"] for e in data["elites"])
    row = next(csv.DictReader((out.parent / "summary.csv").open()))
    assert float(row["coverage"]) == float(last["coverage"]) and float(row["qd_score"]) == data["qd_score"]
    assert float(row["best_elite"]) == best and int(row["n_elites"]) == len(data["elites"])
    assert row["descriptors"] == "actuator x rigid" and float(row["score_offset"]) == FLOORS["Walker-v0"]
    text = out.read_text()
    line = next(x for x in text.splitlines() if x.startswith("| map-elites") and "actuator x rigid" in x)
    assert f"{100 * float(last['coverage']):.1f} %" in line and f"{best:.2f} |" in line
    assert (out.parent / "qd-curves.png").is_file()
    assert "alt='QD curves'" in (out.parent / "report.html").read_text()


@pytest.mark.parametrize("damage, named", [
    (lambda s: s.update(format="sgr-map-elites-0"), "search.format"),
    (lambda s: s["elites"][0].update(tags=[]), "search.elites[0].tags"),
    (lambda s: s["elites"][0].update(total="1.0"), "search.elites[0].total"),
    (lambda s: s["elites"].pop(), "search.elites: "),
    (lambda s: s["elites"][0].update(cell=s["elites"][0]["cell"] + 1000),
     "do not fall in their recorded cells"),
])
def test_a_damaged_archive_checkpoint_is_refused_naming_the_field(tiny, damage, named):
    """The checkpoint is data checked field by field: a damaged archive fails in one line naming
    what is wrong, before anything runs (the elite's cell is checked against where its body falls)."""
    from evolve.config import RunConfig
    from evolve.methods.map_elites import MapElitesProblem, MapElitesSearch
    from evolve.runs.checkpoint import decode_checkpoint
    from evolve.search.neat_ini import load_neat_config
    from evolve.search.state_codec import StateError

    data = checkpoint(tiny.checkpoints()[0])
    damage(data["search"])
    cfg, nc = RunConfig.of(tiny.config()), load_neat_config(tiny.path / "neat.ini")
    with pytest.raises(StateError, match=named.replace("[", "\\[").replace("]", "\\]")):
        state = decode_checkpoint(data, cfg, nc)
        MapElitesSearch(MapElitesProblem(cfg, nc), nc, seed=cfg.seed, state=state)


@pytest.fixture(scope="module")
def by_behaviour(tmp_path_factory) -> RunDir:
    return run_tiny(tmp_path_factory.mktemp("me") / "behaviour", qd=BEHAVIOUR_QD, episode_steps=60)


def test_an_archive_of_behaviour_places_each_elite_by_what_it_did(by_behaviour):
    """Over gait frequency x contact: each elite of elites.json holds its behaviour features (the mean
    over its scored episodes), its descriptors are those features, and its record replayed from the
    file does that again; champion.json says the champion's cell, descriptors and behaviour."""
    data = elites(by_behaviour)
    assert data["descriptors"] == ["gait_frequency", "contact"] and len(data["elites"]) >= 2
    for e in data["elites"]:
        b = e["behaviour"]
        assert e["measures"] == {"gait_frequency": b["gait_frequency"], "contact": b["contact"]}
        again = champion_behaviour(by_behaviour.path, cell=tuple(e["cell"]))
        assert again == pytest.approx(b, abs=1e-12)
    champ = by_behaviour.champion()
    best = max(data["elites"], key=lambda e: e["champion"]["fitness"])
    assert champ["archive"] == {"cell": best["cell"], "measures": best["measures"],
                                "behaviour": best["behaviour"]}


def test_a_run_extended_with_more_generations_is_the_longer_run(tmp_path):
    """A finished 4-generation run extended to 6 (`sgr evolve --resume RUN --generations 6`) has the
    rows and archive of a run asked for 6 from the start: the search does not depend on the run's
    length (the QD study reads SGR's budget and twice it from one run)."""
    from evolve.cli import main

    qd = {**BEHAVIOUR_QD}
    straight = run_tiny(tmp_path / "six", qd=qd, episode_steps=60, generations=6)
    extended = run_tiny(tmp_path / "four", qd=qd, episode_steps=60, generations=4)
    assert main(["evolve", "--resume", str(extended.path), "--generations", "6", "--quiet"]) == 0
    assert rows(extended) == rows(straight) and elites(extended) == elites(straight)


def test_sgr_render_elites_shows_elites_across_the_map_side_by_side(tiny, tmp_path, capsys):
    """`sgr render RUN --elites 3`: one GIF of three elites' panels side by side (2-pixel gaps), each
    its exact episode; without a run it is one error line."""
    import imageio.v3 as iio

    from evolve.cli import main

    gif = tmp_path / "strip.gif"
    assert main(["render", str(tiny.path), "--elites", "3", "--width", "64", "--height", "48",
                 "--out", str(gif)]) == 0
    assert "3 elites across the archive" in capsys.readouterr().out
    frames = iio.imread(gif)
    assert frames.shape[1:3] == (48, 3 * 64 + 2 * 2) and len(frames) >= 2
    assert main(["render", "--elites", "3", "--task", "Walker-v0", "--body", "33,33"]) == 2
    assert "give RUN_DIR" in capsys.readouterr().err
    # --every K: a frame every K steps (4 by default): fewer frames, the same panels
    assert main(["render", str(tiny.path), "--elites", "3", "--width", "64", "--height", "48",
                 "--every", "8", "--out", str(gif)]) == 0
    sparse = iio.imread(gif)
    assert sparse.shape[1:] == frames.shape[1:] and len(sparse) < len(frames)
    assert main(["render", str(tiny.path), "--every", "8"]) == 2
    assert "--every sets the frames of an --elites strip" in capsys.readouterr().err
