"""Body decoders (evolve/methods/sgr/decoders/): each draws (H, W) material grids from the genome's CPPN at
any shape, as its docstring says (checked here against slow one-query-at-a-time oracles and the
growth rule's invariants); a good share of random mutated genomes draw valid robots, invalid ones
are flagged invalid; the new decoders draw other bodies than the paper's substrate from the same
genome; the controller is the same genome's, at its own output column; and a bad name or setting
is one line."""

import numpy as np
import pytest

from evolve.methods.sgr import SgrProblem
from evolve.methods.sgr import record as sgr_record
from evolve.methods.sgr.decoder import DecoderSettings, body_from_cppn, decode
from evolve.methods.sgr.decoders import DECODERS, body_decoder
from evolve.methods.sgr.decoders.growth import CHANNELS, NEIGHBOURS, grow
from evolve.methods.sgr.substrates import cell_coordinates
from evolve.nn.cppn import CompiledCPPN
from evolve.nn.genome_record import genome_json
from evolve.runs.config import config_from_dict
from tsim.body import is_connected
from tsim.errors import SgrError

NEW = ["cppn", "fourier", "growth"]


def settings(name: str, shape=(5, 5), cppn_outputs: int = 1, **given) -> DecoderSettings:
    return DecoderSettings(shape=shape, cppn_outputs=cppn_outputs, body_decoder=name,
                           body_settings=DECODERS[name].resolve(given))


def expressed(v: float) -> float:
    """The weight expression at threshold 0.2, max_weight 1, written out."""
    return 0.0 if abs(v) <= 0.2 else float(np.sign(v) * (abs(v) - 0.2) / 0.8)


def test_the_registry_holds_the_papers_substrate_as_default_and_three_more():
    assert list(DECODERS)[0] == "substrate" and DecoderSettings().body_decoder == "substrate"
    assert set(NEW) <= set(DECODERS)
    assert DECODERS["cppn"].body_outputs == 5 and DECODERS["growth"].body_outputs == 1


@pytest.mark.parametrize("name", ["substrate", *NEW])
@pytest.mark.parametrize("shape", [(5, 5), (10, 10)])
def test_random_mutated_genomes_draw_a_good_share_of_valid_robots_and_invalid_ones_are_flagged(
        neat_config, genomes, name, shape):
    """Of 150 random genomes mutated 6 times, >= 20 % draw valid robots (when written: substrate
    ~53 %, cppn ~60 %, fourier ~30-40 %, growth ~35 %); every phenotype says valid exactly when its
    body is connected with an actuator, and only a valid one gets a controller, driving its
    actuators."""
    s = settings(name, shape)
    cfg = neat_config(outputs=s.n_outputs)
    n_valid = 0
    for g in genomes(cfg, 150, seed=1):
        p = decode(g, cfg.genome_config, "Walker-v0", s)
        assert p.body.shape == shape and p.body.dtype == np.int64 and set(np.unique(p.body)) <= set(range(5))
        assert p.valid == (np.any(p.body != 0) and is_connected(p.body) and np.isin(p.body, (3, 4)).any())
        assert (p.controller is not None) == p.valid
        n_valid += p.valid
    assert n_valid >= 30, n_valid


@pytest.mark.parametrize("name", NEW)
def test_each_new_decoder_draws_other_bodies_than_the_substrate_from_the_same_genomes(
        neat_config, genomes, name):
    s = settings(name, (10, 10))
    cfg = neat_config(outputs=s.n_outputs)
    gs = genomes(cfg, 40, seed=2)
    cppns = [CompiledCPPN(g, cfg.genome_config) for g in gs]
    ours = [body_from_cppn(c, s) for c in cppns]
    paper = [body_from_cppn(c, DecoderSettings(shape=(10, 10))) for c in cppns]
    drawn = [(a, b) for a, b in zip(ours, paper, strict=True) if np.any(a) or np.any(b)]
    assert len(drawn) >= 20 and sum(not np.array_equal(a, b) for a, b in drawn) >= 0.8 * len(drawn)
    assert len({b.tobytes() for b in ours}) >= 10  # and not one body for every genome


