"""Checkpoints are data: a run folder written by someone else cannot make `sgr evolve --resume` run
code. Planted pickles execute nothing and are skipped with one line; an older sgr's pickled
checkpoints load only after `sgr convert-checkpoints DIR --trust-pickle`, and then resume exactly;
a checkpoint that names a function outside the fixed tables, or has a field of the wrong type, is
refused as damaged."""

from __future__ import annotations

import gzip
import json
import os
import pickle
import subprocess
import sys
from pathlib import Path

import pytest
import yaml

from evolve.cli import main
from evolve.records.rundir import RunDir, checkpoint_bytes, read_checkpoint_file
from evolve.runs.checkpoint import decode_checkpoint, load_checkpoint
from evolve.runs.experiment import Experiment
from evolve.search.neat_ini import load_neat_config

FITNESS = ["generation", "best", "mean", "median", "n_species", "n_valid", "n_invalid", "episodes"]
SMALL = {"sgr": {"neat_config": "configs/neat/sgr.ini", "pop_size": 12},
         "nested": {"neat_config": "configs/neat/nested-body.ini", "pop_size": 4, "inner_pop_size": 4,
                    "inner_generations": 1, "controller_neat_config": "configs/neat/nested-controller.ini"}}


def config(tmp_path: Path, repo_root: Path, method: str = "sgr") -> Path:
    raw = {"method": method, "task": "Walker-v0", "generations": 4, "seed": 5, "episode_steps": 8,
           "checkpoint_every": 2, "render_champion": False, "workers": 1, "robust": None,
           "final_selection": None, **SMALL[method]}
    for key in ("neat_config", "controller_neat_config"):
        if key in raw:
            raw[key] = str(repo_root / raw[key])
    p = tmp_path / f"{method}.yaml"
    p.write_text(yaml.safe_dump(raw))
    return p


def fitness(run: RunDir) -> list[list[str]]:
    return [[r[c] for c in FITNESS] for r in run.rows()]


def run(cfg: Path, out: Path, generations: int) -> RunDir:
    exp = Experiment.create(str(cfg), str(out), {"generations": generations}, quiet=True)
    exp.run_all()
    exp.close()
    return exp.run


class _MakesAFile:
    """Unpickling this calls builtins.open(path, "w"): the file appears if anything unpickles it."""
    def __init__(self, path: Path):
        self.path = str(path)

    def __reduce__(self):
        return (open, (self.path, "w"))


def planted_pickle(marker: Path) -> bytes:
    return pickle.dumps(_MakesAFile(marker), protocol=pickle.HIGHEST_PROTOCOL)


def test_the_planted_pickle_would_run_code_if_loaded(tmp_path):
    """The control for the tests below: loading the planted bytes does create the marker file."""
    marker = tmp_path / "ran"
    pickle.loads(planted_pickle(marker)).close()
    assert marker.exists()


@pytest.mark.slow
@pytest.mark.subprocess
def test_a_pickle_planted_in_checkpoints_runs_nothing_and_the_run_resumes_from_the_newest_real_one(
        tmp_path, repo_root):
    cfg = config(tmp_path, repo_root)
    full = run(cfg, tmp_path / "full", 4)
    victim = run(cfg, tmp_path / "victim", 2)  # checkpoints of generations 0 and 2
    marker = tmp_path / "code-ran"
    payload = planted_pickle(marker)
    for name in ("gen-00009.json.gz", "gen-00008.pkl", "notes.bin"):  # newest-looking, old-style, any
        (victim.ckpt_dir / name).write_bytes(payload)
    proc = subprocess.run([sys.executable, "-m", "evolve.cli", "evolve", "--resume", str(victim.path),
                           "--generations", "4", "--quiet"], capture_output=True, text=True, timeout=300)
    assert proc.returncode == 0, proc.stderr
    assert not marker.exists(), "a planted pickle was loaded"
    err = proc.stderr
    assert err.count("\n") == 1 and err.startswith("sgr: warning: skipped gen-00009.json.gz (damaged, "), err
    assert "gen-00008.pkl (a pickle, never loaded)" in err and "notes.bin (a pickle, never loaded)" in err
    assert err.endswith("resuming from gen-00002.json.gz\n")
    assert fitness(victim) == fitness(full)


