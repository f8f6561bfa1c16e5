"""Body measures where people look (issue 47): `sgr report`'s summary.csv, report.md and the
gallery's captions carry each run's champion body measures and its last generation's body
diversity; a run made before body_diversity was recorded still reports, the column empty; the
console names the champion's body at a run's end."""

from __future__ import annotations

import csv
import json
import shutil
from pathlib import Path

import numpy as np
import pytest

from evolve.cli import main
from evolve.methods.body_measures import measures
from evolve.records.rundir import champion_of
from evolve.report.gallery import report_html
from evolve.report.report import BODY_COLUMNS, write_report
from evolve.runs.experiment import Experiment
from tests.evolve.conftest import TINY

ROOT = Path(__file__).resolve().parents[3]
# a run of an older sgr (generations.csv without body_diversity, rows counted from 0), committed
OLD_RUN = ROOT / "results" / "run-records" / "sgr-Walker-v0-s0"


def summary(out: Path) -> dict[str, dict]:
    return {r["run"]: r for r in csv.DictReader((out.parent / "summary.csv").open())}


def test_summary_csv_holds_the_champion_bodys_measures_and_the_last_generations_diversity(tmp_path, sgr_run):
    out = write_report(sgr_run, tmp_path / "out" / "report.md", robustness=False, gallery=False)
    row = summary(out)[sgr_run.name]
    body = np.array(json.loads((sgr_run / "champion.json").read_text())["body"])
    want = measures(body)
    for column in BODY_COLUMNS[:-1]:
        assert float(row[column]) == pytest.approx(want[column], rel=1e-12), column
    last = list(csv.DictReader((sgr_run / "generations.csv").open()))[-1]
    assert row["body_diversity"] == last["body_diversity"] != ""
    # report.md's "Champion bodies" line of the run: rows x columns, then the final diversity
    start = f"| {sgr_run.name} | {want['height']}x{want['width']} |"
    line = next(x for x in out.read_text().splitlines() if x.startswith(start))
    assert line.endswith(f" | {float(last['body_diversity']):.3f} |")


def test_an_older_run_without_body_diversity_reports_its_champions_body_and_no_diversity(tmp_path):
    """The committed run's champion is a staircase of vertical actuators (4, 3, 2, 1 from the top)
    in a 5x5 grid: a 4x4 box, all actuators; left-right, row by row, the cells filled in the row or
    its mirror and agreeing are 4 of 4, 2 of 4, 0 of 4, 0 of 2: 6 of 14; the staircase is its own
    transpose, so top-bottom is the same 6 of 14."""
    runs = tmp_path / "runs"
    shutil.copytree(OLD_RUN, runs / OLD_RUN.name)
    assert "body_diversity" not in (runs / OLD_RUN.name / "generations.csv").read_text().splitlines()[0]
    out = write_report(runs, tmp_path / "out" / "report.md", robustness=False, gallery=False)
    row = summary(out)[OLD_RUN.name]
    assert (row["width"], row["height"], float(row["actuator"])) == ("4", "4", 1.0)
    assert float(row["fill"]) == 10 / 16 and float(row["v_actuator"]) == 1.0
    assert float(row["rigid"]) == float(row["soft"]) == float(row["h_actuator"]) == 0.0
    assert float(row["symmetry_lr"]) == float(row["symmetry_tb"]) == pytest.approx(6 / 14, rel=1e-12)
    assert int(row["irregularity"]) > 0 and row["body_diversity"] == ""
    assert f"| {OLD_RUN.name} | 4x4 | 62 % | 0 / 0 / 0 / 100 % | 0.43 | 0.43 | {row['irregularity']} | - |" \
        in out.read_text()


@pytest.mark.parametrize("text, says", [
    ('{"fitness": ', "not valid JSON (Expecting value: line 1 column 13"),
    ("[1, 2]", "a champion record is a JSON object, got list"),
    ('{"fitness": "high", "body": [[3]]}', "key 'fitness' must be a number, got 'high'"),
    ('{"fitness": 1.0, "body": [[3, 3], [3]]}', "key 'body': "),
    (b"\xff\xfe", "not valid JSON ('utf-8' codec can't decode byte 0xff"),
    ("[" * 100_000, "not a champion's record (nested too deeply)"),
])
def test_a_damaged_champion_stops_the_report_naming_the_file(tmp_path, capsys, monkeypatch, text, says):
    """A champion.json that is not a champion's record (ours are written whole) showed as a run
    without a champion and `sgr report` exited 0; it is one line naming the file, found before any
    run's champion is replayed (the damaged run is the last of two). A run with no champion.json
    yet is no error (`champion_of` is None, its columns stay empty)."""
    import evolve.report.report as report

    assert champion_of(tmp_path / "missing") is None
    shutil.copytree(OLD_RUN, tmp_path / "runs" / "a-good")
    shutil.copytree(OLD_RUN, tmp_path / "runs" / "z-bad")
    f = tmp_path / "runs" / "z-bad" / "champion.json"
    f.write_bytes(text if isinstance(text, bytes) else text.encode())

    def no_replay(*args, **kwargs):
        raise AssertionError("a champion was replayed before the damaged file was found")

    monkeypatch.setattr(report, "champion_robustness", no_replay)
    assert main(["report", str(tmp_path / "runs"), "--out", str(tmp_path / "r.md"), "--no-gallery"]) == 2
    line, = capsys.readouterr().err.splitlines()
    assert line.startswith(f"sgr: error: {f}: {says}"), line
    assert not (tmp_path / "r.md").exists()
    assert main(["plot", str(tmp_path / "runs" / "z-bad"), "--out", str(tmp_path / "p.png")]) == 2
    assert capsys.readouterr().err.startswith(f"sgr: error: {f}: {says}")