def test_the_cppn_decoder_reads_presence_and_materials_at_each_cells_x_y_distance(neat_config, genomes):
    """Oracle: the CPPN asked once per cell at (x, y, d, 0, 0, 1, 1), d = |(x, y)| / sqrt(2);
    output 0 > 0 fills the cell, with 1 + the argmax of outputs 1-4."""
    s = settings("cppn", (4, 6))
    cfg = neat_config(outputs=5)
    for g in genomes(cfg, 6, seed=4):
        cppn = CompiledCPPN(g, cfg.genome_config)
        body = body_from_cppn(cppn, s)
        for (r, c), (x, y) in zip(np.ndindex(4, 6), cell_coordinates((4, 6)), strict=True):
            assert np.isclose(x, -1 + 2 * c / 5) and np.isclose(y, 1 - 2 * r / 3)
            out = cppn(np.array([[x, y, np.hypot(x, y) / np.sqrt(2), 0, 0, 1, 1]]))[0]
            assert body[r, c] == (1 + int(np.argmax(out[1:5])) if out[0] > 0 else 0)


def test_the_fourier_decoder_is_its_body_network_of_fourier_features(neat_config, genomes):
    """Oracle, one frequency and 2 hidden nodes: inputs (x, y, sin pi x, cos pi x, sin pi y,
    cos pi y) on a row at z=1, hidden at z=2 (tanh), 5 outputs at z=3, every weight one query."""
    s = settings("fourier", (3, 4), frequencies=1, hidden=2)
    cfg = neat_config()
    ins = [(x, 0.0, 1.0) for x in np.linspace(-1, 1, 6)]
    hid = [(-1.0, 0.0, 2.0), (1.0, 0.0, 2.0)]
    outs = [(x, 0.0, 3.0) for x in np.linspace(-1, 1, 5)]
    for g in genomes(cfg, 6, seed=5):
        cppn = CompiledCPPN(g, cfg.genome_config)
        body = body_from_cppn(cppn, s)

        def w(src, dst, cppn=cppn):
            return expressed(cppn(np.array([[*src, *dst, 1.0]]))[0, 0])
        for (r, c), (x, y) in zip(np.ndindex(3, 4), cell_coordinates((3, 4)), strict=True):
            f = [x, y, np.sin(np.pi * x), np.cos(np.pi * x), np.sin(np.pi * y), np.cos(np.pi * y)]
            h = [np.tanh(sum(f[i] * w(ins[i], hn) for i in range(6)) + w((0, 0, 0), hn)) for hn in hid]
            o = [sum(h[j] * w(hid[j], on) for j in range(2)) + w((0, 0, 0), on) for on in outs]
            assert body[r, c] == int(np.argmax(o))


def test_the_growth_rules_weights_are_cppn_queries_on_its_own_substrate(neat_config, genomes):
    """The first input -> hidden weight (the cell itself, channel 0, at (0, 0, 4)) and a bias, asked
    of the CPPN one at a time, are those the decoder grows with."""
    import evolve.methods.sgr.decoders.growth as growth

    cfg = neat_config()
    g = genomes(cfg, 1, seed=1)[0]
    cppn = CompiledCPPN(g, cfg.genome_config)
    seen = {}
    real = growth.grow
    try:
        growth.grow = lambda *a: seen.setdefault("w", a) and real(*a)
        body_from_cppn(cppn, settings("growth"))
    finally:
        growth.grow = real
    W1, b1, W2, b2, shape, steps = seen["w"]
    assert W1.shape == (5 * CHANNELS, CHANNELS) and W2.shape == (CHANNELS, CHANNELS)
    assert shape == (5, 5) and steps == 5  # max(H, W) by default
    assert NEIGHBOURS[1] == (0, 1)  # the second block of inputs is the neighbour above (+y)
    hidden = [(x, 0.0, 0.6) for x in np.linspace(-1, 1, CHANNELS)]
    outs = [(x, 0.0, 0.8) for x in np.linspace(-1, 1, CHANNELS)]
    for i, ((dx, dy), c) in enumerate((n, c) for n in NEIGHBOURS for c in range(CHANNELS)):
        for j, h in enumerate(hidden):
            q = np.array([[dx, dy, 0.25 + 0.25 * c / CHANNELS, *h, 1.0]])
            assert W1[i, j] == expressed(cppn(q)[0, 0])
    for j, o in enumerate(outs):
        assert b2[j] == expressed(cppn(np.array([[0, 0, 0, *o, 1.0]]))[0, 0])
        assert W2[3, j] == expressed(cppn(np.array([[*hidden[3], *o, 1.0]]))[0, 0])
    assert np.count_nonzero(W1) > 100  # most queries give links: the comparison is of numbers


