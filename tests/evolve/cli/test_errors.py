"""What the `sgr` command shows when something fails.

Bad input (SgrError) is one line on stderr, `sgr: error: ...` naming the file or key, exit code 2,
never a traceback. Where the error could come from import-time or worker code (Taichi's start-up,
rollout worker processes) the CLI runs as a real subprocess; pure-Python paths run in-process.
An internal error keeps its traceback (any other exception: the traceback itself; a ValueError
that is not an SgrError: one line plus the file holding its traceback); `--debug` shows every
traceback; an error in a user's task module shows the user's own code."""

import json
import os
import shutil
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
import yaml

from evolve.cli import main
from tasks.env import obs_dim
from tsim.backend import runtime

ROOT = Path(__file__).resolve().parents[3]
NO_CUDA = shutil.which("nvidia-smi") is None


def run_cli(*args, cwd, env=None) -> tuple[int, str]:
    base = {k: v for k, v in os.environ.items() if k not in ("SGR_ARCH", "SGR_THREADS")}
    r = subprocess.run([sys.executable, "-m", "evolve.cli", *args], cwd=cwd, capture_output=True,
                       text=True, env={**base, **(env or {})}, timeout=300)
    return r.returncode, r.stderr


def one_error(rc: int, err: str, *names: str) -> str:
    assert rc == 2, err
    assert "Traceback" not in err, err
    lines = err.splitlines()
    assert len(lines) == 1, err
    assert lines[0].startswith("sgr: error: "), err
    for name in names:
        assert name in lines[0], (name, err)
    return lines[0]


def in_process(capsys, *argv: str, names=()) -> str:
    rc = main(list(argv))
    return one_error(rc, capsys.readouterr().err, *map(str, names))


def tiny_config(tmp_path, repo_root, name="tiny.yaml", **changes):
    cfg = {"method": "sgr", "task": "Walker-v0", "generations": 1, "pop_size": 4, "episode_steps": 2,
           "render_champion": False, "neat_config": str(repo_root / "configs/neat/sgr.ini"), "robust": None,
           "final_selection": None, **changes}
    p = tmp_path / name
    p.write_text(yaml.safe_dump(cfg))
    return p


# ---------------------------------------------------------------- subprocess: Taichi and workers
@pytest.mark.slow
@pytest.mark.subprocess
def test_config_that_is_a_list(tmp_path):
    (tmp_path / "list.yaml").write_text("- method: sgr\n- task: Walker-v0\n")
    line = one_error(*run_cli("evolve", "--config", "list.yaml", "--out", "r", cwd=tmp_path), "list.yaml")
    assert "mapping" in line and not (tmp_path / "r").exists()


@pytest.mark.slow
@pytest.mark.subprocess
def test_unknown_arch(tmp_path, repo_root):
    env = {"SGR_ARCH": "foo"}
    one_error(*run_cli("bench", "--robots", "2", "--steps", "2", cwd=tmp_path, env=env), "SGR_ARCH=foo")
    cfg = tiny_config(tmp_path, repo_root, workers=2)
    one_error(*run_cli("evolve", "--config", str(cfg), "--out", "r", "--quiet", cwd=tmp_path, env=env),
              "SGR_ARCH=foo")
    assert not (tmp_path / "r").exists()  # checked before the run directory is made


@pytest.mark.slow
@pytest.mark.subprocess
@pytest.mark.skipif(not NO_CUDA, reason="this machine may have CUDA")
def test_unavailable_arch_in_this_process(tmp_path):
    line = one_error(*run_cli("bench", "--robots", "2", "--steps", "2", cwd=tmp_path,
                              env={"SGR_ARCH": "cuda"}), "SGR_ARCH=cuda")
    assert "cannot run on cuda here" in line


@pytest.mark.slow
@pytest.mark.subprocess
@pytest.mark.skipif(sys.platform == "darwin", reason="Metal exists on macOS")
def test_unavailable_arch_in_rollout_workers(tmp_path, repo_root):
    """Taichi starts in the worker processes only: their error reaches the user as one line."""
    cfg = tiny_config(tmp_path, repo_root, workers=2)
    line = one_error(*run_cli("evolve", "--config", str(cfg), "--out", "r", "--quiet", cwd=tmp_path,
                              env={"SGR_ARCH": "metal"}), "SGR_ARCH=metal")
    assert "cannot run on metal here" in line


