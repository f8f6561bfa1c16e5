"""Champion files small enough to commit at 10x10 (issue 36), losslessly: SGR's controller is
recorded as its genome's decoding and direct NEAT's network as its genome's compiled form, each
checked against a SHA-256 when read; a 10x10 SGR champion is a few KB (it was ~650 KB), reads back as
the very controller decoding gives, bit for bit, and replays to the same fitness as the same robot
written in full. Files of the older layout (tests/data/champions) still load, and their rewrite
(`evolve.records.compact`) is the same robot with the same returns."""

import json
import shutil
from pathlib import Path

import numpy as np
import pytest

from evolve.methods.sgr.decoder import DecoderSettings, decode
from evolve.nn.dense import DenseController
from evolve.nn.genome_record import genome_from_record
from evolve.nn.graph import GraphController
from evolve.records.compact import compact_file
from evolve.records.decode import write_decoded
from evolve.records.files import record_json
from evolve.records.replay import load_champion, rescore_champion
from evolve.search.neat_ini import load_neat_config
from tests.evolve.conftest import tiny_run
from tsim.errors import SgrError

OLD = Path(__file__).resolve().parents[2] / "data" / "champions"
# what the committed files give where numpy's float kernels are not those they were recorded with
AVX2 = json.loads((OLD / "avx2-float-kernels.json").read_text())


def recording_kernels() -> bool:
    """Whether numpy here takes the AVX-512 kernels for tanh and exp that the committed results were
    recorded with (else an AVX2-only CPU's, whose bits `AVX2` holds)."""
    try:
        from numpy._core._multiarray_umath import __cpu_features__
    except ImportError:  # numpy 1.x
        from numpy.core._multiarray_umath import __cpu_features__
    return bool(__cpu_features__.get("AVX512_SKX"))
@pytest.fixture(scope="module")
def big(sgr_run, tmp_path_factory):
    """The tiny run's champion genome decoded at 10x10: a champion folder."""
    return write_decoded(sgr_run, (10, 10), tmp_path_factory.mktemp("big") / "big")


def same_dense(a: DenseController, b: DenseController) -> bool:
    """Bit for bit: the same float64 bytes in every weight and bias, same activations and cells."""
    return (len(a.weights) == len(b.weights) and a.activations == b.activations
            and a.input_size == b.input_size and np.array_equal(a.action_cells, b.action_cells)
            and all(x.shape == y.shape and x.tobytes() == y.tobytes()
                    for x, y in zip(a.weights + a.biases, b.weights + b.biases, strict=True)))


def test_a_10x10_sgr_champion_file_is_a_few_kb(big):
    """~650 KB when the controller's 24,400 weights were written as JSON numbers."""
    size = (big / "champion.json").stat().st_size
    record = json.loads((big / "champion.json").read_text())
    assert record["controller"]["format"] == "sgr-hyperneat-controller-1"
    assert np.asarray(record["body"]).shape == (10, 10)
    assert size < 12_000, size


def test_a_10x10_sgr_champion_reads_back_as_its_decoding_bit_for_bit(sgr_run, big):
    record = json.loads((big / "champion.json").read_text())
    gc = load_neat_config(sgr_run / "neat.ini").genome_config
    genome = genome_from_record(record["genome"], gc)
    decoded = decode(genome, gc, "Walker-v0", DecoderSettings(shape=(10, 10)))
    champ = load_champion(big)
    assert np.array_equal(champ.body, decoded.body)
    assert same_dense(champ.controller, decoded.controller)
    assert champ.controller.weights[1].shape == (100, 100)  # 10x10 hidden nodes to 10x10 outputs


def test_the_compact_and_the_full_file_of_a_champion_replay_the_same_fitness(big, tmp_path):
    """The same record with the controller written in full (the older layout) and as the genome's
    decoding: the same returns, bit for bit, and the recorded fitness."""
    record = json.loads((big / "champion.json").read_text())
    full = tmp_path / "full"
    full.mkdir()
    record["controller"] = load_champion(big).controller.to_json()
    (full / "champion.json").write_text(json.dumps(record, indent=1))
    assert (full / "champion.json").stat().st_size > 40 * (big / "champion.json").stat().st_size
    assert rescore_champion(big) == rescore_champion(full) == record["fitness"]
    obs = np.random.default_rng(0).uniform(-1, 1, load_champion(big).controller.input_size)
    assert load_champion(big).policy(obs).tobytes() == load_champion(full).policy(obs).tobytes()


@pytest.mark.parametrize("edit, message", [
    (lambda r: r["controller"].update(sha256="0" * 64), "sha256 differs"),
    (lambda r: r["genome"]["connections"]["weight"].__setitem__(0, r["genome"]["connections"]["weight"][0]
                                                                + 1e-9), "key 'controller'"),
    (lambda r: r["controller"]["decoder"].update(max_weight=2.0), "key 'controller'"),
])
def test_a_compact_record_whose_genome_no_longer_gives_its_weights_is_refused_in_one_line(big, tmp_path, edit,
                                                                                           message):
    record = json.loads((big / "champion.json").read_text())
    edit(record)
    (tmp_path / "champion.json").write_text(json.dumps(record))
    with pytest.raises(SgrError, match=message) as err:
        load_champion(tmp_path)
    assert "\n" not in str(err.value) and "champion.json: key 'controller'" in str(err.value)