def test_the_gallery_caption_under_a_champions_picture_gives_its_body(tmp_path):
    """report.html's figure of a champion: its body's size, symmetries, irregularity, actuator share,
    fill and materials, and the final population's diversity under the fitness (a row measured
    before the materials were reported: without them)."""
    gif, png = tmp_path / "a.gif", tmp_path / "a-body.png"
    gif.write_bytes(b"GIF89a")
    png.write_bytes(b"\x89PNG")
    curves = tmp_path / "curves.png"
    curves.write_bytes(b"\x89PNG")
    row = {"method": "sgr", "task": "Walker-v0", "seed": 0, "champion_fitness": 1.5, "run": "r",
           "width": 3, "height": 4, "actuator": 0.5, "symmetry_lr": 1.0, "symmetry_tb": 0.25,
           "irregularity": 7, "body_diversity": 0.125}
    page = report_html("# Results\n", curves, [{"row": row, "run": tmp_path, "gif": gif, "body": png}])
    assert ("fitness 1.500<br>body 4x3, symmetry lr 1.00 tb 0.25, irregularity 7, actuators 50 % · "
            "final diversity 0.125</figcaption>") in page
    row.update(fill=0.75, rigid=0.25, soft=0.25, h_actuator=0.125, v_actuator=0.375)
    page = report_html("# Results\n", curves, [{"row": row, "run": tmp_path, "gif": gif, "body": png}])
    assert ("fitness 1.500<br>body 4x3, symmetry lr 1.00 tb 0.25, irregularity 7, actuators 50 % · "
            "fill 75 %, rigid / soft / h / v 25 / 25 / 12 / 38 % · final diversity 0.125</figcaption>"
            ) in page


def test_a_runs_end_names_its_champions_body_before_the_verdict(tmp_path, capsys):
    """Under the line naming champion.json; the verdict's line stays the last."""
    with Experiment.from_config({"method": "sgr", **TINY, "generations": 1}, tmp_path / "run") as exp:
        exp.run_all()
        exp.finish()
    lines = capsys.readouterr().out.splitlines()
    body = np.array(json.loads((tmp_path / "run" / "champion.json").read_text())["body"])
    m = measures(body)
    named = next(i for i, x in enumerate(lines) if x.startswith("champion: genome"))
    assert lines[-1].startswith(("champion holds", "champion knife-edge"))
    assert lines[named + 1] == (f"champion body: {m['height']}x{m['width']}, symmetry lr "
                                  f"{m['symmetry_lr']:.2f} tb {m['symmetry_tb']:.2f}, irregularity "
                                  f"{m['irregularity']}, actuators {100 * m['actuator']:.0f} %")


@pytest.mark.subprocess
def test_a_champion_json_that_is_a_fifo_or_a_device_is_skipped_not_read_forever(tmp_path):
    """A planted champion.json that never ends (a FIFO, a link to /dev/zero) hung `sgr report` and
    `sgr migrate`: read only as a regular file, it is a champion that cannot be read (checked in
    a child process with a time limit, so a regression fails instead of hanging the suite)."""
    import os
    import subprocess
    import sys

    (tmp_path / "devzero").mkdir()
    (tmp_path / "devzero" / "champion.json").symlink_to("/dev/zero")
    (tmp_path / "fifo-run").mkdir()
    os.mkfifo(tmp_path / "fifo-run" / "champion.json")
    code = ("import sys; from pathlib import Path; from evolve.records.rundir import champion_of\n"
            "for p in sys.argv[1:]:\n"
            "    try: champion_of(Path(p))\n"
            "    except ValueError as e: print(e)")
    r = subprocess.run([sys.executable, "-c", code, str(tmp_path / "fifo-run"), str(tmp_path / "devzero")],
                       cwd=ROOT, capture_output=True, text=True, timeout=60,
                       env={**os.environ, "PYTHONPATH": str(ROOT)})
    assert r.returncode == 0, r.stderr
    assert r.stdout.splitlines() == [f"{tmp_path / d / 'champion.json'}: not a regular file"
                                     for d in ("fifo-run", "devzero")], r.stdout