# ---------------------------------------------------------------- in-process: the rest
def test_bad_environment_values_name_the_variable(monkeypatch):
    monkeypatch.setenv("SGR_ARCH", "foo")
    with pytest.raises(ValueError, match="SGR_ARCH=foo: unknown arch"):
        runtime.requested_arch()
    for bad in ("abc", "0"):
        monkeypatch.setenv("SGR_THREADS", bad)
        with pytest.raises(ValueError, match=f"SGR_THREADS={bad}: must be a positive int"):
            runtime.threads()


def test_missing_and_invalid_config(tmp_path, capsys):
    in_process(capsys, "evolve", "--config", str(tmp_path / "nope.yaml"), names=["nope.yaml"])
    bad = tmp_path / "bad.yaml"
    bad.write_text("method: sgr\ntask: [Walker-v0\n")
    assert "line 3" in in_process(capsys, "evolve", "--config", str(bad), names=[bad, "not valid YAML"])


def with_value(ini: str, key: str, value: str) -> str:
    lines = [f"{key} = {value}" if line.split("=")[0].strip() == key else line for line in ini.splitlines()]
    assert lines != ini.splitlines()
    return "\n".join(lines)


INIS = {"no section header": ("garbage\n", "line 1"),
        "missing section": ("[NEAT]\npop_size = 3\n", "[DefaultGenome]"),
        "duplicate section": ("[NEAT]\n[NEAT]\n", "appears twice"),
        "not key = value": ("[NEAT]\nfoo\n", "line 2"),
        "bad value": (None, "num_hidden")}


@pytest.mark.parametrize("case", INIS)
def test_broken_neat_ini(tmp_path, repo_root, capsys, case):
    text, detail = INIS[case]
    if text is None:
        text = with_value((repo_root / "configs/neat/sgr.ini").read_text(), "num_hidden", "xyz")
    ini = tmp_path / "broken.ini"
    ini.write_text(text)
    cfg = tiny_config(tmp_path, repo_root, neat_config=str(ini))
    in_process(capsys, "evolve", "--config", str(cfg), "--out", str(tmp_path / "r"), names=[ini, detail])
    assert not (tmp_path / "r").exists()


def test_missing_neat_ini(tmp_path, repo_root, capsys):
    cfg = tiny_config(tmp_path, repo_root, neat_config="nothere.ini")
    in_process(capsys, "evolve", "--config", str(cfg), names=["neat_config", "nothere.ini"])


@pytest.mark.parametrize("ini", ["garbage\n", None, "missing"])
def test_broken_nested_controller_ini(tmp_path, repo_root, capsys, ini):
    raw = yaml.safe_load((repo_root / "configs/nested/Walker-v0.yaml").read_text())
    raw["neat_config"] = str(repo_root / "configs/neat/nested-body.ini")
    ctrl = tmp_path / "ctrl.ini"
    if ini is None:  # valid INI, a value neat-python rejects
        ini = (repo_root / "configs/neat/nested-controller.ini").read_text()
        ini = with_value(ini, "bias_init_mean", "x")
    if ini != "missing":
        ctrl.write_text(ini)
    raw.update(controller_neat_config=str(ctrl), generations=1)
    p = tmp_path / "nested.yaml"
    p.write_text(yaml.safe_dump(raw))
    in_process(capsys, "evolve", "--config", str(p), "--out", str(tmp_path / "r"), names=[ctrl])
    assert not (tmp_path / "r").exists()


def _dense(n_in: int, n_out: int, action_cells: list[int]) -> dict:
    return {"layers": [{"weights": np.zeros((n_in, n_out)).tolist(), "biases": [0.0] * n_out,
                        "activation": "tanh"}], "input_size": n_in, "action_cells": action_cells}