def test_every_file_a_run_writes_is_data(tmp_path, repo_root):
    done = run(config(tmp_path, repo_root, "nested"), tmp_path / "run", 2)
    files = [f for f in done.path.rglob("*") if f.is_file() and f.name != ".lock"]
    assert {f.name for f in files} >= {"config.yaml", "neat.ini", "generations.csv", "champion.json",
                                       "gen-00000.json.gz", "gen-00002.json.gz"}
    for f in files:
        raw = f.read_bytes()
        assert not raw.startswith(b"\x80"), f"{f} is a pickle"
        if f.suffix == ".gz":
            data = json.loads(gzip.decompress(raw))
            assert (data["format"], data["version"], data["method"]) == ("sgr-checkpoint", 1, "nested")
            assert data["generation"] == 0 or data["problem"]["inner"], "inner populations are kept"


def _as_old_pickles(done: RunDir) -> None:
    """Replace a run's checkpoints with what an older sgr wrote: the state objects, pickled."""
    cfg = done.config()
    neat_config = load_neat_config(done.path / "neat.ini")
    for f in done.checkpoints():
        state = decode_checkpoint(read_checkpoint_file(f), cfg, neat_config)
        (f.parent / f.name.replace(".json.gz", ".pkl")).write_bytes(pickle.dumps(state))
        f.unlink()


