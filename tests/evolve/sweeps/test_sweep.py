"""Sweeps: a sweep's runs depend on their configs alone (killed and resumed = uninterrupted), bad
sweep files are one line, and `sgr report` writes its three files from the runs."""

from __future__ import annotations

import csv
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest
import yaml

from evolve.cli import main
from evolve.records.rundir import RunDir

FITNESS_COLUMNS = ["generation", "best", "mean", "median", "n_species", "n_valid", "n_invalid", "episodes"]
TINY = {"methods": ["sgr", "nested"], "tasks": ["Walker-v0"], "seeds": [0, 4],
        "overrides": {"robust": None, "final_selection": None,  # the paper's nominal evaluation
                      "generations": 4, "pop_size": 8, "episode_steps": 12, "checkpoint_every": 2,
                      "render_champion": False, "workers": 1,
                      "nested": {"pop_size": 4, "inner_pop_size": 4, "inner_generations": 1}}}


def write_sweep(tmp_path: Path, sweep: dict, name: str = "sweep.yaml") -> Path:
    p = tmp_path / name
    p.write_text(yaml.safe_dump(sweep))
    return p


def fitness(run_dir: Path) -> list[list[str]]:
    return [[r[c] for c in FITNESS_COLUMNS] for r in RunDir(run_dir).rows()]


def run_names() -> list[str]:
    return [f"{m}-Walker-v0-s{s}" for m in TINY["methods"] for s in TINY["seeds"]]


def best_seeds(sweep: Path) -> list[tuple[str, int]]:
    """(method, seed) of the best champion of each method by its headline, the figure the report
    shows (ties: the lower seed)."""
    out = []
    for m in TINY["methods"]:
        fit = {s: RunDir(sweep / "runs" / f"{m}-Walker-v0-s{s}").champion()["headline"]["return"]
               for s in TINY["seeds"]}
        out.append((m, max(TINY["seeds"], key=lambda s: (fit[s], -s))))
    return out


# shorter: each method's SIGKILLed run resumes (runs/test_resume.py); a sweep's stop (runs/test_stops.py)
@pytest.mark.long
@pytest.mark.slow
@pytest.mark.subprocess
def test_a_killed_sweep_resumes_to_the_same_runs(tmp_path):
    spec = write_sweep(tmp_path, TINY)
    assert main(["sweep", "--config", str(spec), "--out", str(tmp_path / "whole"), "--quiet"]) == 0

    cut = tmp_path / "cut"
    proc = subprocess.Popen([sys.executable, "-m", "evolve.cli", "sweep", "--config", str(spec),
                             "--out", str(cut), "--quiet"], stdout=subprocess.DEVNULL, stderr=subprocess.PIPE)
    third = cut / "runs" / run_names()[2] / "generations.csv"  # killed inside the third run
    deadline = time.monotonic() + 120
    while not (third.is_file() and len(RunDir(third.parent).rows()) >= 1):
        assert proc.poll() is None, proc.stderr.read()
        assert time.monotonic() < deadline
        time.sleep(0.01)
    os.kill(proc.pid, signal.SIGKILL)
    proc.wait()
    # the run's own process dies with the sweep (it would otherwise finish the run by itself)
    pid = (third.parent / ".lock").read_text().strip()
    deadline = time.monotonic() + 1.0
    while os.path.exists(f"/proc/{pid}") and "zombie" not in Path(f"/proc/{pid}/status").read_text():
        assert time.monotonic() < deadline, "a run process outlived its killed sweep"
        time.sleep(0.01)
    time.sleep(1.0)
    assert len(RunDir(third.parent).rows()) < 4
    assert main(["sweep", "--resume", str(cut), "--quiet"]) == 0

    for name in run_names():
        a, b = fitness(tmp_path / "whole" / "runs" / name), fitness(cut / "runs" / name)
        assert len(a) == 4 and a == b, name
    # every run is an ordinary run directory with the sweep's overrides and its own seed
    raw = RunDir(cut / "runs" / "nested-Walker-v0-s4").config()
    assert (raw["seed"], raw["pop_size"], raw["inner_pop_size"], raw["generations"]) == (4, 4, 4, 4)
    stored = yaml.safe_load((cut / "sweep.yaml").read_text())
    assert stored["seeds"] == [0, 4] and Path(stored["configs"]).is_absolute()

    out = tmp_path / "report" / "paper.md"
    assert main(["report", str(cut), "--out", str(out)]) == 0
    assert {p.name for p in out.parent.iterdir()} == {"paper.md", "summary.csv", "curves.png", "report.html",
                                                      "gallery"}
    # the best seed of each method and task: its episode and its body
    assert sorted(p.name for p in (out.parent / "gallery").iterdir()) == sorted(
        f"{m}-Walker-v0-s{s}{ext}" for m, s in best_seeds(cut) for ext in (".gif", "-body.png"))
    rows = list(csv.DictReader((out.parent / "summary.csv").open()))
    assert sorted(r["run"] for r in rows) == sorted(run_names())
    for r in rows:
        best = max(float(x[1]) for x in fitness(cut / "runs" / r["run"]))
        assert float(r["best_final"]) == best and float(r["champion_fitness"]) == best
        assert float(r["replay"]) == pytest.approx(best, abs=1e-9)  # the JSON champion replays
        assert float(r["nominal"]) == float(r["replay"])  # nominal runs: the same episode
        assert set(r) >= {"noise1e-09_mean", "noise1e-03_min", "noise1e-03_ratio"}
    text = out.read_text()
    assert "| sgr | Walker-v0 | 2 (seeds 0, 4) | 4 |" in text and "5.75 / 6.09 / 6.56 / 6.60" in text
    assert (out.parent / "curves.png").read_bytes()[:4] == b"\x89PNG"


