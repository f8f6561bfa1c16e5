"""A run of a task registered in a script travels with its script: task.json keeps the script's
file name (looked up in the run folder and beside it) and its sha256, so a copy of the run moved to
another folder, with the script copied beside it and the original gone, renders, reports and loads
(`load_champion`) with --trust-imports, or with --import FILE naming the copy. Without trust, or
with a changed script (one line appended, which would leave the attack's marker), it is refused in
one line, and nothing of the script runs."""

from __future__ import annotations

import shutil
from pathlib import Path

import gymnasium as gym
import pytest

from evolve.records.replay import load_champion
from evolve.runs.experiment import Experiment
from tasks.registry import import_tasks, trust_imports
from tasks.specs import TASKS, forget_worlds
from tests.evolve.attack import Attack
from tsim.errors import SgrError

pytestmark = [pytest.mark.slow]

NAME = "TravelLeft-v0"
SENDER: list[Path] = []  # the sender's script, renamed away (`made`)

# the script that registers the task; each time it runs it leaves a line in imported.log beside itself
SCRIPT = f'''
import pathlib

import numpy as np

import tasks
from tasks import TaskSpec
from tasks import observations as O
from tsim import world_from_matrix

ground = np.zeros((8, 30), dtype=int)
ground[-1, :] = 5


def leftward(before, after):
    return before.com[:, 0] - after.com[:, 0]


tasks.register(TaskSpec(name={NAME!r}, world=world_from_matrix(ground), origin=(20, 1), paper_steps=20,
                        evogym_steps=20, observation=(O.VCOM, O.POINTS), reward=leftward), replace=True)
with open(pathlib.Path(__file__).with_name("imported.log"), "a") as log:
    log.write("imported\\n")
'''


def forget_task() -> None:
    TASKS.pop(NAME, None)
    forget_worlds()
    gym.registry.pop(f"sgr/{NAME}", None)


@pytest.fixture(scope="module")
def made(tmp_path_factory) -> Path:
    """A finished one-generation run of the script's task, made where the script was (its
    task.json names that script); the script is then renamed away: its absolute path is gone."""
    home = tmp_path_factory.mktemp("sender")
    script = home / "left_task.py"
    script.write_text(SCRIPT)
    import_tasks(str(script))  # as `python left_task.py` would register it
    try:
        cfg = {"method": "sgr", "task": NAME, "generations": 1, "pop_size": 8, "workers": 1,
               "episode_steps": 20, "render_champion": False, "robust": None, "final_selection": None}
        with Experiment.from_config(cfg, home / "run", quiet=True) as exp:
            exp.run_all()
    finally:
        forget_task()
    script.rename(home / "left_task.py.moved")
    SENDER[:] = [home / "left_task.py.moved"]
    return home


@pytest.fixture
def received(made, tmp_path) -> Path:
    """The run copied to another folder, as a colleague receives it (the script not yet beside it)."""
    run = tmp_path / "inbox" / "run"
    shutil.copytree(made / "run", run)
    yield run
    forget_task()


def place_script(run: Path, where: str, extra: str = "") -> Path:
    """The sender's script copied to `where` ("beside": the run folder's parent, "inside": the run
    folder, "elsewhere": a folder of its own), with `extra` appended."""
    folder = {"beside": run.parent, "inside": run, "elsewhere": run.parent.parent / "mine"}[where]
    folder.mkdir(exist_ok=True)
    copy = folder / "left_task.py"
    copy.write_text(SENDER[0].read_text() + extra)
    return copy


def imported(run: Path) -> bool:
    """Whether a copy of the script ran (it logs beside itself)."""
    return any(p.name == "imported.log" for p in run.parents[1].rglob("imported.log"))


COMMANDS = {
    "render": lambda run, out: ["render", str(run), "--width", "32", "--height", "16", "--out", str(out)],
    "report": lambda run, out: ["report", str(run), "--replays", "1", "--no-gallery"],
}


