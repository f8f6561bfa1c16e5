"""Runs with each new body decoder (`body_decoder`): the champion decoded at the run's own size is the
champion bit for bit and replays its fitness; it decodes at other sizes and the run continues at
another size (`start_from`) with the same decoder; a run killed with SIGKILL and resumed in a new
process is exactly the run it would have been."""

from __future__ import annotations

import json

import numpy as np
import pytest

from evolve.cli import main
from evolve.records.decode import write_decoded
from evolve.records.replay import load_champion, rescore_champion
from evolve.records.rundir import RunDir
from evolve.runs.checkpoint import load_checkpoint
from evolve.runs.experiment import Experiment
from tests.evolve.conftest import TINY
from tests.evolve.runs.test_resume import fitness_rows, genomes_and_species, kill_when, sgr, write_config
from tsim.body import is_connected
from tsim.errors import SgrError

pytestmark = pytest.mark.slow
DECODERS = ["cppn", "fourier", "growth"]


@pytest.fixture(scope="module", params=DECODERS)
def decoder_run(request, tmp_path_factory):
    """A finished tiny SGR run with the decoder (3 generations of 8, 20-step episodes)."""
    folder = tmp_path_factory.mktemp(request.param) / "run"
    cfg = {"method": "sgr", **TINY, "generations": 3, "body_decoder": request.param}
    with Experiment.from_config(cfg, folder, quiet=True) as exp:
        exp.run_all()
    return request.param, folder


def test_the_champion_decoded_at_its_runs_size_is_the_champion_bit_for_bit(decoder_run, tmp_path):
    name, run = decoder_run
    before = json.loads((run / "champion.json").read_text())
    assert before["controller"]["decoder"]["body_decoder"] == name  # recorded as its genome's decoding
    out = write_decoded(run, (5, 5), tmp_path / "same")
    after = json.loads((out / "champion.json").read_text())
    assert after["body"] == before["body"] and after["controller"] == before["controller"]
    assert after["fitness"] == before["fitness"]
    assert rescore_champion(out) == before["fitness"] == rescore_champion(run)
    assert np.array_equal(load_champion(run).body, np.asarray(before["body"]))


@pytest.mark.parametrize("shape", [(10, 10), (10, 5)])
def test_the_champion_decodes_at_other_sizes_to_a_valid_robot_or_says_why_not(decoder_run, tmp_path, shape):
    name, run = decoder_run
    try:
        out = write_decoded(run, shape, tmp_path / "big")
    except SgrError as exc:  # a genome may draw no valid robot at another size: one line says so
        assert "draws no valid robot" in str(exc) and "\n" not in str(exc)
        return
    champ = load_champion(out)
    body = np.asarray(champ.body)
    assert body.shape == shape and is_connected(body)
    assert json.loads((out / "champion.json").read_text())["controller"]["decoder"]["body_decoder"] == name
    assert rescore_champion(out) == champ.fitness


def test_a_run_continues_at_another_size_with_its_decoder(decoder_run, tmp_path):
    name, run = decoder_run
    out = tmp_path / "cont"
    assert main(["evolve", "--from", str(run), "--shape", "10x5", "--generations", "4", "--out", str(out),
                 "--quiet"]) == 0
    champ = json.loads((out / "champion.json").read_text())
    assert np.asarray(champ["body"]).shape == (10, 5)
    assert champ["controller"]["decoder"]["body_decoder"] == name
    assert rescore_champion(out) == champ["fitness"]


@pytest.mark.subprocess
@pytest.mark.parametrize("name", [n if n == "cppn" else pytest.param(n, marks=pytest.mark.long)
                                  for n in DECODERS])
def test_a_sigkilled_run_resumes_to_the_same_run(tmp_path, repo_root, name):
    cfg = write_config(tmp_path, repo_root, "sgr", generations=7, pop_size=12, body_decoder=name)
    crashed = RunDir(tmp_path / "crashed")
    proc = sgr("evolve", "--config", str(cfg), "--out", str(crashed.path), "--quiet")
    kill_when(proc, crashed, 5)  # during generation 6; the newest checkpoint is generation 3
    assert load_checkpoint(crashed)["generation"] == 3
    full = Experiment.create(str(cfg), str(tmp_path / "full"), {}, quiet=True)  # the reference
    full.run_all()
    full.close()
    resumed = sgr("evolve", "--resume", str(crashed.path), "--quiet")
    _, err = resumed.communicate(timeout=300)
    assert resumed.returncode == 0, err
    reference = RunDir(tmp_path / "full")
    assert len(crashed.rows()) == 7 and fitness_rows(crashed) == fitness_rows(reference)
    assert genomes_and_species(load_checkpoint(crashed)) == genomes_and_species(load_checkpoint(reference))
    assert crashed.champion() == reference.champion()
    assert json.loads((crashed.path / "champion.json").read_text())["controller"]["decoder"][
        "body_decoder"] == name


def test_a_continuation_may_switch_to_a_decoder_whose_cppn_has_as_many_outputs(decoder_run, tmp_path, capsys):
    """fourier and growth read one CPPN output, as the paper's substrate does: a run of one continues
    with another; cppn's genomes have 5 outputs: refused in one line naming both counts."""
    name, run = decoder_run
    other = "growth" if name == "fourier" else "fourier"
    out = tmp_path / "switched"
    code = main(["evolve", "--from", str(run), "--body-decoder", other, "--generations", "4", "--out",
                 str(out), "--quiet"])
    if name == "cppn":
        err = capsys.readouterr().err
        assert code == 2 and err.count("\n") == 1
        assert "evolved CPPNs with 5 outputs" in err and "this config's have 1" in err
        return
    assert code == 0
    champ = json.loads((out / "champion.json").read_text())
    assert champ["controller"]["decoder"]["body_decoder"] == other
    assert rescore_champion(out) == champ["fitness"]


@pytest.mark.parametrize("name, given", [("growth", {"steps": 2}),
                                         ("fourier", {"frequencies": 1, "hidden": 3})])
def test_a_run_with_a_decoders_own_settings_records_them_and_decodes_to_its_champion(tmp_path, name, given):
    """A decoder's non-default settings reach the champion file, and decoding its genome at the
    run's size with them (`sgr decode`'s path) gives the champion bit for bit: a path that dropped
    the settings would decode with the defaults."""
    folder = tmp_path / "run"
    cfg = {"method": "sgr", **TINY, "generations": 2, "body_decoder": name, "body_decoder_settings": given}
    with Experiment.from_config(cfg, folder, quiet=True) as exp:
        exp.run_all()
    before = json.loads((folder / "champion.json").read_text())
    decoder = before["controller"]["decoder"]
    assert decoder["body_decoder"] == name and decoder["body_decoder_settings"] == given
    after = json.loads((write_decoded(folder, (5, 5), tmp_path / "same") / "champion.json").read_text())
    assert after["body"] == before["body"] and after["controller"] == before["controller"]
    assert rescore_champion(folder) == before["fitness"]
