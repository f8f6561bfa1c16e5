"""MP4 beside GIF: with imageio's ffmpeg plugin (the `video` extra) a run's champion.gif gets a
champion.mp4 of the same frames and `sgr render --out X.mp4` writes an MP4; without it, the GIF
alone, and asking for an MP4 is one line saying how to install the plugin."""

from __future__ import annotations

import imageio.v3 as iio
import numpy as np
import pytest
from PIL import Image, ImageSequence

import tsim.render
from evolve.cli import main
from evolve.records.replay import champion_gif

FPS = 30.0


def gif_frames(path) -> list[np.ndarray]:
    """The GIF's frames as shown: a frame that Pillow merged with identical neighbours (their
    durations added up) repeated as many times as it lasts frames of 1/FPS s."""
    out = []
    with Image.open(path) as im:
        for frame in ImageSequence.Iterator(im):
            times = max(1, round(frame.info["duration"] / (1000.0 / FPS)))
            out += [np.asarray(frame.convert("RGB"))] * times
    return out


def assert_same_frames(mp4, frames) -> None:
    """As many video frames as GIF frames, each the GIF's picture up to H.264's loss (4:2:0 colour
    and its rounding: ~4 of 255 on average), and the first and last each nearer its own GIF frame
    than the other end's (the robot moves: the video runs forwards, in step)."""
    video = list(iio.imiter(mp4))
    assert len(video) == len(frames)
    h, w = frames[0].shape[:2]

    def err(v, f):
        return np.abs(v[:h, :w].astype(int) - f.astype(int)).mean()

    errors = [err(v, f) for v, f in zip(video, frames, strict=True)]
    assert max(errors) < 8.0, max(errors)  # of 255
    assert err(video[0], frames[0]) < err(video[0], frames[-1])
    assert err(video[-1], frames[-1]) < err(video[-1], frames[0])


def test_a_runs_champion_gif_gets_an_mp4_of_the_same_frames_beside_it(sgr_run, tmp_path):
    pytest.importorskip("imageio_ffmpeg", reason="the video extra: pip install 'sgr[video]'")
    gif = champion_gif(sgr_run, width=160, height=80)
    assert gif == sgr_run / "champion.gif"
    assert_same_frames(sgr_run / "champion.mp4", gif_frames(gif))
    # an explicit GIF path (a report's gallery) gets no MP4 beside it
    champion_gif(sgr_run, tmp_path / "g.gif", width=160, height=80)
    assert not (tmp_path / "g.mp4").exists()


def test_sgr_render_out_mp4_writes_the_episode_as_an_mp4(sgr_run, tmp_path, capsys):
    pytest.importorskip("imageio_ffmpeg", reason="the video extra: pip install 'sgr[video]'")
    out = tmp_path / "c.mp4"
    assert main(["render", str(sgr_run), "--out", str(out), "--width", "161", "--height", "81"]) == 0
    printed = capsys.readouterr().out
    assert f"wrote {out}: " in printed and "nominal return" in printed, printed
    assert main(["render", str(sgr_run), "--out", str(tmp_path / "c.gif"), "--width", "161",
                 "--height", "81"]) == 0
    assert iio.improps(out, index=0).shape == (82, 162, 3)  # odd sides padded by one pixel
    assert_same_frames(out, gif_frames(tmp_path / "c.gif"))


def test_without_the_ffmpeg_plugin_the_gif_alone_and_an_mp4_asked_for_is_one_line(
        sgr_run, tmp_path, capsys, monkeypatch):
    monkeypatch.setattr(tsim.render, "video_available", lambda: False)
    stale = sgr_run / "champion.mp4"
    stale.write_bytes(b"an older champion's video")
    assert main(["render", str(sgr_run), "--width", "64", "--height", "32"]) == 0
    assert capsys.readouterr().out.startswith(f"wrote {sgr_run / 'champion.gif'}: ")
    assert not stale.exists()  # it showed another episode than champion.gif now does
    assert main(["render", str(sgr_run), "--out", str(tmp_path / "c.mp4")]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert err == [f"sgr: error: --out {tmp_path / 'c.mp4'}: writing an MP4 needs imageio's ffmpeg plugin: "
                   "pip install 'sgr[video]' (or: pip install imageio-ffmpeg)"]
    assert not (tmp_path / "c.mp4").exists()


def test_champion_gif_names_the_task_step_and_return_unless_asked_not_to(sgr_run, tmp_path, capsys):
    """champion.gif's frames carry a line (task, step, running return) in their top-left band;
    `overlay=False` (`sgr render RUN --no-overlay`) draws the robot alone; elsewhere they agree."""
    shown = iio.imread(champion_gif(sgr_run, tmp_path / "a.gif", width=160, height=80, replay=0))
    assert main(["render", str(sgr_run), "--exact", "--no-overlay", "--width", "160", "--height", "80",
                 "--out", str(tmp_path / "b.gif")]) == 0, capsys.readouterr().err
    plain = iio.imread(tmp_path / "b.gif")
    assert shown.shape == plain.shape
    rows = np.nonzero(np.any(shown != plain, axis=(0, 2, 3)))[0]
    assert len(rows) and rows.max() < 80 // 3
