"""Rendering a task episode headlessly, and its GIF."""

import imageio.v3 as iio
import numpy as np

from tasks.render_episode import render_episode
from tsim.body import build_body
from tsim.render import SOFT_COLOR, write_gif

# no soft (2) voxels: in Thrower-v0 the ground is fixed (5) and the package is 3 x 2 soft voxels, so
# every soft-coloured pixel must belong to the package
BODY = np.array([[1, 1, 3, 3, 3],
                 [3, 3, 3, 1, 1],
                 [4, 4, 1, 4, 4],
                 [3, 1, 1, 1, 3],
                 [4, 0, 0, 0, 4]])


def test_render_episode_frames_and_lossless_gif(tmp_path):
    """A short Thrower episode gives 1 + steps/every frames, each showing the package, and the GIF
    holds exactly those frames (palette written without quantization).

    The robot has no soft voxels, so the soft-coloured pixels are the package alone: at 160 px for
    40 voxels (4 px a voxel) its 3 x 2 voxels fill at most 12 x 8 px, less the 1-px outline.
    """
    body = build_body(BODY)
    assert not np.any(body.voxel_type == 2)
    n = body.n_actuators
    frames = render_episode("Thrower-v0", body, lambda t, obs: np.full(n, 1.0 + 0.3 * (t % 2)), 6,
                            160, 80, every=2)
    assert len(frames) == 4
    assert all(f.shape == (80, 160, 3) and f.dtype == np.uint8 for f in frames)
    for f in frames:
        rows, cols = np.nonzero(np.all(f == SOFT_COLOR, axis=-1))
        assert 48 <= len(rows) <= 96  # at least half of the package's 12 x 8 px
        assert cols.max() - cols.min() < 12 and rows.max() - rows.min() < 8  # one 3 x 2 blob
    path = write_gif(frames, tmp_path / "ep.gif", fps=15)
    back = iio.imread(path)[..., :3]
    assert back.shape == (4, 80, 160, 3)
    assert np.array_equal(back, np.stack(frames))


def test_an_episode_too_long_to_keep_every_frame_keeps_every_kth_and_fits(monkeypatch):
    """Frames at most FRAME_BYTES: a run may ask for 1,000,000 steps, whose GIF at 640x320 would
    need 191 GiB (its end files then failed, and so did every resume). The least stride that fits
    is taken, and the frames are those of that stride asked for, bit for bit."""
    import tasks.render_episode as module

    body = build_body(BODY)
    n = body.n_actuators

    def policy(t, obs):
        return np.full(n, 1.0 + 0.3 * (t % 2))

    monkeypatch.setattr(module, "FRAME_BYTES", 96 * 48 * 6)  # six indexed frames of 96x48
    assert module.frame_stride(20, 96, 48, True) == 4 and module.frame_stride(21, 96, 48, True) == 5
    frames = render_episode("Thrower-v0", body, policy, 20, 96, 48, indexed=True)
    assert len(frames) == 6 and sum(f.nbytes for f in frames) <= module.FRAME_BYTES
    monkeypatch.setattr(module, "FRAME_BYTES", 2 << 30)
    assert module.frame_stride(20, 96, 48, True) == 1
    strided = render_episode("Thrower-v0", body, policy, 20, 96, 48, every=4, indexed=True)
    assert all(np.array_equal(a, b) for a, b in zip(frames, strided, strict=True))
    assert module.frame_stride(1_000_000, 640, 320, True) == 96  # ~2 GiB of a 1,000,000-step episode


def test_a_caption_says_the_step_and_the_return_so_far_and_covers_only_its_band():
    """`caption(t, running_return)` is asked for every frame with the steps done and the sum of the
    rewards so far (checked against the env's own rewards); the captioned frames equal the plain
    ones outside a band in the top-left corner, and stay `PALETTE` indices."""
    from tasks.env import BatchEnv
    from tsim.render import I_BACKGROUND, I_OUTLINE

    body = build_body(BODY)
    n = body.n_actuators

    def policy(t, obs):
        return np.full(n, 1.0 + 0.3 * (t % 2))

    asked = []

    def line(t, total):
        asked.append((t, total))
        return f"Thrower-v0 step {t} return {total:.3f}"

    plain = render_episode("Thrower-v0", body, policy, 6, 160, 80, every=2, indexed=True)
    shown = render_episode("Thrower-v0", body, policy, 6, 160, 80, every=2, indexed=True, caption=line)
    env = BatchEnv("Thrower-v0", [body], episode_steps=6)
    totals = [0.0]
    for t in range(6):
        _, reward, _, _, _ = env.step([policy(t, None)])
        totals.append(totals[-1] + float(reward[0]))
    assert [t for t, _ in asked] == [0, 2, 4, 6]
    assert [total for _, total in asked] == [totals[t] for t in (0, 2, 4, 6)]
    for a, b in zip(plain, shown, strict=True):
        rows, cols = np.nonzero(a != b)
        assert len(rows) > 20 and rows.max() < 80 // 3 and cols.min() < 10  # the band, top left
        assert set(np.unique(b[a != b])) <= {I_BACKGROUND, I_OUTLINE}
        assert np.any(b == I_OUTLINE)
