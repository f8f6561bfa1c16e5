"""A damaged elites.json (a map-elites run's archive, evolve/records/elites.py) is one line naming
its bad key wherever it is read (`sgr render --cell`, `sgr report`), not a traceback: reading a run
folder's data never fails on what the data holds."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from evolve.cli import main
from evolve.records.elites import FORMAT, elite_record

GOOD_ELITE = {"cell": [0, 0], "measures": {"actuator": 0.4, "rigid": 0.2},
              "champion": {"fitness": 1.0, "body": [[3, 3], [3, 3]]}}
GOOD = {"format": FORMAT, "generation": 2, "descriptors": ["actuator", "rigid"], "ranges": [[0, 1], [0, 1]],
        "resolution": [3, 3], "coverage": 1 / 9, "qd_score": 1.0, "elites": [GOOD_ELITE]}


def run_with(tmp_path: Path, data: dict) -> Path:
    run = tmp_path / "run"
    run.mkdir()
    (run / "elites.json").write_text(json.dumps(data))
    return run


def test_an_intact_archive_gives_its_elite(tmp_path):
    """The control: the same file undamaged is read (so the damaged cases fail for their damage)."""
    assert elite_record(run_with(tmp_path, GOOD), (0, 0)) == GOOD_ELITE["champion"]


@pytest.mark.parametrize("change, named", [
    ({"resolution": None}, "key 'resolution'"),
    ({"elites": [{"cell": 5}]}, "key 'elites[0].cell'"),
    ({"elites": [{**GOOD_ELITE, "champion": {"body": [[3]]}}]}, "key 'elites[0].champion'"),
    ({"elites": [{**GOOD_ELITE, "measures": []}]}, "key 'elites[0].measures'"),
    ({"ranges": [[0, 1]]}, "key 'ranges'"),
    ({"elites": [{**GOOD_ELITE, "cell": [3, 0]}]}, "key 'elites[0].cell'"),
])
def test_a_damaged_archive_is_one_line_naming_its_key(tmp_path, capsys, change, named):
    """`sgr render RUN --cell 0,0` on an elites.json with one bad key: exit 2, one line naming it."""
    run = run_with(tmp_path, {**GOOD, **change})
    assert main(["render", str(run), "--cell", "0,0", "--exact"]) == 2
    err = capsys.readouterr().err
    assert len(err.strip().splitlines()) == 1 and named in err, err


@pytest.mark.parametrize("cell", [(0.9, 0.2), (True, False), None])
def test_a_cell_that_is_not_integer_indices_is_refused(tmp_path, cell):
    """(0.9, 0.2) silently gave cell (0, 0)'s elite."""
    from tsim.errors import SgrError

    run = run_with(tmp_path, GOOD)
    assert elite_record(run, [0, 0]) == elite_record(run, "0,0") == GOOD_ELITE["champion"]
    assert elite_record(run, __import__("numpy").array([0, 0])) == GOOD_ELITE["champion"]
    with pytest.raises(SgrError, match="a cell is a tuple of integer indices"):
        elite_record(run, cell)


def test_a_compact_archive_elites_json_gz_reads_as_its_json(tmp_path, monkeypatch):
    """A results folder keeps its archive as elites.json.gz: it reads as the JSON it holds; one that
    would inflate past the record cap is refused in one line, without inflating it whole."""
    import gzip

    import evolve.records.elites as elites_module
    from evolve.records.elites import read_elites
    from tsim.errors import SgrError

    run = tmp_path / "run"
    run.mkdir()
    (run / "elites.json.gz").write_bytes(gzip.compress(json.dumps(GOOD).encode(), mtime=0))
    assert read_elites(run) == GOOD and elite_record(run, "0,0") == GOOD_ELITE["champion"]
    bomb = tmp_path / "bomb"
    bomb.mkdir()
    (bomb / "elites.json.gz").write_bytes(gzip.compress(b" " * (3 * 2**20), mtime=0))
    monkeypatch.setattr(elites_module, "RECORD_CAP", 2**20)
    with pytest.raises(SgrError, match="uncompressed"):
        read_elites(bomb)


def test_the_committed_archives_read(repo_root):
    """results/map-elites keeps its six archives gzipped: each reads whole (100 generations, 60+
    elites)."""
    from evolve.records.elites import read_elites

    runs = sorted((repo_root / "results" / "map-elites" / "runs").iterdir())
    assert len(runs) == 6
    for run in runs:
        data = read_elites(run)
        assert len(data["elites"]) >= 60 and data["generation"] == 100
