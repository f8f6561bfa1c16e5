"""The run-config object: frozen and typed, checked and parsed once (a run never parses `robust`
again), the `workers` rule written once, the run folder recording arch and precision, and every
existing run folder (docs' sweeps, tests' data) read back."""

import dataclasses
from collections.abc import Mapping
from pathlib import Path

import pytest
import yaml

from evolve.cli import main
from evolve.config import RunConfig
from evolve.records.rundir import RunDir
from evolve.rollout.pool import RolloutPool
from evolve.rollout.robust import Robust
from evolve.runs.config import config_from_dict, load_config
from evolve.runs.experiment import Experiment

ROOT = Path(__file__).resolve().parents[3]


def tiny(repo_root, **changes) -> dict:
    return {"method": "sgr", "task": "Walker-v0", "generations": 2, "pop_size": 6, "episode_steps": 5,
            "render_champion": False, "workers": 1, "neat_config": str(repo_root / "configs/neat/sgr.ini"),
            "robust": None, "final_selection": None, **changes}


def test_a_config_is_frozen_typed_read_by_attribute_and_writes_its_yaml(repo_root):
    cfg = config_from_dict(tiny(repo_root, robust={"episodes": 2}, episode_steps=None))
    with pytest.raises(dataclasses.FrozenInstanceError):
        cfg.generations = 3
    assert isinstance(cfg.robust, Robust) and cfg.robust.episodes == 2
    yaml_values = cfg.to_yaml()
    assert cfg.robot_shape == (5, 5) and yaml_values["robot_shape"] == [5, 5]
    assert cfg.episode_steps == 500 == yaml_values["episode_steps"]  # Walker-v0's, resolved once
    assert yaml_values["robust"] == Robust(episodes=2).to_json() and cfg.cppn_outputs == 1  # a method's key
    assert yaml_values["arch"] == "cpu" and list(yaml_values)[:2] == ["method", "task"]
    assert not isinstance(cfg, Mapping) and not hasattr(cfg, "__getitem__")  # one way to read it
    with pytest.raises(AttributeError, match="no key 'not_a_key'"):
        _ = cfg.not_a_key


def test_robust_is_parsed_once_not_at_every_evaluation(tmp_path, repo_root, monkeypatch):
    calls = []
    parse = Robust.from_config.__func__
    monkeypatch.setattr(Robust, "from_config", classmethod(lambda cls, *a, **k: calls.append(a) or
                                                           parse(cls, *a, **k)))
    cfg = config_from_dict(tiny(repo_root, robust={"episodes": 2}))
    assert len(calls) == 1
    counts = []
    for generations in (2, 4):  # the run's end reads its records back (the headline): a fixed count
        calls.clear()
        raw = {**cfg.to_yaml(), "generations": generations}
        with Experiment.from_config(raw, tmp_path / f"r{generations}", quiet=True) as exp:
            exp.run_all()
        assert len(RunDir(tmp_path / f"r{generations}").rows()) == generations
        counts.append(len(calls))
    assert counts[0] == counts[1]  # the generations themselves: never


@pytest.mark.parametrize("value", [0, -1, "many"])
def test_the_workers_rule_is_the_same_in_the_config_the_flag_and_the_pool(tmp_path, repo_root, value, capsys):
    with pytest.raises(ValueError, match="key 'workers' must be a positive int, 'auto' or 'ray'"):
        config_from_dict(tiny(repo_root, workers=value))
    with pytest.raises(ValueError, match="workers must be a positive int"):
        RolloutPool(value)
    with pytest.raises(SystemExit):
        main(["evolve", "--workers", str(value)])
    assert "argument --workers: must be a positive int, 'auto' or 'ray'" in capsys.readouterr().err


def test_the_run_folder_records_arch_and_precision(tmp_path, repo_root, monkeypatch):
    monkeypatch.delenv("SGR_ARCH", raising=False)
    monkeypatch.setenv("SGR_PRECISION", "f32")
    (tmp_path / "c.yaml").write_text(yaml.safe_dump(tiny(repo_root, arch="cuda")))
    cfg = load_config(tmp_path / "c.yaml")  # a run's config.yaml used as a config: its arch replaced
    assert (cfg.arch, cfg.precision) == ("cpu", "f32")  # precision left out: $SGR_PRECISION's
    (tmp_path / "d.yaml").write_text(yaml.safe_dump(tiny(repo_root, arch="cuda", precision="f64")))
    assert load_config(tmp_path / "d.yaml").precision == "f64"  # a config's own precision is chosen
    monkeypatch.setenv("SGR_PRECISION", "f16")
    with pytest.raises(ValueError, match="SGR_PRECISION=f16: unknown precision; use one of f64, f32"):
        load_config(tmp_path / "c.yaml")


def stored_configs() -> list[Path]:
    found = sorted(p for d in ("results/paper/runs", "results/robust/runs", "tests/data")
                   for p in (ROOT / d).rglob("config.yaml"))
    assert len(found) > 50
    return found


