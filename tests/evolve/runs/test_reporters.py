"""Reporters watch the generation loop (start, each generation's row, end) without editing it, and
the TensorBoard reporter writes each generation's scalars as generations.csv has them."""

from __future__ import annotations

import struct
import sys
from pathlib import Path

import numpy as np
import pytest

from evolve.cli import main
from evolve.records.rundir import RunDir
from evolve.runs.experiment import Experiment

TINY = {"method": "sgr", "task": "Walker-v0", "generations": 3, "pop_size": 8, "seed": 11,
        "episode_steps": 12, "workers": 1, "render_champion": False,
        "robust": None, "final_selection": None}  # one exact episode: the best-ever is the best row's


class Recorder:
    """Every hook call, with what the run had done at that moment."""

    def __init__(self):
        self.calls = []

    def start(self, exp):
        self.calls.append(("start", exp.search.generation))

    def generation(self, exp, row):
        # the row, the champion and (when due) the checkpoint are written before the reporters
        self.calls.append(("generation", dict(row), len(exp.run.rows())))

    def end(self, exp):
        self.calls.append(("end", exp.search.generation))


def test_a_reporter_sees_the_start_each_generations_csv_row_once_written_and_the_end(tmp_path):
    rec = Recorder()
    only_rows = []

    class OnlyRows:  # a reporter with one hook of three
        def generation(self, exp, row):
            only_rows.append(row["generation"])

    with Experiment.from_config(TINY, tmp_path / "run", quiet=True) as exp:
        exp.add_reporter(rec)
        exp.add_reporter(OnlyRows())
        exp.run_all()
    rows = RunDir(tmp_path / "run").rows()
    assert [c[0] for c in rec.calls] == ["start", "generation", "generation", "generation", "end"]
    assert rec.calls[0] == ("start", 0) and rec.calls[-1] == ("end", 3)
    for i, (_, row, written) in enumerate(rec.calls[1:-1]):
        assert written == i + 1  # its row is in generations.csv already
        assert {k: str(v) if isinstance(v, int) else repr(float(v)) for k, v in row.items()} == rows[i]
    assert only_rows == [1, 2, 3]


def test_a_reporter_hears_the_end_of_a_stopped_loop_and_one_without_hooks_is_refused(tmp_path):
    rec = Recorder()

    def stop(exp):
        raise KeyboardInterrupt

    with Experiment.from_config(TINY, tmp_path / "run", quiet=True) as exp:
        with pytest.raises(TypeError, match="a reporter needs one of the methods start, generation, end"):
            exp.add_reporter(object())
        exp.add_reporter(rec)
        with pytest.raises(KeyboardInterrupt):
            exp.run_all(after_generation=stop)
    assert [c[0] for c in rec.calls] == ["start", "generation", "end"]


def tfrecords(path: Path) -> list[bytes]:
    """The records of a TFRecord file (TensorBoard's event files): length, its CRC, data, its CRC."""
    data, out, i = path.read_bytes(), [], 0
    while i < len(data):
        (n,) = struct.unpack("<Q", data[i:i + 8])
        out.append(data[i + 12:i + 12 + n])
        i += 12 + n + 4
    return out


def scalars(folder: Path) -> dict[str, dict[int, float]]:
    """tag -> step -> value of every scalar in the event files under `folder` (a later file's value
    for a step replaces an earlier one's)."""
    from tensorboardX.proto.event_pb2 import Event

    out: dict[str, dict[int, float]] = {}
    for f in sorted(folder.glob("events.out.tfevents.*")):
        for rec in tfrecords(f):
            ev = Event.FromString(rec)
            for v in ev.summary.value:
                out.setdefault(v.tag, {})[ev.step] = v.simple_value
    return out


def test_tensorboard_events_hold_each_generations_scalars_as_generations_csv_has_them(tmp_path):
    pytest.importorskip("tensorboardX", reason="the tensorboard extra: pip install 'sgr[tensorboard]'")
    with Experiment.from_config({**TINY, "tensorboard": True}, tmp_path / "run", quiet=True) as exp:
        exp.run_all()
    run = RunDir(tmp_path / "run")
    got = scalars(run.path / "tensorboard")
    rows = run.rows()
    f32 = np.float32  # TensorBoard keeps a scalar as a float32

    def column(name, of=float):
        return {int(r["generation"]): f32(of(r[name]) if callable(of) else r[name]) for r in rows}

    for tag, col in [("fitness/best", "best"), ("fitness/mean", "mean"), ("fitness/median", "median"),
                     ("population/species", "n_species"), ("population/episodes", "episodes"),
                     ("seconds/build", "build_s"), ("seconds/sim", "sim_s"), ("seconds/neat", "neat_s"),
                     ("seconds/total", "total_s")]:
        assert got[tag] == column(col), tag
    genomes = {int(r["generation"]): int(r["n_valid"]) + int(r["n_invalid"]) for r in rows}
    assert got["population/genomes"] == {g: f32(n) for g, n in genomes.items()}
    assert got["population/valid_fraction"] == {
        int(r["generation"]): f32(int(r["n_valid"]) / genomes[int(r["generation"])]) for r in rows}
    bests = [float(r["best"]) for r in rows]
    assert got["fitness/best_ever"] == {g: f32(max(bests[:g])) for g in range(1, len(rows) + 1)}
    assert got["fitness/best_ever"][3] == f32(run.champion()["fitness"])