@pytest.mark.parametrize("change, message", [
    ({"methods": ["cmaes"]}, "key 'methods' must be a list of sgr, direct, nested"),
    ({"tasks": ["Jumper-v9"]}, "key 'tasks': unknown task 'Jumper-v9'; did you mean Jumper-v0"),
    ({"seeds": -1}, "key 'seeds' must be a count from 1 to 10,000 or a list of seeds"),
    ({"seeds": 10**9}, "key 'seeds' must be a count from 1 to 10,000"),  # a typo, not a day's listing
    ({"seeds": [*range(2000), -1]}, "got [0, 1, 2, 3,"),  # the value cut short in the line
    ({"seeds": 3334, "methods": ["sgr", "direct", "nested"]}, "3 methods x 1 tasks x 3334 seeds is more "
                                                               "than 10,000 runs"),
    ({"overrides": {"popsize": 3}}, "unknown key 'popsize'"),
    ({"overrides": {"nested": {"layout": "per_cell"}}}, "unknown key 'layout' for method 'nested'"),
    ({"overrides": {"seed": 3}}, "must not set 'seed'"),
    ({"configs": "nowhere"}, "no config for sgr on Walker-v0"),
    ({"budget": 3}, "unknown key 'budget'"),
])
def test_a_bad_sweep_file_is_one_error_line_and_no_sweep(tmp_path, capsys, change, message):
    spec = write_sweep(tmp_path, {**TINY, **change})
    assert main(["sweep", "--config", str(spec), "--out", str(tmp_path / "s")]) == 2
    err = capsys.readouterr().err
    assert err.startswith("sgr: error:") and message in err and err.count("\n") == 1, err
    assert "1999" not in err  # a long value is cut short in the line
    assert not (tmp_path / "s").exists()


def test_a_sweep_file_that_is_not_a_mapping_and_a_folder_that_is_not_a_sweep(tmp_path, capsys):
    (tmp_path / "list.yaml").write_text("- sgr\n")
    assert main(["sweep", "--config", str(tmp_path / "list.yaml"), "--out", str(tmp_path / "s")]) == 2
    assert "a sweep must be a mapping" in capsys.readouterr().err
    assert main(["sweep", "--resume", str(tmp_path)]) == 2
    assert "is not a sweep directory" in capsys.readouterr().err
    assert main(["report", str(tmp_path)]) == 2
    assert "holds no run directories" in capsys.readouterr().err


def test_report_names_champions_that_do_not_replay_to_their_fitness():
    """champion.json alone must reproduce a run's fitness; where the unperturbed replay differs,
    report.md says so with both numbers, and says nothing when every replay agrees."""
    from evolve.report.report import report_markdown

    base = {"method": "direct", "task": "Walker-v0", "generations": 100, "best_final": 2.0,
            "best_gen1": 1.0, "best_gen30": 1.5, "best_gen100": 2.0, "noise1e-09_mean": 2.0,
            "noise1e-09_sd": 0.0, "noise1e-09_min": 2.0, "champion_fitness": 2.0, "nominal": 2.0}
    rows = [{**base, "seed": 0, "run": "direct-Walker-v0-s0", "replay": 2.0},
            {**base, "seed": 1, "run": "direct-Walker-v0-s1", "replay": 1.5}]
    text = report_markdown(rows)
    assert "1 of 2 champions do not replay" in text and "direct-Walker-v0-s1 2 -> 1.5" in text
    rows[1]["replay"] = 2.0
    assert "do not replay" not in report_markdown(rows)


@pytest.mark.slow
@pytest.mark.subprocess
def test_a_ray_task_passes_on_a_stop_marked_while_its_run_starts_and_starts_none_after_it(tmp_path):
    """The Ray backend's stop mark (evolve/sweeps/ray_sweep.py: Ray's cancel can be lost), run as a
    plain function: marked as the task's run is still starting (its program not yet in its loop), the
    stop is held and the run ends its first generation with a checkpoint (exit 138: SIGUSR1's stop),
    neither dying of SIGUSR1 nor going on to its end; a task that finds the mark starts no run."""
    import threading

    from evolve.sweeps.ray_sweep import STOPPED, _run_on_node
    from evolve.sweeps.sweep import Sweep

    spec = write_sweep(tmp_path, {**TINY, "methods": ["sgr"], "seeds": [0, 1]})
    sweep = Sweep.create(spec, tmp_path / "sweep")
    first, second = sweep.runs
    for run in (first, second):
        sweep.prepare(run)
    mark = tmp_path / "sweep" / ".stop-test"
    got = []
    task = threading.Thread(target=lambda: got.append(_run_on_node(str(sweep.run_dir(first).path), 1, (),
                                                                    str(mark))))
    run = sweep.run_dir(first)
    task.start()
    deadline = time.monotonic() + 60
    while not (run.path / "log.txt").exists():  # made just before the run's process starts
        assert time.monotonic() < deadline and task.is_alive()
        time.sleep(0.001)
    mark.touch()  # the run's program is starting (Python, its imports, Taichi): not yet in its loop
    task.join(timeout=300)
    assert got == [STOPPED], (run.path / "log.txt").read_text()
    assert len(run.rows()) == 1 and run.last_checkpoint_generation() == 1
    assert "asked by the sweep: stopping after this generation" in (run.path / "log.txt").read_text()

    assert _run_on_node(str(sweep.run_dir(second).path), 1, (), str(mark)) == STOPPED
    assert not (sweep.run_dir(second).path / "log.txt").exists()  # no run was started
    assert sweep.run_dir(second).last_checkpoint_generation() == 0
