"""The packaged configs (issue 45, item 3): a config of every method for every task, generated
from one template per method (tools/gen_configs.py) and equal to what the generator writes; and a
copied config whose relative files are not beside it takes sgr's packaged ones, saying so."""

import argparse
import importlib.util
import shutil
from pathlib import Path

import pytest

from evolve.cli.evolve_cmd import evolve_config
from evolve.runs.config import configs_dir, load_config
from tasks.specs import BUILTIN, TASKS

ROOT = Path(__file__).resolve().parents[3]
PAPER_TASKS = {"Walker-v0", "ObstacleTraverser-v1", "Climber-v2", "Thrower-v0"}  # the SGR paper's four


@pytest.fixture(scope="module")
def gen():
    spec = importlib.util.spec_from_file_location("gen_configs", ROOT / "tools" / "gen_configs.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def test_the_committed_configs_are_what_the_generator_writes(gen):
    """Edit the templates, not the files: a hand edit of a generated config fails here."""
    made = gen.generated()
    assert len(made) == 5 * len(BUILTIN) == 160  # sgr, direct, nested, map-elites, ga-ppo
    stale = [str(rel) for rel, text in made.items() if (ROOT / "configs" / rel).read_text() != text]
    assert not stale, f"run python tools/gen_configs.py: {stale}"


def test_a_method_of_sgrs_with_a_template_gets_its_configs_without_a_generator_edit(gen, monkeypatch):
    """The generator names no method: it writes one config per task for every method of sgr's
    whose class declares `packaged` (here a sixth, registered beside the five)."""
    from evolve import methods
    from evolve.methods.packaged import PackagedConfig

    class Sixth(methods.Problem):
        name = "sixth"
        packaged = PackagedConfig("# sixth on $task$about\nmethod: sixth\ntask: $task\n$episode\n",
                                  about=(" (a paper task)", ""))

    monkeypatch.setitem(methods.METHODS, "sixth", Sixth)
    monkeypatch.setattr(gen, "BUILTIN_METHODS", methods.BUILTIN | {"sixth"})
    made = gen.generated()
    assert len(made) == 6 * len(BUILTIN)
    assert made[Path("sixth/Walker-v0.yaml")] == "# sixth on Walker-v0 (a paper task)\nmethod: sixth\n" \
        "task: Walker-v0\nepisode_steps: 500                # evogym's max_episode_steps for Walker-v0\n"


def test_the_generators_check_finds_a_hand_edited_config(gen, tmp_path, capsys):
    out = tmp_path / "configs"
    assert gen.main(["--out", str(out)]) == 0  # writes all 160
    assert gen.main(["--check", "--out", str(out)]) == 0
    edited = out / "direct" / "Jumper-v0.yaml"
    edited.write_text(edited.read_text().replace("pop_size: 128", "pop_size: 64"))
    capsys.readouterr()
    assert gen.main(["--check", "--out", str(out)]) == 1
    assert "direct/Jumper-v0.yaml" in capsys.readouterr().err


@pytest.mark.parametrize("method", ["sgr", "direct", "nested"])
def test_every_task_has_a_config_of_every_method(method):
    """`sgr evolve --task T --method M` finds a packaged config for each of the 32 tasks, and it
    loads and validates, with the paper's episode length on the paper's tasks and evogym's on the
    others (cheap: the config is checked, nothing evolves)."""
    for task in sorted(BUILTIN):
        path = evolve_config(argparse.Namespace(config=None, task=task, method=method))
        assert path == configs_dir() / method / f"{task}.yaml"
        cfg = load_config(path)
        assert (cfg.method, cfg.task, cfg.generations, cfg.robot_shape) == (method, task, 250, (5, 5))
        spec = TASKS[task]
        assert cfg.episode_steps == (spec.paper_steps if task in PAPER_TASKS else spec.evogym_steps), task
        assert cfg.robust is not None and (cfg.final_selection is not None) == (method != "nested"), task
        assert cfg.pop_size == (12 if method == "nested" else 128)


def test_every_task_has_a_ga_ppo_config_with_evogyms_ga_and_ppo_arguments():
    """configs/ga-ppo/<task>.yaml: evogym's episode length on every task (its GA trains on its
    envs), evogym's PPO arguments (examples/ppo/args.py) and GA mutation rate, honest evaluation."""
    pytest.importorskip("torch", reason="method ga-ppo needs torch: pip install 'sgr[rl]'")
    from evolve.rollout.ppo import PpoSettings

    for task in sorted(BUILTIN):
        path = evolve_config(argparse.Namespace(config=None, task=task, method="ga-ppo"))
        cfg = load_config(path)
        assert (cfg.method, cfg.task, cfg.episode_steps) == ("ga-ppo", task, TASKS[task].evogym_steps)
        assert PpoSettings.from_config(dict(cfg.ppo)) == PpoSettings() and cfg.ga["mutation_rate"] == 0.1
        assert cfg.robust is not None and cfg.final_selection is not None


def test_a_copied_config_takes_the_packaged_neat_files_saying_so(tmp_path, capsys):
    copy = tmp_path / "mine.yaml"
    shutil.copy(configs_dir() / "nested" / "Jumper-v0.yaml", copy)  # ../neat/nested-*.ini: not here
    cfg = load_config(copy)
    err = capsys.readouterr().err.splitlines()
    assert cfg.neat_config == str((configs_dir() / "neat" / "nested-body.ini").resolve())
    assert cfg.controller_neat_config == str((configs_dir() / "neat" / "nested-controller.ini").resolve())
    assert len(err) == 2 and all("mine.yaml" in line and "packaged" in line for line in err)
    assert "neat_config ../neat/nested-body.ini" in err[0]
    assert "controller_neat_config ../neat/nested-controller.ini" in err[1]


def test_a_file_beside_the_config_wins_over_the_packaged_one(tmp_path, capsys):
    (tmp_path / "neat").mkdir()
    (tmp_path / "cfg").mkdir()
    ini = tmp_path / "neat" / "sgr.ini"
    ini.write_text((configs_dir() / "neat" / "sgr.ini").read_text())
    shutil.copy(configs_dir() / "sgr" / "Jumper-v0.yaml", tmp_path / "cfg" / "c.yaml")
    assert load_config(tmp_path / "cfg" / "c.yaml").neat_config == str(ini.resolve())
    assert capsys.readouterr().err == ""


def test_a_relative_file_found_nowhere_is_still_one_error(tmp_path):
    (tmp_path / "c.yaml").write_text("method: sgr\ntask: Walker-v0\nneat_config: mine.ini\n")
    with pytest.raises(ValueError, match=r"key 'neat_config': file not found: .*mine\.ini"):
        load_config(tmp_path / "c.yaml")
