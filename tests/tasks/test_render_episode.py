"""Rendering a task episode headlessly, and its GIF."""

import imageio.v3 as iio
import numpy as np

from tasks.render_episode import render_episode
from tsim.body import build_body
from tsim.render import SOFT_COLOR, write_gif

BODY = np.array([[1, 1, 2, 2, 2],
                 [3, 3, 3, 1, 2],
                 [4, 4, 1, 4, 4],
                 [3, 2, 2, 2, 3],
                 [4, 0, 0, 0, 4]])


def test_render_episode_frames_and_lossless_gif(tmp_path):
    """A short Thrower episode gives 1 + steps/every frames with the package (soft) visible, and the
    GIF holds exactly those frames (palette written without quantization)."""
    body = build_body(BODY)
    n = body.n_actuators
    frames = render_episode("Thrower-v0", body, lambda t, obs: np.full(n, 1.0 + 0.3 * (t % 2)), 6,
                            160, 80, every=2)
    assert len(frames) == 4
    assert all(f.shape == (80, 160, 3) and f.dtype == np.uint8 for f in frames)
    assert np.any(np.all(frames[-1] == SOFT_COLOR, axis=-1))
    path = write_gif(frames, tmp_path / "ep.gif", fps=15)
    back = iio.imread(path)[..., :3]
    assert back.shape == (4, 80, 160, 3)
    assert np.array_equal(back, np.stack(frames))