def test_a_direct_champion_records_its_network_as_its_genome_and_replays_its_fitness(tmp_path):
    d = tiny_run("direct", tmp_path / "direct")
    record = json.loads((d / "champion.json").read_text())
    assert record["controller"]["format"] == "sgr-genome-graph-controller-1"
    assert "nodes" not in record["controller"]
    assert rescore_champion(d) == record["fitness"]


def old_controller(d: Path):
    record = json.loads((d / "champion.json").read_text())
    c = record["controller"]
    dense = c["format"] == "sgr-dense-controller-1"
    return DenseController.from_json(c) if dense else GraphController.from_json(c)


@pytest.mark.parametrize("name, fmt, replay", [
    ("sgr-Walker-v0-paper-s0", "sgr-hyperneat-controller-1", True),
    ("direct-Walker-v0-paper-s1", "sgr-genome-graph-controller-1", True),
    ("direct-per-cell-Walker-v0-s0", "sgr-genome-graph-controller-1", False),
])
def test_an_old_champion_file_loads_and_its_rewrite_is_the_same_robot(tmp_path, name, fmt, replay):
    d = tmp_path / name
    shutil.copytree(OLD / name, d)
    old = json.loads((d / "champion.json").read_text())
    assert isinstance(old["genome"]["nodes"], list)  # the older layout: an object per gene
    before = load_champion(d)
    original = old_controller(d)
    returns = rescore_champion(d) if replay else None
    if replay:  # the paper's nominal runs: their episode gives the recorded fitness (bit for bit with
        # the float kernels it was recorded with; an AVX2-only CPU's give `AVX2`'s)
        want = old["fitness"] if recording_kernels() else AVX2["fitness"].get(name, old["fitness"])
        assert returns == want
    b, a = compact_file(d / "champion.json")
    assert a < b / 2 and a == (d / "champion.json").stat().st_size
    new = json.loads((d / "champion.json").read_text())
    assert new["controller"]["format"] == fmt and isinstance(new["genome"]["nodes"], dict)
    assert {k: v for k, v in new.items() if k not in ("controller", "genome")} == \
           {k: v for k, v in old.items() if k not in ("controller", "genome")}
    after = load_champion(d)
    assert np.array_equal(after.body, before.body)
    if isinstance(original, DenseController):
        assert same_dense(after.controller, original)
    else:
        assert after.controller.to_json() == original.to_json()
    if replay:
        assert rescore_champion(d) == returns
    assert compact_file(d / "champion.json") == (a, a)  # a second rewrite changes nothing


def test_an_old_champion_whose_genome_decodes_otherwise_keeps_its_controller_in_full(tmp_path):
    """The rewrite never trades a controller for a decoding that differs from it."""
    d = tmp_path / "run"
    shutil.copytree(OLD / "sgr-Walker-v0-paper-s0", d)
    record = json.loads((d / "champion.json").read_text())
    record["controller"]["layers"][0]["weights"][0][0] += 1e-12
    (d / "champion.json").write_text(json.dumps(record, indent=1))
    compact_file(d / "champion.json")
    new = json.loads((d / "champion.json").read_text())
    assert new["controller"]["format"] == "sgr-dense-controller-1"
    w = new["controller"]["layers"][0]["weights"][0][0]
    assert w == record["controller"]["layers"][0]["weights"][0][0]


def test_every_committed_sgr_champion_decodes_again_to_its_recorded_body_and_weights():
    """The results' champion files (results/**/champion*.json) in the compact format are decoded
    again from their genomes and checked against their recorded bodies and weights' SHA-256s:
    data written by the runs, over every body decoder and at 5x5, 10x5 and 10x10, so a change to
    any decoder's bits (or to the default's, which every older run used) fails here."""
    from evolve.methods.sgr.record import FORMAT, rebuild

    seen = set()
    root = OLD.parents[2]
    for path in sorted((root / "results").rglob("champion*.json")):
        record = json.loads(path.read_text())
        c = record.get("controller")
        if not (isinstance(c, dict) and c.get("format") == FORMAT):
            continue
        if not recording_kernels():  # the digest with this machine's float kernels (`recording_kernels`)
            c["sha256"] = AVX2["digests"].get(path.relative_to(root).as_posix(), c["sha256"])
        rebuild(record)  # ValueError naming what differs
        seen.add((c["decoder"].get("body_decoder", "substrate"), tuple(c["decoder"]["shape"])))
    assert {d for d, _ in seen} == {"substrate", "cppn", "fourier", "growth"}
    assert {(5, 5), (10, 5), (10, 10)} <= {shape for _, shape in seen}


def test_record_json_puts_lists_of_plain_values_on_one_line_and_parses_to_the_same_data():
    data = {"body": [[0, 3], [4, 1]], "genome": {"key": 5, "nodes": {"bias": [0.1, -2.5e-17]}},
            "controller": None, "nested": [{"a": 1}, [1, 2], 3.0]}
    text = record_json(data)
    assert json.loads(text) == data
    lines = text.splitlines()
    assert "  [0, 3]," in lines and '   "bias": [0.1, -2.5e-17]' in lines and '  {"a": 1},' in lines
    assert len(lines) == 18