BODY = [[3, 3, 3]]  # 8 points, 3 actuators
OBS = obs_dim("Walker-v0", 8)
GOOD = {"task": "Walker-v0", "episode_steps": 4, "body": BODY, "controller": _dense(OBS, 3, [0, 1, 2])}
CHAMPIONS = {"not JSON": ("{not json", "not valid JSON"),
             "a list": ([1, 2], "JSON object"),
             "missing keys": ({"task": "Walker-v0"}, "missing keys episode_steps, body, controller"),
             "unknown task": ({**GOOD, "task": "Runner-v9"}, "key 'task'"),
             "bad body": ({**GOOD, "body": [[3, 0, 3]]}, "key 'body': bad body matrix"),
             "body of text": ({**GOOD, "body": "xyz"}, "key 'body': bad body matrix"),
             "controller lacks keys": ({**GOOD, "controller": {}}, "key 'controller'"),
             "controller for another body": ({**GOOD, "controller": _dense(5, 3, [0, 1, 2])}, "controller"),
             "too few actions": ({**GOOD, "controller": _dense(OBS, 3, [0])}, "3 actuators"),
             # sizes that hung a replay (a probe of hostile inputs): refused before any simulation
             "an episode of 1e12 steps": ({**GOOD, "episode_steps": 10**12}, "must be at most 1,000,000"),
             "a 65-column body": ({**GOOD, "body": [[3] * 65]}, "bodies of up to 64x64")}


@pytest.mark.parametrize("case", CHAMPIONS)
def test_corrupt_champion(tmp_path, capsys, case):
    content, detail = CHAMPIONS[case]
    (tmp_path / "champion.json").write_text(content if isinstance(content, str) else json.dumps(content))
    in_process(capsys, "render", str(tmp_path), names=["champion.json", detail])
    assert not (tmp_path / "champion.gif").exists()


def test_champion_check_accepts_a_good_one(tmp_path):
    from evolve.records.champion import read_champion

    (tmp_path / "champion.json").write_text(json.dumps(GOOD))
    _, body, ctrl = read_champion(tmp_path)
    assert body.tolist() == BODY and ctrl.act(np.zeros(OBS)).shape == (3,)


def test_bad_body_files(tmp_path, capsys):
    files = {"a.json": ("{bad", "not valid JSON"), "b.json": ('{"foo": 1}', "'body' or 'matrix' key"),
             "c.npy": ("xx", "not a .npy file"),
             "ragged.json": ('{"body": [[3, 3], [3]]}', "not a list of equal-length rows"),
             "flat.json": ("[3, 3]", "not a list of equal-length rows"),
             "empty.json": ("[]", "not a list of equal-length rows")}
    for name, (text, detail) in files.items():
        (tmp_path / name).write_text(text)
        in_process(capsys, "render", "--task", "Walker-v0", "--body", str(tmp_path / name),
                   names=["bad body matrix", name, detail])
    in_process(capsys, "render", "--task", "Walker-v0", "--body", str(tmp_path / "none.npy"),
               names=["file not found", "none.npy"])


def test_plot_and_validate_on_folders_that_are_not_runs_or_references(tmp_path, capsys):
    in_process(capsys, "plot", str(tmp_path), names=[tmp_path, "no generations.csv"])
    run = tmp_path / "run"
    run.mkdir()
    (run / "generations.csv").write_text("generation,best\n0,1.0\n")
    (run / "config.yaml").write_text("task: [\n")
    in_process(capsys, "plot", str(run), names=[run / "config.yaml", "not valid YAML"])
    (run / "generations.csv").write_bytes(b"\xff\xfe,\n")
    in_process(capsys, "plot", str(run), names=[run / "generations.csv"])
    in_process(capsys, "validate", str(tmp_path / "missing"), names=["not a folder", "missing"])
    in_process(capsys, "validate", str(tmp_path), names=[tmp_path, "neither reference traces"])
    (tmp_path / "Walker-v0.npz").write_text("junk")
    in_process(capsys, "validate", str(tmp_path), names=["Walker-v0.npz", "not a .npz file"])
    (tmp_path / "index.json").write_text("{")
    in_process(capsys, "validate", str(tmp_path), names=["index.json", "not valid JSON"])