@pytest.mark.slow
def test_sgr_evolve_tensorboard_flag_writes_the_events_and_without_the_extra_says_how_to_install(
        tmp_path, repo_root, capsys, monkeypatch):
    import yaml

    pytest.importorskip("tensorboardX", reason="the tensorboard extra: pip install 'sgr[tensorboard]'")
    cfg = tmp_path / "cfg.yaml"
    cfg.write_text(yaml.safe_dump({**TINY, "generations": 1,
                                   "neat_config": str(repo_root / "configs/neat/sgr.ini")}))
    assert main(["evolve", "--config", str(cfg), "--out", str(tmp_path / "on"), "--quiet",
                 "--tensorboard"]) == 0
    assert RunDir(tmp_path / "on").config()["tensorboard"] is True  # a resume goes on logging
    assert scalars(tmp_path / "on" / "tensorboard")["fitness/best"].keys() == {1}
    # a run made without it logs the part of it a --resume --tensorboard runs
    assert main(["evolve", "--config", str(cfg), "--out", str(tmp_path / "later"), "--quiet"]) == 0
    assert not (tmp_path / "later" / "tensorboard").exists()
    assert main(["evolve", "--resume", str(tmp_path / "later"), "--generations", "2", "--quiet",
                 "--tensorboard"]) == 0
    assert scalars(tmp_path / "later" / "tensorboard")["fitness/best"].keys() == {2}

    monkeypatch.setitem(sys.modules, "tensorboardX", None)  # the extra not installed
    capsys.readouterr()
    assert main(["evolve", "--config", str(cfg), "--out", str(tmp_path / "off"), "--quiet",
                 "--tensorboard"]) == 0
    err = capsys.readouterr().err.strip().splitlines()
    assert err == ["sgr: warning: tensorboard: true, but tensorboardX is not installed: pip install "
                   "'sgr[tensorboard]' (or: pip install tensorboardX); the run goes on without TensorBoard "
                   "logging"]
    assert not (tmp_path / "off" / "tensorboard").exists()
    assert len(RunDir(tmp_path / "off").rows()) == 1


def test_a_resumed_run_tells_tensorboard_to_drop_the_generations_it_computes_again(tmp_path):
    """Stopped after generation 3 with its newest checkpoint at 2: the resumed process computes
    generation 3 again, and its events file starts with TensorBoard's purge marker (a SessionLog
    START at step 3: earlier events of steps >= 3 are dropped), so each generation shows once; the
    values read back, the newer file's winning, are generations.csv's."""
    pytest.importorskip("tensorboardX", reason="the tensorboard extra: pip install 'sgr[tensorboard]'")
    from tensorboardX.proto.event_pb2 import Event, SessionLog

    cfg = {**TINY, "generations": 4, "checkpoint_every": 2, "tensorboard": True}

    def stop(exp):
        if exp.search.generation == 3:
            raise KeyboardInterrupt

    with Experiment.from_config(cfg, tmp_path / "run", quiet=True) as exp:
        with pytest.raises(KeyboardInterrupt):
            exp.run_all(after_generation=stop)
    with Experiment.resume(tmp_path / "run", quiet=True) as exp:
        exp.run_all()
    files = sorted((tmp_path / "run" / "tensorboard").glob("events.out.tfevents.*"))
    assert len(files) == 2
    starts = [[ev.step for ev in map(Event.FromString, tfrecords(f))
               if ev.HasField("session_log") and ev.session_log.status == SessionLog.START] for f in files]
    assert starts == [[], [3]]
    rows = RunDir(tmp_path / "run").rows()
    assert scalars(files[0].parent)["fitness/best"] == {int(r["generation"]): np.float32(r["best"])
                                                        for r in rows}


