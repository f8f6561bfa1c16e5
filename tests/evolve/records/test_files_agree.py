"""A command that draws or re-chooses never leaves a run folder's files disagreeing: `sgr render
--replay I` writes its own GIF (champion.gif keeps the champion) and prints the replay's return
beside the nominal one; `sgr select-champion` draws champion.gif and fitness.png again for the
champion it wrote."""

from __future__ import annotations

import re
from pathlib import Path

import pytest
from PIL import Image

from evolve.cli import main
from evolve.records.replay import replay_champion


@pytest.fixture(scope="module")
def run_dir(tmp_path_factory) -> Path:
    """A finished tiny run with its champion.gif and fitness.png."""
    folder = tmp_path_factory.mktemp("agree")
    out = folder / "run"
    config = folder / "tiny.yaml"
    config.write_text("method: sgr\ntask: Walker-v0\ngenerations: 2\npop_size: 8\nepisode_steps: 40\n"
                      "workers: 1\nseed: 1\n")
    assert main(["evolve", "--config", str(config), "--out", str(out), "--quiet"]) == 0
    return out


def test_a_perturbed_replay_goes_to_its_own_gif_and_prints_both_returns(run_dir, capsys):
    before = (run_dir / "champion.gif").read_bytes()
    assert main(["render", str(run_dir), "--replay", "1", "--width", "64", "--height", "32"]) == 0
    line = capsys.readouterr().out.strip()
    assert (run_dir / "champion.gif").read_bytes() == before  # still the champion's own episode
    with Image.open(run_dir / "champion-replay1.gif") as im:
        assert im.size == (64, 32)
    returns = replay_champion(run_dir, 1, 1e-3)  # what sgr report replays: nominal, replay 1
    found = [float(x) for x in re.findall(r"return (-?\d+\.\d+)", line)]
    assert line.startswith(f"wrote {run_dir / 'champion-replay1.gif'}:"), line
    assert found == pytest.approx([returns[1], returns[0]], abs=1e-4), line
    assert "nominal" in line and "1e-3" in line.replace("0.001", "1e-3"), line


def test_re_choosing_the_champion_draws_its_gif_and_plot_again(run_dir, capsys):
    (run_dir / "champion.gif").write_bytes(b"the old genome's GIF")
    (run_dir / "fitness.png").write_bytes(b"the old genome's plot")
    assert main(["select-champion", str(run_dir), "--candidates", "2", "--episodes", "2"]) == 0
    for name in ("champion.gif", "fitness.png"):
        with Image.open(run_dir / name) as im:
            im.load()
    assert not (run_dir / ".writing-end-files").exists()