def test_validate_refuses_reference_files_that_are_not_the_ones_recorded(tmp_path, repo_root, capsys,
                                                                          monkeypatch):
    """index.json records each case's sha256, and the sets have a format version; `sgr validate`
    compared an edited case, a case swapped for another task's, an unknown format and a returns
    file renamed to another task as if they were evogym's. Each is one line, before any replay."""
    data = repo_root / "tests" / "data"
    traces = tmp_path / "traces"
    shutil.copytree(data / "traces", traces)
    index = json.loads((traces / "index.json").read_text())
    first = index["cases"][0]["file"]

    def write(i):
        (traces / "index.json").write_text(json.dumps(i))

    write({**index, "format_version": 7})
    in_process(capsys, "validate", str(traces),
               names=[traces / "index.json", "format_version 7; this sgr reads 1"])
    write(index)
    raw = bytearray((traces / first).read_bytes())
    raw[-30] ^= 1  # one bit of the recorded data (the zip's directory still reads)
    (traces / first).write_bytes(bytes(raw))
    in_process(capsys, "validate", str(traces), names=[traces / first, "sha256 is not the one"])
    shutil.copy(data / "traces" / first, traces / first)
    other = next(c for c in index["cases"] if c["task"] != index["cases"][0]["task"])
    swapped = {**other, "file": first, "sha256": index["cases"][0]["sha256"]}  # the file says its own task
    write({**index, "cases": [swapped, *index["cases"][1:]]})
    in_process(capsys, "validate", str(traces),
               names=[traces / first, f"holds task {index['cases'][0]['task']!r}"])
    write({**index, "cases": [{**index["cases"][0], "file": "../x.npz"}]})
    in_process(capsys, "validate", str(traces), names=["'../x.npz' is not a file of", traces])
    returns = tmp_path / "returns"
    returns.mkdir()
    shutil.copy(data / "returns" / "Walker-v0.npz", returns / "Climber-v2.npz")
    in_process(capsys, "validate", str(returns),
               names=[returns / "Climber-v2.npz", "holds task 'Walker-v0', its name says 'Climber-v2'"])
    (traces / "linked").mkdir()  # a set whose files are links (git-annex) is read through them
    (traces / "linked" / first).symlink_to(data / "traces" / first)
    (traces / "linked" / "index.json").write_text(json.dumps({**index, "cases": index["cases"][:1]}))
    assert main(["validate", str(traces / "linked")]) == 0
    capsys.readouterr()
    e32 = tmp_path / "evogym32"
    e32.mkdir()
    index32 = json.loads((data / "evogym32" / "index.json").read_text())
    (e32 / "index.json").write_text(json.dumps({**index32, "all_tasks": ["Walker-v0", "Climber-v2"]}))
    for f in (data / "evogym32").glob("*_Walker-v0*.npz"):
        shutil.copy(f, e32 / f.name)
    shutil.copy(data / "evogym32" / "returns_Walker-v0.npz", e32 / "returns_Climber-v2.npz")  # task 2's
    import parity.harness

    def no_replay(*args):
        raise AssertionError("a task was replayed before every file was checked")

    monkeypatch.setattr(parity.harness, "evogym32_returns", no_replay)
    in_process(capsys, "validate", str(e32), names=[e32 / "returns_Climber-v2.npz", "sha256 is not the one"])
    (e32 / "index.json").write_text(json.dumps({**index32, "tasks": []}))
    in_process(capsys, "validate", str(e32), names=[e32 / "index.json", "key 'tasks' must be a dict"])


def test_out_paths_that_cannot_be_written(tmp_path, repo_root, capsys):
    a_file = tmp_path / "a_file"
    a_file.write_text("")
    in_process(capsys, "demo", "--robots", "1", "--steps", "1", "--out", str(a_file), names=["--out", a_file])
    cfg = tiny_config(tmp_path, repo_root)
    in_process(capsys, "evolve", "--config", str(cfg), "--out", str(a_file / "run"),
               names=["--out", "is a file, not a folder"])
    in_process(capsys, "render", "--task", "Walker-v0", "--body", "333", "--out", str(tmp_path),
               names=["--out", "is a folder"])