def test_every_existing_run_folder_reads_back(repo_root):
    for path in stored_configs():
        raw = yaml.safe_load(path.read_text())
        cfg = RunConfig.of(raw)
        assert isinstance(cfg.episode_steps, int) and cfg.episode_steps > 0, path
        assert cfg.arch == raw.get("arch") and cfg.precision == raw.get("precision", "f64"), path
        assert cfg.robust == Robust.from_config(raw.get("robust")), path
        yaml_values = cfg.to_yaml()
        for key, value in raw.items():  # every key as written (episode_steps: resolved)
            assert yaml_values[key] == value or key == "episode_steps" and value in (None, "evogym"), \
                (path, key)


@pytest.mark.parametrize("method", ["sgr", "direct", "nested"])
def test_a_config_without_robust_keys_evaluates_as_the_cli_default_run_does(tmp_path, method):
    """One default: a config (a dict for `Experiment.from_config`, or a YAML file) that leaves out
    `robust` and `final_selection` gets the honest evaluation of `sgr evolve`'s default run
    (configs/sgr/quick.yaml; nested: its packaged config's, which has no final selection); null
    keeps the paper's nominal evaluation."""
    from evolve.runs.config import configs_dir

    cli = load_config(configs_dir() / "sgr" / "quick.yaml")
    assert cli.robust is not None and cli.final_selection is not None  # the control: honest
    packaged = load_config(configs_dir() / method / "Walker-v0.yaml") if method == "nested" else cli
    cfg = config_from_dict({"method": method, "task": "Walker-v0"})
    assert (cfg.robust, cfg.final_selection) == (packaged.robust, packaged.final_selection)
    (tmp_path / "c.yaml").write_text(yaml.safe_dump({"method": method, "task": "Walker-v0"}))
    assert (load_config(tmp_path / "c.yaml").robust, load_config(tmp_path / "c.yaml").final_selection) \
        == (packaged.robust, packaged.final_selection)
    nominal = config_from_dict({"method": method, "task": "Walker-v0", "robust": None,
                                "final_selection": None})
    assert (nominal.robust, nominal.final_selection) == (None, None)


def test_from_config_without_robust_keys_writes_the_honest_evaluation_in_full(tmp_path, repo_root):
    """The run folder records what the run did: a run started without the keys keeps them in
    config.yaml, so it reads back (and resumes) as the honest run it was, not as an older folder
    whose missing keys meant nominal."""
    cfg = {k: v for k, v in tiny(repo_root).items() if k not in ("robust", "final_selection")}
    Experiment.from_config(cfg, tmp_path / "r", quiet=True).close()
    written = RunDir(tmp_path / "r").config()
    quick = yaml.safe_load((ROOT / "configs/sgr/quick.yaml").read_text())
    assert (written["robust"], written["final_selection"]) == (quick["robust"], quick["final_selection"])
    back = RunConfig.of(written)
    assert back.robust == Robust.from_config(quick["robust"]) and back.final_selection is not None
    older = {k: v for k, v in written.items() if k not in ("robust", "final_selection")}
    assert (RunConfig.of(older).robust, RunConfig.of(older).final_selection) == (None, None)


@pytest.mark.parametrize("changes, words", [
    ({"method": ["sgr"]}, "key 'method' must be one of"),         # unhashable type: 'list'
    ({"method": {"sgr": 1}}, "key 'method' must be one of"),
    ({"robot_shape": [True, 5]}, "key 'robot_shape' must be [rows, cols] of positive ints"),  # crashed later
])
def test_a_config_value_of_the_wrong_kind_is_one_line_naming_its_key(changes, words):
    with pytest.raises(ValueError) as err:
        config_from_dict({"method": "sgr", "task": "Walker-v0", **changes}, "c.yaml")
    assert words in str(err.value) and "\n" not in str(err.value)


@pytest.mark.parametrize("statistic", ["q²", "q٣", "q101", "q-5"])
def test_a_quantile_statistic_is_q_and_ascii_digits_up_to_100(statistic):
    """'²' passed str.isdigit() and failed int() with a line naming no key; '٣' was taken."""
    def config(s: str):
        return config_from_dict({"method": "sgr", "task": "Walker-v0",
                                 "robust": {"episodes": 4, "statistic": s}}, "c.yaml")
    with pytest.raises(ValueError, match="statistic' must be one of"):
        config(statistic)
    assert config("q25").robust.statistic == "q25"


@pytest.mark.parametrize("out", ["afile", "afile/sub"])
def test_a_run_folder_that_is_a_file_is_one_line(tmp_path, repo_root, out):
    """Was a raw FileExistsError / NotADirectoryError."""
    from tsim.errors import SgrError

    (tmp_path / "afile").write_text("x")
    with pytest.raises(SgrError, match="is not a folder"):
        Experiment.from_config(tiny(repo_root), tmp_path / out, quiet=True)
