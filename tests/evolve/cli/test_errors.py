"""What the `sgr` command shows when something fails: bad input (SgrError) is one line and exit 2;
an internal error keeps its traceback (any other exception: the traceback itself; a ValueError
that is not an SgrError: one line plus the file holding its traceback); `--debug` shows every
traceback; an error in a user's task module shows the user's own code."""

import os
import subprocess
import sys
from pathlib import Path

import yaml

from evolve.cli import main

ROOT = Path(__file__).resolve().parents[3]


def sgr_with(patch: str, *argv: str, cwd: Path) -> subprocess.CompletedProcess:
    """`sgr argv` in a fresh process after running `patch` (which plants a bug)."""
    code = f"import sys\n{patch}\nfrom evolve.cli import main\nsys.exit(main({list(argv)!r}))\n"
    env = {**os.environ, "PYTHONPATH": str(ROOT)}
    return subprocess.run([sys.executable, "-c", code], cwd=cwd, capture_output=True, text=True, env=env,
                          timeout=300)


BUG = ("import evolve.runs.plots as plots\n"
       "def plot_run(*a, **k):\n"
       "    raise {exc}('a planted bug')\n"
       "plots.plot_run = plot_run")


def test_an_internal_error_inside_a_command_shows_its_traceback(tmp_path):
    r = sgr_with(BUG.format(exc="KeyError"), "plot", str(tmp_path), cwd=tmp_path)
    assert r.returncode == 1, r.stderr
    assert "Traceback (most recent call last)" in r.stderr, r.stderr
    assert "in plot_run" in r.stderr and "KeyError: 'a planted bug'" in r.stderr, r.stderr


def test_an_internal_value_error_gives_one_line_and_the_file_with_its_traceback(tmp_path, capsys,
                                                                               monkeypatch):
    import evolve.runs.plots as plots

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


def test_debug_shows_the_traceback_of_bad_input_too(tmp_path):
    for argv in (("--debug", "evolve", "--config", "missing.yaml"), ("evolve", "--config", "missing.yaml",
                                                                      "--debug")):
        r = sgr_with("", *argv, cwd=tmp_path)
        assert r.returncode == 1, r.stderr
        assert "Traceback (most recent call last)" in r.stderr and "in find_config" in r.stderr, r.stderr
        assert r.stderr.rstrip().endswith("SgrError: config missing.yaml does not exist, nor is it the name "
                                          "of a packaged config (e.g. sgr/Climber-v2, quick, paper)")


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