@pytest.mark.parametrize("argv, detail", [
    (["evolve", "--workers", "0"], "argument --workers"),
    (["evolve", "--workers", "many"], "argument --workers"),
    (["evolve", "--generations", "0"], "argument --generations"),
    (["render", "--width", "0"], "argument --width"),
    (["bench", "--robots", "-1"], "argument --robots"),
    (["frobnicate"], "invalid choice"),
    # typos that ran for days or filled memory (a probe of bad inputs): the most is said
    (["demo", "--steps", "100000000000"], "argument --steps: must be at most 1,000,000"),
    (["bench", "--robots", "1000000001"], "argument --robots: must be at most 1,000,000"),
    (["demo", "--seed", "-1"], "argument --seed: must be an int >= 0"),
    (["render", "--width", "100000"], "argument --width: must be at most 4,096"),
    (["render", "--height", "5000"], "argument --height: must be at most 4,096"),
    (["render", "--steps", "1000001"], "argument --steps: must be at most 1,000,000"),
    (["report", ".", "--replays", "1000000000"], "argument --replays: must be at most 100,000"),
    (["render", ".", "--replay", "1000000000"], "argument --replay: must be at most 100,000"),
])
def test_argparse_errors(capsys, argv, detail):
    with pytest.raises(SystemExit) as exc:
        main(argv)
    err = capsys.readouterr().err
    assert exc.value.code == 2 and detail in err and "Traceback" not in err
    assert err.splitlines()[-1].startswith("sgr")


def test_ray_options_without_ray(tmp_path, repo_root, capsys, monkeypatch):
    import importlib.util

    find_spec = importlib.util.find_spec
    monkeypatch.setattr(importlib.util, "find_spec",
                        lambda name, *a: None if name == "ray" else find_spec(name, *a))
    sweep = tmp_path / "sweep.yaml"
    sweep.write_text("methods: [sgr]\ntasks: [Walker-v0]\nseeds: 1\n")
    line = in_process(capsys, "sweep", "--config", str(sweep), "--out", str(tmp_path / "sw"),
                      "--backend", "ray")
    assert line == 'sgr: error: --backend ray needs Ray: pip install "sgr[ray]"'
    assert not (tmp_path / "sw").exists()
    line = in_process(capsys, "evolve", "--config", str(tiny_config(tmp_path, repo_root)), "--workers", "ray",
                      "--out", str(tmp_path / "run"))
    assert line == 'sgr: error: workers: ray needs Ray: pip install "sgr[ray]"'
    assert not (tmp_path / "run").exists()
    in_process(capsys, "sweep", "--config", str(sweep), "--address", "auto",
               names=["--address", "--backend ray"])


# ---------------------------------------------------------------- messages a person can act on
def test_a_bad_override_names_the_sweep_file_and_the_key(tmp_path, capsys):
    """A sweep's override that the config refuses blames the sweep file (where it was written) and
    names the key; a packaged config file is not blamed for it."""
    sweep = tmp_path / "my-sweep.yaml"
    sweep.write_text(yaml.safe_dump({"methods": ["sgr"], "tasks": ["Walker-v0"], "seeds": 1,
                                     "overrides": {"generations": "many"}}))
    line = in_process(capsys, "sweep", "--config", str(sweep), "--out", str(tmp_path / "s"),
                      names=[sweep, "'overrides'", "'generations'"])
    assert line.startswith(f"sgr: error: {sweep}: ") and not (tmp_path / "s").exists()
    sweep.write_text(yaml.safe_dump({"methods": ["sgr"], "tasks": ["Walker-v0"], "seeds": 1,
                                     "overrides": {"sgr": {"pop_sise": 8}}}))
    line = in_process(capsys, "sweep", "--config", str(sweep), "--out", str(tmp_path / "s"),
                      names=[sweep, "'overrides'", "'pop_sise'"])
    assert line.startswith(f"sgr: error: {sweep}: ")