@pytest.mark.parametrize("command", sorted(COMMANDS))
@pytest.mark.parametrize("how", ["trust, script beside", "trust, script inside", "--import FILE"])
def test_a_moved_run_with_its_script_renders_and_reports(received, tmp_path, capsys, command, how):
    """With --trust-imports and the script beside the run (or inside it), or --import naming a copy
    elsewhere: the command works, having imported that copy (its digest matches)."""
    where = {"trust, script beside": "beside", "trust, script inside": "inside", "--import FILE": "elsewhere"}
    copy = place_script(received, where[how])
    trust = ["--import", str(copy)] if how == "--import FILE" else ["--trust-imports"]
    attack = Attack(tmp_path)
    r = attack.main(*COMMANDS[command](received, tmp_path / "c.gif"), *trust, capsys=capsys, timeout=120)
    assert r.code == 0, r.err
    assert (copy.parent / "imported.log").is_file()
    if command == "render":
        assert (tmp_path / "c.gif").is_file()


def test_load_champion_of_a_moved_run_works_when_trusted_and_says_why_in_one_line_when_not(received):
    place_script(received, "beside")
    with pytest.raises(SgrError) as err:
        load_champion(received)
    line = str(err.value)
    assert "\n" not in line and "task.json" in line and "left_task.py" in line and "--trust-imports" in line
    assert not imported(received)
    trust_imports()
    try:
        champ = load_champion(received)
    finally:
        trust_imports(False)
    assert champ.task == NAME and champ.rollout() == champ.fitness
    assert imported(received)


def test_load_champion_of_a_moved_run_without_its_script_is_one_line_naming_what_to_do(received):
    trust_imports()
    try:
        with pytest.raises(SgrError) as err:
            load_champion(received)
    finally:
        trust_imports(False)
    line = str(err.value)
    assert "\n" not in line and "not there" in line and "--import" in line and "left_task.py" in line


REFUSED = {
    # case: (where the script lies, what is appended to it, the options, words the line says)
    "no trust": ("beside", "", [], ("which sgr does not run for reading a folder", "--trust-imports",
                                    "--import")),
    "no trust, script inside": ("inside", "", [], ("which sgr does not run", "--trust-imports")),
    "changed beside, trusted": ("beside", "MARK", ["--trust-imports"], ("has changed", "sha256")),
    "changed inside, trusted": ("inside", "MARK", ["--trust-imports"], ("has changed", "sha256")),
    "changed, named by --import": ("elsewhere", "MARK", ["--import"], ("--import", "not the script",
                                                                       "sha256")),
    "changed, --import and trust": ("elsewhere", "MARK", ["--import", "--trust-imports"],
                                    ("not the script",)),
    "gone, trusted": (None, "", ["--trust-imports"], ("not there", "--import FILE")),
    "--import of no file": (None, "", ["--import"], ("--import", "file not found")),
}


@pytest.mark.parametrize("command", ["render", "report"])
@pytest.mark.parametrize("case", sorted(REFUSED))
def test_a_moved_run_is_refused_in_one_line_without_trust_or_with_a_changed_script(received, tmp_path,
                                                                                   capsys, case, command):
    """Each refusal is one `sgr: error:` line naming task.json (or the --import file) and the
    problem; no copy of the script ran (its log and the attack's marker are absent), nothing
    outside the run changed and nothing in it was deleted."""
    where, extra, options, words = REFUSED[case]
    attack = Attack(tmp_path)
    if extra == "MARK":
        extra = "\n" + attack.code()
    copy = place_script(received, where, extra) if where else tmp_path / "mine" / "left_task.py"
    args = [a for o in options for a in ((o, str(copy)) if o == "--import" else (o,))]
    with attack.watching(received):
        r = attack.main(*COMMANDS[command](received, tmp_path / "c.gif"), *args, capsys=capsys, timeout=60)
    line = r.error_line()
    for w in words:
        assert w in line, line
    assert "task.json" in line or "file not found" in line, line
    assert not imported(received) and not attack.marker.exists()
    assert not (tmp_path / "c.gif").exists()
