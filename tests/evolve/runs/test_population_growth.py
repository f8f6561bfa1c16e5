"""A run whose speciation splits every genome off says so, once: neat-python keeps each species'
elites whatever pop_size says, so the population (and each generation's cost) grows without
bound, as the first 10x10 SGR run's did before the body distance was scaled to 5x5."""

from evolve.runs.experiment import Experiment
from tests.evolve.conftest import TINY


def test_a_population_past_pop_size_is_reported_once(tmp_path, capsys):
    cfg = {"method": "sgr", **TINY, "generations": 4, "body_distance_weight": 100.0}
    with Experiment.from_config(cfg, tmp_path / "run", quiet=True) as exp:
        exp.run_all()
    sizes = [int(r["n_valid"]) + int(r["n_invalid"]) for r in exp.run.rows()]
    err = capsys.readouterr().err
    assert max(sizes) > 1.25 * TINY["pop_size"], sizes  # the setting does grow it
    assert err.count("warning: the population has grown to") == 1, err
    assert "compatibility_threshold" in err and "body_distance_weight" in err


def test_the_packaged_speciation_keeps_pop_size(tmp_path, capsys):
    with Experiment.from_config({"method": "sgr", **TINY, "generations": 4}, tmp_path / "run",
                                quiet=True) as exp:
        exp.run_all()
    assert "population has grown" not in capsys.readouterr().err