@pytest.mark.slow
@pytest.mark.subprocess
def test_a_closed_stdout_is_no_disk_error_and_the_run_goes_on(tmp_path, repo_root):
    """`sgr evolve ... | head -2`: once the reader is gone the run goes on without progress lines
    and finishes (exit 0), with no 'cannot write' or 'make room' and no traceback."""
    cfg = tiny_config(tmp_path, repo_root, generations=6, workers=1)
    env = {k: v for k, v in os.environ.items() if k not in ("SGR_ARCH", "SGR_THREADS")}
    proc = subprocess.Popen([sys.executable, "-m", "evolve.cli", "evolve", "--config", str(cfg),
                             "--out", "r"], cwd=tmp_path, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                            env=env)
    head = [proc.stdout.readline() for _ in range(3)]  # what `head -3` reads, then it exits
    proc.stdout.close()
    err = proc.stderr.read().decode()
    assert proc.wait(timeout=300) == 0, err
    assert head[0].startswith(b"backend: cpu (")  # the first line names the backend (issue 45)
    assert head[1].startswith(b"run directory: r") and head[2].startswith(b"gen    1/6")
    assert "make room" not in err and "cannot write" not in err and "Traceback" not in err, err
    assert "Exception ignored" not in err, err
    assert len((tmp_path / "r" / "generations.csv").read_text().splitlines()) == 7  # all 6 generations


def test_resume_of_a_missing_path_says_it_does_not_exist(tmp_path, capsys):
    line = in_process(capsys, "evolve", "--resume", str(tmp_path / "nowhere"), names=["nowhere"])
    assert line.endswith("does not exist")
    line = in_process(capsys, "sweep", "--resume", str(tmp_path / "nowhere"), names=["nowhere"])
    assert line.endswith("does not exist")
    line = in_process(capsys, "evolve", "--config", str(tmp_path / "nowhere.yaml"), names=["nowhere.yaml"])
    assert "does not exist" in line


def test_resume_of_a_sweep_folder_points_to_sgr_sweep_resume(tmp_path, capsys):
    sweep = tmp_path / "sweep"
    (sweep / "runs").mkdir(parents=True)
    (sweep / "sweep.yaml").write_text("methods: [sgr]\n")
    line = in_process(capsys, "evolve", "--resume", str(sweep), names=[f"sgr sweep --resume {sweep}"])
    assert "is a sweep directory" in line


@pytest.mark.parametrize("argv, names", [
    (["evolve", "--task", "Climbr-v2"], ["unknown task 'Climbr-v2'", "did you mean Climber-v2"]),
    (["evolve", "--task", "Climber-v2", "--method", "dirct"],
     ["unknown method 'dirct'", "did you mean direct"]),
    (["evolve", "--config", "sgr/Walkr-v0"], ["sgr/Walkr-v0", "did you mean sgr/Walker-v0"]),
])
def test_unknown_task_method_and_config_names_suggest_the_closest(capsys, argv, names):
    in_process(capsys, *argv, names=names)


def test_unknown_names_in_config_and_sweep_files_suggest_the_closest(tmp_path, repo_root, capsys):
    cfg = tiny_config(tmp_path, repo_root, task="Walkr-v0")
    in_process(capsys, "evolve", "--config", str(cfg), names=[cfg, "'task'", "did you mean Walker-v0"])
    cfg = tiny_config(tmp_path, repo_root, method="nestd")
    in_process(capsys, "evolve", "--config", str(cfg), names=[cfg, "'method'", "did you mean nested"])
    sweep = tmp_path / "s.yaml"
    sweep.write_text(yaml.safe_dump({"methods": ["sgr"], "tasks": ["Thrower-v9"], "seeds": 1}))
    in_process(capsys, "sweep", "--config", str(sweep), names=[sweep, "did you mean Thrower-v0"])


# ---------------------------------------------------------------- internal errors and --debug

def sgr_with(patch: str, *argv: str, cwd: Path) -> subprocess.CompletedProcess:
    """`sgr argv` in a fresh process after running `patch` (which plants a bug)."""
    code = f"import sys\n{patch}\nfrom evolve.cli import main\nsys.exit(main({list(argv)!r}))\n"
    env = {**os.environ, "PYTHONPATH": str(ROOT)}
    return subprocess.run([sys.executable, "-c", code], cwd=cwd, capture_output=True, text=True, env=env,
                          timeout=300)


