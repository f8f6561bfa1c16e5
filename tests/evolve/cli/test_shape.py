"""`sgr evolve --shape RxC`: the packaged <task>-RxC config when one ships, else the task's config
at that size; bad text, and a body the task's world cannot hold, are one line each."""

import argparse

import pytest

from evolve.cli import main
from evolve.cli.common import parse_shape
from evolve.cli.evolve_cmd import evolve_config
from evolve.runs.config import configs_dir, load_config
from tsim.errors import SgrError


def _args(**kw) -> argparse.Namespace:
    return argparse.Namespace(**{"config": None, "task": None, "method": None, **kw})


@pytest.mark.parametrize("method", ["sgr", "direct"])
@pytest.mark.parametrize("task", ["Walker-v0", "ObstacleTraverser-v1"])
def test_the_shipped_10x10_config_is_picked_and_holds_a_10x10_body(method, task):
    path = evolve_config(_args(task=task, method=method), (10, 10))
    assert path == configs_dir() / method / f"{task}-10x10.yaml"
    cfg, base = load_config(path), load_config(configs_dir() / method / f"{task}.yaml")
    assert cfg.robot_shape == (10, 10) and base.robot_shape == (5, 5)
    # a copy of the 5x5 config but for its size
    assert {k: v for k, v in cfg.to_yaml().items() if k != "robot_shape"} == \
        {k: v for k, v in base.to_yaml().items() if k != "robot_shape"}


def test_without_a_shipped_size_the_tasks_config_is_used_at_that_size():
    assert evolve_config(_args(task="Jumper-v0"), (10, 10)) == configs_dir() / "sgr" / "Jumper-v0.yaml"
    cfg = load_config(configs_dir() / "sgr" / "Jumper-v0.yaml", {"robot_shape": [10, 10]})
    assert cfg.robot_shape == (10, 10)


@pytest.mark.parametrize("text", ["10by10", "10x", "0x5", "-3x4", "10x10x2", ""])
def test_bad_shape_text_is_one_line(text, tmp_path, capsys, monkeypatch):
    monkeypatch.chdir(tmp_path)
    with pytest.raises(SgrError):
        parse_shape(text)
    assert main(["evolve", "--task", "Walker-v0", f"--shape={text}", "--out", str(tmp_path / "r")]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "--shape" in err and "RxC" in err, err
    assert not (tmp_path / "r").exists()


def test_shape_text_reads_rows_then_columns():
    assert parse_shape("10x10") == (10, 10) and parse_shape("3X7") == (3, 7)


def test_a_body_too_big_for_the_world_is_one_line_naming_the_key(tmp_path, capsys, monkeypatch):
    monkeypatch.chdir(tmp_path)
    assert main(["evolve", "--task", "Thrower-v0", "--shape", "10x10", "--out", str(tmp_path / "r")]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "key 'robot_shape' [10, 10]" in err and "[6, 6]" in err, err
    assert not (tmp_path / "r").exists()


def test_a_10x10_run_starts_from_any_folder(tmp_path, monkeypatch):
    """`sgr evolve --task Walker-v0 --shape 10x10` from a folder that is not the checkout takes the
    packaged Walker-v0-10x10 config. The configs are a copy whose 10x10 file is the shipped one
    with short episodes and a small final selection (the shipped 500-step episodes and 5 x 65
    selection episodes at 10x10 took ~30 s of the suite to test the same lookup)."""
    import json
    import shutil

    import yaml

    import evolve.runs.config as run_config

    configs = tmp_path / "configs"
    shutil.copytree(configs_dir(), configs)
    cfg_file = configs / "sgr" / "Walker-v0-10x10.yaml"
    raw = yaml.safe_load(cfg_file.read_text())
    assert raw["robot_shape"] == [10, 10] and raw["final_selection"]  # the shipped file, as shipped
    raw.update(episode_steps=40, final_selection={**raw["final_selection"], "candidates": 2,
                                                  "episodes": 2, "confirm": 2})
    cfg_file.write_text(yaml.safe_dump(raw))
    monkeypatch.setattr(run_config, "configs_dir", lambda: configs)  # the CLI imports it when called
    monkeypatch.chdir(tmp_path)
    out = tmp_path / "r"
    assert main(["evolve", "--task", "Walker-v0", "--shape", "10x10", "--generations", "1", "--pop", "4",
                 "--workers", "1", "--quiet", "--out", str(out)]) == 0
    run_raw = yaml.safe_load((out / "config.yaml").read_text())
    assert run_raw["robot_shape"] == [10, 10] and run_raw["episode_steps"] == 40  # that file's
    body = json.loads((out / "champion.json").read_text())["body"]
    assert len(body) == 10 and all(len(row) == 10 for row in body)
