"""`sgr decode`: an SGR champion genome decoded at its run's own size is the run's champion bit for
bit (body, controller, and its fitness when replayed); at other sizes it draws valid robots
(connected, with an actuator) that load and replay like any champion; direct NEAT decodes at its
own size only, nested not at all, each refusal one line."""

import json

import numpy as np
import pytest

from evolve.cli import main
from evolve.records.decode import write_decoded
from evolve.records.replay import load_champion, rescore_champion
from evolve.runs.experiment import Experiment
from tests.evolve.conftest import TINY, tiny_run
from tsim.body import check_robot, has_actuator, is_connected


def test_decoding_at_the_runs_own_size_gives_its_champion_bit_for_bit(sgr_run, tmp_path):
    before = json.loads((sgr_run / "champion.json").read_text())
    out = write_decoded(sgr_run, (5, 5), tmp_path / "same")
    after = json.loads((out / "champion.json").read_text())
    assert after["body"] == before["body"]
    assert after["controller"] == before["controller"]  # every weight, as JSON floats: bit for bit
    assert after["fitness"] == before["fitness"] and after["decoded"]["shape"] == [5, 5]
    assert rescore_champion(out) == before["fitness"]  # replayed from the decoded file alone
    champ = load_champion(out)
    assert champ.rollout() == before["fitness"]  # and in gymnasium


@pytest.mark.parametrize("shape", [(10, 10), (8, 8), (7, 12)])
def test_other_sizes_give_valid_connected_bodies_with_actuators_that_replay(sgr_run, tmp_path, shape):
    out = write_decoded(sgr_run, shape, tmp_path / "big")
    champ = load_champion(out)
    body = np.asarray(champ.body)
    assert body.shape == shape
    check_robot(body)
    assert is_connected(body) and has_actuator(body)
    assert rescore_champion(out) == champ.fitness  # scored as the run scored its champion


def test_sgr_decode_command_writes_a_champion_folder_beside_the_run(sgr_run, capsys):
    assert main(["decode", str(sgr_run), "--shape", "10x10"]) == 0
    out = sgr_run.parent / "sgr-10x10"
    assert load_champion(out).body.shape == (10, 10)
    assert str(out) in capsys.readouterr().out


@pytest.mark.parametrize("argv, message", [
    (["--shape", "ten"], "--shape 'ten'"),
    (["--shape", "10x10", "--out", "{run}"], "a run folder"),
    (["--shape", "10x10", "--out", "{run}.json"], "ending in champion.json"),
])
def test_decode_bad_input_is_one_line(sgr_run, capsys, argv, message):
    argv = [a.format(run=sgr_run) for a in argv]
    assert main(["decode", str(sgr_run), *argv]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and message in err, err


def test_a_body_too_big_for_the_world_is_one_line(sgr_run, tmp_path, capsys):
    assert main(["decode", str(sgr_run), "--shape", "70x3", "--out", str(tmp_path / "o")]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "64x64" in err, err


def test_direct_decodes_at_its_own_size_only(tmp_path, capsys):
    d = tiny_run("direct", tmp_path / "direct")
    before = json.loads((d / "champion.json").read_text())
    out = write_decoded(d, (5, 5), tmp_path / "same")
    after = json.loads((out / "champion.json").read_text())
    assert (after["body"], after["controller"]) == (before["body"], before["controller"])
    assert rescore_champion(out) == before["fitness"]
    assert main(["decode", str(d), "--shape", "10x10", "--out", str(tmp_path / "o")]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "decodes at that size only" in err, err


def test_nested_is_refused_in_one_line(tmp_path, capsys):
    d = tmp_path / "nested"
    with Experiment.from_config({"method": "nested", **TINY}, d, quiet=True):
        pass
    assert main(["decode", str(d), "--shape", "5x5", "--out", str(tmp_path / "o")]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "nested" in err, err


@pytest.mark.parametrize("shape", [(2.7, 5), (True, 5), "55", (5,), (5, 5, 5), None, (0, 5), (-5, 5)])
def test_a_shape_that_is_not_two_positive_integers_is_refused_before_decoding(sgr_run, shape):
    """(2.7, 5) decoded at 2x5, "55" at 5x5; (5,) was an IndexError, (0, 5) 'no valid robot'."""
    from evolve.records.decode import decoded_champion
    from tsim.errors import SgrError

    with pytest.raises(SgrError, match=r"shape must be \(rows, cols\) of positive integers"):
        decoded_champion(sgr_run, shape)
    assert decoded_champion(sgr_run, np.array([5, 5]))["body"] == decoded_champion(sgr_run, (5, 5))["body"]