BUG = ("import evolve.report.plots as plots\n"
       "def plot_run(*a, **k):\n"
       "    raise {exc}('a planted bug')\n"
       "plots.plot_run = plot_run")


@pytest.mark.slow
@pytest.mark.subprocess
def test_an_internal_error_inside_a_command_is_one_line_and_the_file_with_its_traceback(tmp_path):
    """An exception no check expected (a bug, or bad input that reached code unguarded: a KeyError
    of malformed data) is one line naming its type, exit 1; its traceback is in the named file."""
    r = sgr_with(BUG.format(exc="KeyError"), "plot", str(tmp_path), cwd=tmp_path)
    assert r.returncode == 1, r.stderr
    line, = r.stderr.splitlines()
    assert line.startswith("sgr: error: unexpected KeyError: 'a planted bug' (full traceback: "), line
    path = Path(line.split("(full traceback: ")[1].split(";")[0])
    kept = path.read_text()
    path.unlink()
    assert kept.startswith("Traceback (most recent call last)") and "in plot_run" in kept, kept


def test_a_file_that_cannot_be_written_or_a_too_deep_input_is_one_line(tmp_path, capsys, monkeypatch):
    """An OSError names the path and why (a rename's target, not its temporary file), a
    RecursionError (JSON nested 100,000 deep) says the input is nested too deeply: one line each,
    exit 2."""
    import evolve.report.plots as plots

    def plot_run(*a, **k):
        raise PermissionError(13, "Permission denied", str(tmp_path / ".tmp.x"), None,
                              str(tmp_path / "p.png"))

    monkeypatch.setattr(plots, "plot_run", plot_run)
    assert main(["plot", str(tmp_path)]) == 2
    line, = capsys.readouterr().err.splitlines()
    assert line.startswith(f"sgr: error: {tmp_path / 'p.png'}: Permission denied (full traceback: "), line
    Path(line.split("(full traceback: ")[1].removesuffix(")")).unlink()
    run = tmp_path / "run"
    run.mkdir()
    (run / "champion.json").write_text("[" * 100000 + "]" * 100000)
    assert main(["render", str(run), "--out", str(tmp_path / "x.gif")]) == 2
    line, = capsys.readouterr().err.splitlines()  # a champion.json too deep names the file
    assert line == f"sgr: error: {run / 'champion.json'}: not a champion's record (nested too deeply)", line
    (tmp_path / "deep.json").write_text("[" * 100000 + "]" * 100000)  # a file no check reads for depth
    assert main(["render", "--task", "Walker-v0", "--body", str(tmp_path / "deep.json")]) == 2
    line, = capsys.readouterr().err.splitlines()
    assert line.startswith("sgr: error: an input is nested too deeply to read ("), line
    Path(line.split("(full traceback: ")[1].removesuffix(")")).unlink()


def test_an_internal_value_error_gives_one_line_and_the_file_with_its_traceback(tmp_path, capsys,
                                                                               monkeypatch):
    import evolve.report.plots as plots

    def plot_run(*a, **k):
        raise ValueError("a planted bug")

    monkeypatch.setattr(plots, "plot_run", plot_run)
    assert main(["plot", str(tmp_path)]) == 2
    line, = capsys.readouterr().err.splitlines()
    assert line.startswith("sgr: error: a planted bug (full traceback: "), line
    path = Path(line.removeprefix("sgr: error: a planted bug (full traceback: ").removesuffix(")"))
    kept = path.read_text()
    path.unlink()
    assert kept.startswith("Traceback (most recent call last)") and "in plot_run" in kept, kept


