"""Adding a method is one new file and one registration (docs/EVOLVE.md "Adding a method"): the
recipe's module and config, copied from the page as they are, make a run that `sgr evolve` starts,
`sgr report` reports and `sgr evolve --resume` extends, and whose champion reads back; the folder's
code is imported only when trusted."""

from __future__ import annotations

import json
import re

import pytest

from evolve.cli import main
from evolve.methods import BUILTIN, METHODS, Problem, register
from tsim.errors import SgrError


def recipe(repo_root) -> tuple[str, str]:
    """The page's gain.py and gain.yaml, as written there."""
    page = (repo_root / "docs" / "EVOLVE.md").read_text()
    section = page.split("## Adding a method\n", 1)[1].split("\n## ", 1)[0]
    blocks = re.findall(r"```(python|yaml)\n(.*?)```", section, re.S)
    module = next(b for kind, b in blocks if kind == "python" and b.startswith("# gain.py"))
    config = next(b for kind, b in blocks if kind == "yaml" and b.startswith("# gain.yaml"))
    return module, config


@pytest.fixture
def gain_files(tmp_path, repo_root, monkeypatch):
    module, config = recipe(repo_root)
    (tmp_path / "gain.py").write_text(module)
    (tmp_path / "gain.yaml").write_text(config)
    yield tmp_path
    METHODS.pop("gain", None)  # (the registry is this process's: leave it as it was)
    from evolve.methods import formats

    formats.READERS.pop("gain-controller-1", None)


def test_the_recipe_runs_reports_and_resumes(gain_files, capsys):
    """`sgr evolve --config gain.yaml` (the config's imports: register the method), then `sgr report
    RUN --trust-imports` and `sgr evolve --resume RUN --generations 5 --trust-imports`; the champion
    file holds the method's tagged controller and replays to its recorded fitness."""
    from evolve.records.replay import load_champion, rescore_champion

    run = gain_files / "run"
    assert main(["evolve", "--config", str(gain_files / "gain.yaml"), "--out", str(run), "--quiet"]) == 0
    champ = json.loads((run / "champion.json").read_text())
    assert champ["method"] == "gain" and champ["controller"]["format"] == "gain-controller-1"
    assert rescore_champion(run) == champ["fitness"]
    assert load_champion(run).controller.gain == champ["controller"]["gain"]
    assert main(["report", str(run), "--replays", "2", "--trust-imports"]) == 0
    assert "| gain" in (run / "report.md").read_text()
    assert main(["evolve", "--resume", str(run), "--generations", "5", "--quiet", "--trust-imports"]) == 0
    assert len((run / "generations.csv").read_text().splitlines()) == 1 + 5


def test_a_folder_naming_a_method_s_module_is_not_run_untrusted(gain_files, capsys):
    """A run of a method of the user's, read back in a process that does not know the method: its
    module is named by the folder, so without --trust-imports the command is one line saying so."""
    run = gain_files / "run"
    assert main(["evolve", "--config", str(gain_files / "gain.yaml"), "--out", str(run), "--quiet"]) == 0
    METHODS.pop("gain")  # a fresh process: the method is not registered
    capsys.readouterr()
    assert main(["evolve", "--resume", str(run), "--generations", "4", "--quiet"]) == 2
    err = capsys.readouterr().err
    assert len(err.strip().splitlines()) == 1 and "names code to import" in err and "gain.py" in err


def test_register_refuses_what_is_not_a_method_and_sgr_s_own_names():
    class Sgr(Problem):
        name = "sgr"

    with pytest.raises(SgrError, match="one of sgr's own methods"):
        register(Sgr)
    with pytest.raises(SgrError, match="a Problem subclass with a name"):
        register(dict)
    assert "sgr" in BUILTIN and METHODS["sgr"] is not Sgr


def test_sgr_evolve_method_task_import_runs_the_method_s_defaults(gain_files, capsys, monkeypatch, tmp_path):
    """`sgr evolve --method gain --task Walker-v0 --import gain.py`: the module named on the command
    line registers the method, its `default_config` is the run's, and config.yaml names the module in
    its imports: (what a resume imports, when trusted); the defaults' temporary file is removed."""
    import tempfile

    import yaml

    temp = tmp_path / "temp"
    temp.mkdir()
    monkeypatch.setattr(tempfile, "tempdir", str(temp))
    run = gain_files / "cli"
    assert main(["evolve", "--method", "gain", "--task", "Walker-v0", "--import", str(gain_files / "gain.py"),
                 "--out", str(run), "--quiet"]) == 0
    raw = yaml.safe_load((run / "config.yaml").read_text())
    assert raw["method"] == "gain" and raw["generations"] == 3 and raw["pop_size"] == 8
    assert raw["imports"] == [str((gain_files / "gain.py").resolve())]
    assert list(temp.iterdir()) == []  # (the defaults were written there, then removed)
    METHODS.pop("gain")
    capsys.readouterr()
    assert main(["evolve", "--method", "gain", "--task", "Walker-v0", "--out", str(gain_files / "x")]) == 2
    assert "--import FILE" in capsys.readouterr().err