def test_the_console_line_can_be_replaced_and_the_files_stay_the_loops(tmp_path, capsys):
    """A user's reporter takes the built-in console line's place without editing the loop: its line
    is printed, the built-in one is not, and generations.csv and the checkpoints are still written."""
    from evolve.runs.reporters import ConsoleProgress

    class Mine:
        def generation(self, exp, row):
            print(f"mine {row['generation']}")

    with Experiment.from_config(TINY, tmp_path / "run", quiet=False) as exp:
        exp.replace_reporter(ConsoleProgress, Mine())
        with pytest.raises(ValueError, match="no reporter of type int"):
            exp.replace_reporter(int, Mine())
        exp.run_all()
    out = capsys.readouterr().out
    assert [line for line in out.splitlines() if line.startswith("mine")] == ["mine 1", "mine 2", "mine 3"]
    assert "best" not in out
    run = RunDir(tmp_path / "run")
    assert [r["generation"] for r in run.rows()] == ["1", "2", "3"]
    assert (tmp_path / "run" / "champion.json").is_file()


def test_a_checkpointer_of_another_schedule_writes_every_generation(tmp_path):
    """The checkpoint schedule is a reporter: one that checkpoints every generation replaces the
    config's (checkpoint_every 5: generation 0's stays the newest until the last)."""
    from evolve.runs.reporters import Checkpointer

    class Newest:  # added after the built-ins: sees each generation's checkpoint written
        def __init__(self):
            self.names = []

        def generation(self, exp, row):
            self.names.append(exp.run.checkpoints()[0].name)

    newest = {}
    for name, every in (("default", None), ("every", 1)):
        with Experiment.from_config({**TINY, "checkpoint_every": 5}, tmp_path / name, quiet=True) as exp:
            if every:
                exp.replace_reporter(Checkpointer, Checkpointer(every=every))
            newest[name] = Newest()
            exp.add_reporter(newest[name])
            exp.run_all()
    assert newest["default"].names == ["gen-00000.json.gz", "gen-00000.json.gz", "gen-00003.json.gz"]
    assert newest["every"].names == ["gen-00001.json.gz", "gen-00002.json.gz", "gen-00003.json.gz"]


def test_the_console_line_names_the_decoding_time_and_the_body_diversity(capsys):
    """build_s is the generation's decoding: the line says "decode"; the body diversity follows,
    left out for a method without bodies (NaN)."""
    from types import SimpleNamespace

    from evolve.runs.reporters import ConsoleProgress

    exp = SimpleNamespace(quiet=False, search=SimpleNamespace(best=None), cfg=SimpleNamespace(generations=3))
    line = ConsoleProgress()
    line.start(exp)
    row = {"generation": 2, "best": 1.0, "mean": 0.5, "n_species": 3, "n_valid": 7, "n_invalid": 1,
           "total_s": 4.0, "build_s": 0.125, "sim_s": 3.5, "neat_s": 0.25, "body_diversity": 0.3125}
    line.generation(exp, row)
    line.generation(exp, {**row, "body_diversity": float("nan")})
    first, second = capsys.readouterr().out.splitlines()
    assert "(decode 0.12 sim 3.50 neat 0.25)  diversity 0.312 " in first
    assert "(decode 0.12 sim 3.50 neat 0.25)  " in second and "diversity" not in second


def test_tensorboard_has_the_body_diversity_where_the_method_has_bodies():
    """population/body_diversity is the row's value; a row without bodies (NaN) gives no such tag."""
    from types import SimpleNamespace

    from evolve.runs.reporters import tensorboard_scalars

    exp = SimpleNamespace(search=SimpleNamespace(best=None))
    row = {"best": 1.0, "mean": 0.5, "median": 0.5, "n_species": 3, "n_valid": 6, "n_invalid": 2,
           "episodes": 6, "build_s": 0.1, "sim_s": 1.0, "neat_s": 0.2, "total_s": 1.3,
           "body_diversity": 0.375}
    assert tensorboard_scalars(exp, row)["population/body_diversity"] == 0.375
    without = tensorboard_scalars(exp, {**row, "body_diversity": float("nan")})
    assert "population/body_diversity" not in without


def test_the_consoles_seconds_go_on_after_a_resume(tmp_path, capsys):
    """The console line's last column counts the run's seconds, those before a resume included
    (the generations' total_s in generations.csv): it restarted from 0 on every resume."""
    import csv

    from tests.evolve.conftest import TINY as TWO_GENERATIONS

    with Experiment.from_config({"method": "direct", **TWO_GENERATIONS}, tmp_path / "run", quiet=True) as exp:
        exp.run_all()
    rows = list(csv.DictReader((tmp_path / "run" / "generations.csv").open()))
    for r in rows:  # as if each generation had taken a thousand seconds
        r["total_s"] = "1000.0"
    with (tmp_path / "run" / "generations.csv").open("w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=list(rows[0]), lineterminator="\n")
        w.writeheader()
        w.writerows(rows)
    capsys.readouterr()
    with Experiment.resume(RunDir(tmp_path / "run").path, generations=3) as exp:
        exp.run_all()
    line = next(x for x in capsys.readouterr().out.splitlines() if x.startswith("gen    3/3"))
    assert 2000 <= float(line.split()[-2]) < 2100, line