def test_a_bad_config_is_one_line_without_a_traceback(tmp_path, capsys):
    bad = {"method": "sgr", "task": "Walker-v0", "pop_size": "many"}
    (tmp_path / "c.yaml").write_text(yaml.safe_dump(bad))
    assert main(["evolve", "--config", str(tmp_path / "c.yaml"), "--out", str(tmp_path / "r")]) == 2
    err = capsys.readouterr().err
    assert err.splitlines() == [f"sgr: error: {tmp_path / 'c.yaml'}: key 'pop_size' must be int, got 'many'"]


@pytest.mark.slow
@pytest.mark.subprocess
def test_debug_shows_the_traceback_of_bad_input_too(tmp_path):
    for argv in (("--debug", "evolve", "--config", "missing.yaml"), ("evolve", "--config", "missing.yaml",
                                                                      "--debug")):
        r = sgr_with("", *argv, cwd=tmp_path)
        assert r.returncode == 1, r.stderr
        assert "Traceback (most recent call last)" in r.stderr and "in find_config" in r.stderr, r.stderr
        assert r.stderr.rstrip().endswith("SgrError: config missing.yaml does not exist, nor is it the name "
                                          "of a packaged config (e.g. sgr/Climber-v2, quick, paper)")


@pytest.mark.slow
@pytest.mark.subprocess
def test_an_error_in_a_users_task_module_shows_the_users_code(tmp_path):
    (tmp_path / "my_tasks.py").write_text("x = 1\n\ndef broken():\n    return {}['missing key']\n\n"
                                          "broken()\n")
    (tmp_path / "c.yaml").write_text(yaml.safe_dump({"method": "sgr", "task": "Walker-v0",
                                                     "imports": ["my_tasks.py"]}))
    r = sgr_with("", "evolve", "--config", "c.yaml", "--out", "r", cwd=tmp_path)
    assert r.returncode == 1, r.stderr
    assert f'File "{tmp_path / "my_tasks.py"}", line 4, in broken' in r.stderr, r.stderr
    assert "return {}['missing key']" in r.stderr, r.stderr
    assert r.stderr.splitlines()[-1].endswith(f"task module {tmp_path / 'my_tasks.py'} raised KeyError: "
                                              "'missing key'; its traceback is above"), r.stderr


@pytest.mark.parametrize("extra, says", [
    ("body_distance_weight: .nan", "key 'body_distance_weight' must be a finite number, got nan"),
    ("max_weight: .inf", "key 'max_weight' must be a finite number, got inf"),
    ("max_weight: -1", "key 'max_weight' must be > 0, got -1.0"),
    ("weight_threshold: -0.5", "key 'weight_threshold' must be >= 0, got -0.5"),
    ("pop_size: 100000000000000000000", "key 'pop_size' must be at most 1,000,000"),
    ("episode_steps: 1000000000000", "key 'episode_steps' must be at most 1,000,000"),
    ("robust: {episodes: 1000000000}", "key 'robust.episodes' must be an int from 1 to 100,000"),
    ("final_selection: {confirm: 1000000000}",
     "key 'final_selection.confirm' must be an int from 0 to 100,000"),
    ("a: &x [1, 2]\nseed: *x", "not valid YAML: aliases (*name) are not read in sgr's files"),
])
def test_a_config_value_out_of_its_range_or_an_alias_is_one_line(tmp_path, capsys, extra, says):
    """Values found accepted by a probe of bad inputs (a NaN speciation weight, a negative weight
    bound, a population of 1e20 that filled memory) and YAML aliases (a 1.4 KB "billion laughs"
    config expanded into a 17 MB error line, or never finished) are refused in one line."""
    cfg = tmp_path / "c.yaml"
    cfg.write_text(f"method: sgr\ntask: Walker-v0\n{extra}\n")
    assert main(["evolve", "--config", str(cfg), "--out", str(tmp_path / "r")]) == 2
    line, = capsys.readouterr().err.splitlines()
    assert line.startswith(f"sgr: error: {cfg}: ") and says in line, line
    assert not (tmp_path / "r").exists()


def test_an_empty_task_name_is_refused_not_taken_as_none(tmp_path, capsys):
    assert main(["evolve", "--task", "", "--out", str(tmp_path / "r")]) == 2
    assert capsys.readouterr().err.splitlines() == ["sgr: error: --task needs a name, got an empty one"]