@pytest.mark.slow
@pytest.mark.parametrize("method", ["sgr", "nested"])
def test_old_pickled_checkpoints_load_only_once_converted_with_trust_and_resume_exactly(
        tmp_path, repo_root, capsys, method):
    cfg = config(tmp_path, repo_root, method)
    full = run(cfg, tmp_path / "full", 4)
    old = run(cfg, tmp_path / "old", 2)
    _as_old_pickles(old)
    capsys.readouterr()

    assert main(["evolve", "--resume", str(old.path), "--generations", "4", "--quiet"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "holds only pickled checkpoints of an older sgr" in err
    assert err.rstrip().endswith(f"sgr migrate {old.path} --trust-pickle"), err
    assert main(["convert-checkpoints", str(old.path)]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "add --trust-pickle only if you trust" in err
    assert [f.name for f in old.pickled_checkpoints()] == ["gen-00000.pkl", "gen-00002.pkl"]

    assert main(["convert-checkpoints", str(old.path), "--trust-pickle"]) == 0
    assert old.pickled_checkpoints() == []
    assert [f.name for f in old.checkpoints()] == ["gen-00002.json.gz", "gen-00000.json.gz"]
    assert main(["evolve", "--resume", str(old.path), "--generations", "4", "--quiet"]) == 0
    assert fitness(old) == fitness(full)
    assert old.champion() == full.champion()


def test_a_sweep_with_old_pickled_runs_is_refused_before_any_run_starts(tmp_path, repo_root, capsys):
    from evolve.sweeps.sweep import Sweep

    sweep_file = tmp_path / "sweep.yaml"
    sweep_file.write_text(yaml.safe_dump({"methods": ["sgr"], "tasks": ["Walker-v0"], "seeds": 1,
                                          "overrides": {"generations": 2, "pop_size": 8, "episode_steps": 8,
                                                        "render_champion": False}}))
    sweep = Sweep.create(sweep_file, tmp_path / "sw")
    sweep.prepare(sweep.runs[0])
    _as_old_pickles(sweep.run_dir(sweep.runs[0]))
    sweep.prepare(sweep.runs[0])  # a run with old checkpoints is kept, not made anew
    assert sweep.run_dir(sweep.runs[0]).pickled_checkpoints()
    assert main(["sweep", "--resume", str(tmp_path / "sw"), "--quiet"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "sgr-Walker-v0-s0" in err
    assert err.rstrip().endswith(f"sgr migrate {tmp_path / 'sw'} --trust-pickle")


def _rewrite(f: Path, change) -> None:
    data = read_checkpoint_file(f)
    change(data)
    f.write_bytes(checkpoint_bytes({k: v for k, v in data.items() if k not in ("format", "version")}))


def _rename(d: dict, old: str, new: str) -> None:
    names = d["search"]["genomes"]["names"]
    names[names.index(old)] = new


@pytest.mark.parametrize("change, problem", [
    (lambda d: _rename(d, "tanh", "os.system"), "unknown activation or aggregation 'os.system'"),
    (lambda d: _rename(d, "sum", "builtins.eval"), "unknown activation or aggregation 'builtins.eval'"),
    (lambda d: _rename(d, "sum", "tanh"), "an activation that is an aggregation or the reverse"),
    (lambda d: d["search"]["genomes"]["fitness"].__setitem__(2, "0.5"),
     "search.genomes.fitness: expected float, got str"),
    (lambda d: d["search"]["genomes"].__setitem__("conn_weight", "AAAA"),
     "search.genomes.conn_weight: expected"),
    (lambda d: d["search"]["population"].append([10**6, 10**6]), "no genome 1000000"),
    (lambda d: d["search"]["random"].__setitem__("words", "AAAA"), "expected 625 words"),
    (lambda d: d.__setitem__("method", "direct"), "checkpoint of method 'direct'"),
    (lambda d: d.__setitem__("problem", {"inner": []}), "sgr keeps no state of its own"),
])
def test_a_checkpoint_with_a_foreign_name_or_a_wrong_field_is_refused(tmp_path, repo_root, change, problem):
    done = run(config(tmp_path, repo_root), tmp_path / "run", 2)
    for f in done.checkpoints():
        _rewrite(f, change)
    with pytest.raises(ValueError) as exc:
        load_checkpoint(done)
    msg = str(exc.value)
    assert msg.startswith(f"no usable checkpoint in {done.ckpt_dir}: gen-00002.json.gz (damaged, ")
    assert problem in msg and "\n" not in msg


def test_a_damaged_newest_checkpoint_with_bad_fields_falls_back_to_the_one_before(tmp_path, repo_root,
                                                                                  capsys):
    done = run(config(tmp_path, repo_root), tmp_path / "run", 2)
    _rewrite(done.ckpt_dir / "gen-00002.json.gz",
             lambda d: d["search"]["genomes"]["fitness"].__setitem__(0, "high"))
    state = load_checkpoint(done)
    assert state["generation"] == 0
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "search.genomes.fitness: expected float" in err
    assert os.path.exists(done.ckpt_dir / "gen-00002.json.gz")  # kept for the user to look at


def test_a_checkpoint_that_would_fill_the_memory_once_uncompressed_is_refused(tmp_path, repo_root,
                                                                               monkeypatch):
    import evolve.records.rundir as rundir

    done = run(config(tmp_path, repo_root), tmp_path / "run", 2)
    assert load_checkpoint(done)["generation"] == 2
    monkeypatch.setattr(rundir, "MAX_CHECKPOINT_BYTES", 1 << 20)
    bomb = gzip.compress(b" " * (3 << 20))  # 3 MiB of spaces: a few KiB compressed
    (done.ckpt_dir / "gen-00003.json.gz").write_bytes(bomb)
    assert len(bomb) < 20000
    assert load_checkpoint(done)["generation"] == 2  # skipped as damaged
    for f in done.checkpoints():
        f.write_bytes(bomb)
    with pytest.raises(ValueError, match="over 1 MiB once uncompressed"):
        load_checkpoint(done)
