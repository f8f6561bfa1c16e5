"""report.html, opened in a real headless browser (Chromium from the system packages; .ci/run
installs it): the page renders, and every image it inlines (curves, champion GIF, body) loads,
with no network and no file beside it."""

from __future__ import annotations

import os
import re
import shutil
import subprocess
from pathlib import Path

import numpy as np
import pytest

from evolve.report.gallery import VOXEL_RGB, body_image
from evolve.report.report import write_report
from evolve.runs.experiment import Experiment

pytestmark = [pytest.mark.slow, pytest.mark.browser]


def chromium() -> str:
    exe = shutil.which("chromium") or shutil.which("chromium-browser") or shutil.which("google-chrome")
    if exe is None:
        if os.environ.get("CI"):
            pytest.fail("Chromium is missing: .ci/run installs it (apt-get install chromium)")
        pytest.skip("no Chromium here (apt-get install chromium); CI runs this test")
    return exe


def browse(exe: str, page: Path, *flags: str) -> subprocess.CompletedProcess:
    return subprocess.run([exe, "--headless", "--no-sandbox", "--disable-gpu", "--hide-scrollbars",
                           "--allow-file-access-from-files", "--virtual-time-budget=5000", *flags,
                           page.as_uri()], capture_output=True, text=True, timeout=120)


def test_report_html_renders_with_every_image_in_headless_chromium(tmp_path):
    exe = chromium()
    exp = Experiment.from_config({"method": "sgr", "task": "Walker-v0", "generations": 2, "pop_size": 8,
                                  "episode_steps": 40, "render_champion": False, "workers": 1,
                                  "robust": None, "final_selection": None},
                                 tmp_path / "runs" / "sgr-Walker-v0-s0", quiet=True)
    exp.run_all()
    exp.close()
    report = write_report(tmp_path, tmp_path / "out" / "report.md", replays=2)
    page = report.parent / "report.html"
    moved = tmp_path / "elsewhere" / "report.html"  # alone: nothing beside it to load
    moved.parent.mkdir()
    shutil.copy(page, moved)

    dom = browse(exe, moved, "--dump-dom").stdout
    assert 'data-total="3"' in dom and 'data-ok="3"' in dom, dom[-500:]
    assert "3 of 3 images loaded" in dom and "<table>" in dom

    shot = tmp_path / "shot.png"
    browse(exe, moved, f"--screenshot={shot}", "--window-size=1200,2400")
    import imageio.v3 as iio

    img = iio.imread(shot)[:, :, :3].astype(int)
    colors = {tuple(c) for c in img.reshape(-1, 3)[::7]}
    assert len(colors) > 50, "a blank page"
    # the status line shows (in red, #cf222e) only where an image did not decode: here it is hidden
    assert re.search(r"<p id=\"images\"[^>]*hidden", dom), dom[-500:]
    assert not np.any(np.all(np.abs(img - (0xcf, 0x22, 0x2e)) <= 2, axis=2))
    # the champion's body picture is on screen, in its own colours
    body = exp.search.best["phenotype"].body
    want = {tuple(int(v) for v in VOXEL_RGB[t]) for t in np.unique(body) if t > 0}
    for c in want:
        assert np.any(np.all(np.abs(img - c) <= 2, axis=2)), f"voxel colour {c} not on the page"
    assert body_image(body).shape == (body.shape[0] * 20 + 1, body.shape[1] * 20 + 1, 3)