def test_growth_fills_only_cells_next_to_filled_ones_one_ring_per_step():
    """Whatever the rule, the body holds the seed, is connected, and after k steps lies within
    Manhattan distance k of the seed; a rule that always says 'grow' fills exactly that diamond."""
    rng = np.random.default_rng(0)
    for trial in range(40):
        W1, b1 = rng.normal(size=(5 * CHANNELS, CHANNELS)), rng.normal(size=CHANNELS)
        W2, b2 = rng.normal(size=(CHANNELS, CHANNELS)), rng.normal(size=CHANNELS)
        shape = [(5, 5), (10, 10), (10, 5), (4, 7)][trial % 4]
        seed = ((shape[0] - 1) // 2, (shape[1] - 1) // 2)
        for k in (1, 2, 3, max(shape)):
            body = grow(W1, b1, W2, b2, shape, k)
            assert body[seed] != 0 and is_connected(body)
            rows, cols = np.nonzero(body)
            assert np.all(np.abs(rows - seed[0]) + np.abs(cols - seed[1]) <= k)
    W2, b2 = np.zeros((CHANNELS, CHANNELS)), np.zeros(CHANNELS)
    b2[0], b2[4] = 5.0, 5.0  # presence > 0 everywhere, material 4 (V actuator) the largest
    body = grow(np.zeros((5 * CHANNELS, CHANNELS)), np.zeros(CHANNELS), W2, b2, (7, 7), 2)
    rows, cols = np.indices((7, 7))
    assert np.array_equal(body, np.where(np.abs(rows - 3) + np.abs(cols - 3) <= 2, 4, 0))


def test_growth_steps_is_a_setting(neat_config, genomes):
    cfg = neat_config()
    for g in genomes(cfg, 30, seed=7):
        body = body_from_cppn(CompiledCPPN(g, cfg.genome_config), settings("growth", (9, 9), steps=1))
        assert np.count_nonzero(body) <= 5


def test_the_cppn_decoders_controller_reads_its_own_output_column(neat_config, genomes):
    """cppn_outputs 2: the genome has 6 outputs and the controller reads column 5 (cut: no weights),
    the body columns 0-4 in both wirings; cppn_outputs 1: the controller shares column 0."""
    assert SgrProblem.neat_overrides(config_from_dict(
        {"method": "sgr", "task": "Walker-v0", "body_decoder": "cppn", "cppn_outputs": 2}))[
        "DefaultGenome"]["num_outputs"] == "6"
    cfg = neat_config(outputs=6)
    two, one = settings("cppn", cppn_outputs=2), settings("cppn")
    assert (two.controller_output, one.controller_output, two.n_outputs) == (5, 0, 6)
    for g in genomes(cfg, 20, seed=8):
        for key in [k for k in g.connections if k[1] == 5]:
            del g.connections[key]
        g.nodes[5].bias = 0.0
        a, b = decode(g, cfg.genome_config, "Walker-v0", two), decode(g, cfg.genome_config, "Walker-v0", one)
        assert np.array_equal(a.body, b.body)
        if a.valid:
            assert all(np.all(W == 0) for W in a.controller.weights)
            assert any(np.any(W != 0) for W in b.controller.weights)
            return
    raise AssertionError("no valid body among 20 genomes")


@pytest.mark.parametrize("name", NEW)
def test_a_champion_records_its_decoder_and_is_rebuilt_and_checked_by_its_digest(neat_config, genomes, name):
    s = settings(name, (10, 5))
    cfg = neat_config(outputs=s.n_outputs)
    paper_of = DecoderSettings(shape=(10, 5))  # a genome whose body the paper's substrate draws otherwise
    g, p = next((g, p) for g in genomes(cfg, 60, seed=9)
                if (p := decode(g, cfg.genome_config, "Walker-v0", s)).valid
                and not np.array_equal(p.body, body_from_cppn(CompiledCPPN(g, cfg.genome_config), paper_of)))
    c = sgr_record.recorded(g, p.controller, s, p.body, "Walker-v0")
    assert c["format"] == sgr_record.FORMAT and c["decoder"]["body_decoder"] == name
    assert c["decoder"]["body_decoder_settings"] == dict(s.body_settings)
    assert c["doc"].endswith(sgr_record.DOC_DECODER)
    record = {"controller": c, "genome": genome_json(g), "body": p.body.tolist(), "task": "Walker-v0"}
    assert sgr_record.digest(sgr_record.rebuild(record)) == sgr_record.digest(p.controller)
    paper = {**record, "controller": {**c, "decoder": {k: v for k, v in c["decoder"].items()
                                                        if not k.startswith("body_decoder")}}}
    with pytest.raises(ValueError, match="draws another body"):  # read as the substrate's
        sgr_record.rebuild(paper)


def test_a_champion_of_the_papers_substrate_is_recorded_as_before_and_reads_as_it(neat_config, genomes):
    cfg = neat_config()
    s = DecoderSettings()
    g, p = next((g, p) for g in genomes(cfg, 30) if (p := decode(g, cfg.genome_config, "Walker-v0", s)).valid)
    c = sgr_record.recorded(g, p.controller, s, p.body, "Walker-v0")
    assert set(c["decoder"]) == {"shape", "cppn_outputs", "weight_threshold", "max_weight"}
    assert c["doc"] == sgr_record.DOC
    assert sgr_record.settings_of(c) == s


@pytest.mark.parametrize("changes, message", [
    ({"body_decoder": "spiral"}, "key 'body_decoder' must be one of substrate, cppn, fourier, growth, "
                                 "got 'spiral'"),
    ({"body_decoder": 3}, "key 'body_decoder' must be str"),
    ({"body_decoder": "growth", "body_decoder_settings": {"steps": 0}}, "setting 'steps' of body decoder"),
    # a typo's extra zeros hung the run (growth steps, fourier's features and queries)
    ({"body_decoder": "growth", "body_decoder_settings": {"steps": 10**9}},
     "setting 'steps' of body decoder 'growth' must be int or null from 1 to 10,000, got 1000000000"),
    ({"body_decoder": "fourier", "body_decoder_settings": {"frequencies": 10**6}},
     "setting 'frequencies' of body decoder 'fourier' must be int from 1 to 64"),
    ({"body_decoder": "fourier", "body_decoder_settings": {"hidden": 10**6}},
     "setting 'hidden' of body decoder 'fourier' must be int from 1 to 1,024"),
    ({"body_decoder": "fourier", "body_decoder_settings": {"steps": 3}}, "unknown setting 'steps' for body "
                                                                         "decoder 'fourier'"),
    ({"body_decoder_settings": {"hidden": 2}}, "unknown setting 'hidden' for body decoder 'substrate'"),
])
def test_a_bad_decoder_or_setting_in_a_config_is_one_line(changes, message):
    with pytest.raises(SgrError) as err:
        config_from_dict({"method": "sgr", "task": "Walker-v0", **changes}, "c.yaml")
    assert message in str(err.value) and "\n" not in str(err.value) and str(err.value).startswith("c.yaml")


def test_an_unknown_decoder_on_the_command_line_is_one_line_and_exit_2(tmp_path, capsys):
    from evolve.cli import main

    assert main(["evolve", "--body-decoder", "spiral", "--out", str(tmp_path / "r")]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1
    assert "key 'body_decoder' must be one of substrate, cppn, fourier, growth" in err
    assert not (tmp_path / "r").exists()
    assert main(["evolve", "--resume", str(tmp_path), "--body-decoder", "growth"]) == 2  # a run keeps its own
    assert "--resume continues a run with its own config" in capsys.readouterr().err
    with pytest.raises(SgrError, match="key 'body_decoder'"):
        body_decoder("spiral")


def test_body_decoder_with_a_method_that_draws_no_body_names_the_flag_in_one_line(tmp_path, capsys):
    """Direct NEAT's genome is the body: the line names the flag and the methods that take it, not
    an unknown key of the packaged config; nothing is run."""
    from evolve.cli import main

    assert main(["evolve", "--method", "direct", "--task", "Walker-v0", "--body-decoder", "cppn",
                 "--out", str(tmp_path / "r")]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "--body-decoder is for the methods whose genome draws the body" in err
    assert "sgr" in err and "method 'direct' has no body decoder" in err
    assert not (tmp_path / "r").exists()


def test_an_older_runs_config_without_the_keys_reads_as_the_papers_decoder(neat_config):
    raw = config_from_dict({"method": "sgr", "task": "Walker-v0"}).to_yaml()
    del raw["body_decoder"], raw["body_decoder_settings"]
    problem = SgrProblem(raw, neat_config())
    assert problem.settings == DecoderSettings()


def test_runs_of_another_body_decoder_are_reported_as_a_method_of_their_own(tmp_path):
    """Reports and plots never average runs of two decoders: sgr with the growth decoder is
    "sgr (growth)"; the paper's substrate, named or not (an older run), stays "sgr"."""
    from evolve.report.groups import run_settings

    base = {"method": "sgr", "task": "Walker-v0"}
    assert run_settings(tmp_path, base)["method"] == "sgr"
    assert run_settings(tmp_path, {**base, "body_decoder": "substrate"})["method"] == "sgr"
    assert run_settings(tmp_path, {**base, "body_decoder": "growth"})["method"] == "sgr (growth)"
