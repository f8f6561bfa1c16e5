"""`sgr render` and `sgr plot` from the command line: BODY parsing, GIF and PNG outputs."""

import json

import imageio.v3 as iio
import numpy as np
import pytest

from evolve.cli import main, parse_body


def test_body_argument_forms(tmp_path):
    m = parse_body("33333,33033,11111")
    assert m.shape == (3, 5) and m[1, 2] == 0
    (tmp_path / "b.json").write_text(json.dumps({"body": m.tolist()}))
    np.save(tmp_path / "b.npy", m)
    assert np.array_equal(parse_body(str(tmp_path / "b.json")), m)
    assert np.array_equal(parse_body(str(tmp_path / "b.npy")), m)
    for bad in ("333,33", "3a3,333", ""):
        with pytest.raises(ValueError, match="bad body matrix"):
            parse_body(bad)


def test_render_any_body_writes_a_gif_and_bad_bodies_are_named(tmp_path, capsys):
    out = tmp_path / "w.gif"
    assert main(["render", "--task", "Walker-v0", "--body", "333,303", "--steps", "4",
                 "--width", "96", "--height", "48", "--out", str(out)]) == 0
    assert iio.imread(out).shape[:3] == (5, 48, 96)  # reset frame + 4 steps
    assert main(["render", "--task", "Walker-v0", "--body", "303,303", "--steps", "4"]) == 2
    assert "bad body matrix" in capsys.readouterr().err  # two disconnected columns


def test_steps_on_a_runs_champion_is_refused_not_ignored(tmp_path, capsys):
    """A run's champion is drawn over its run's episode: --steps (meant for --body) was silently
    ignored there."""
    assert main(["render", str(tmp_path), "--steps", "10"]) == 2
    assert "--steps sets the length of a --body episode" in capsys.readouterr().err


def test_plot_three_runs_writes_one_png(tmp_path):
    runs = []
    for i, method in enumerate(["sgr", "sgr", "direct"]):
        d = tmp_path / f"r{i}"
        d.mkdir()
        (d / "config.yaml").write_text(f"method: {method}\ntask: Walker-v0\n")
        (d / "generations.csv").write_text("generation,best,mean,median\n0,1.0,0.5,0.5\n1,2.0,1.0,1.0\n")
        runs.append(str(d))
    assert main(["plot", *runs, "--out", str(tmp_path / "c.png")]) == 0
    assert (tmp_path / "c.png").read_bytes()[:4] == b"\x89PNG"
