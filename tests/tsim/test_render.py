"""Headless renderer: evogym's colours and strain shading, pixel coverage, episodes and GIFs."""

import numpy as np
import pytest

from tasks.specs import task_world
from tsim.body import build_body
from tsim.render import (
    BLUES,
    ORANGES,
    PALETTE,
    RIGID_COLOR,
    SOFT_COLOR,
    Renderer,
    strain_index,
    write_gif,
)

WALKER_ORIGIN = (1, 1)  # grid cell of the robot's bottom-left in Walker-v0 (spec section 7)

# rigid 1, soft 2, H actuator 3, V actuator 4: 4 rigid, 7 soft, 5 H, 6 V voxels
BODY = np.array([[1, 1, 2, 2, 2],
                 [3, 3, 3, 1, 2],
                 [4, 4, 1, 4, 4],
                 [3, 2, 2, 2, 3],
                 [4, 0, 0, 0, 4]])


def test_actuator_tables_match_spec_samples():
    """Spec section 9 lists 11 entries of each 100-colour table; ours must reproduce them exactly."""
    idx = [0, 25, 37, 40, 45, 50, 55, 60, 62, 70, 99]
    orange = [(255, 245, 235), (253, 207, 161), (253, 174, 108), (253, 166, 96), (253, 153, 77),
              (253, 140, 58), (248, 125, 42), (243, 110, 25), (241, 105, 19), (225, 83, 7), (127, 39, 4)]
    blue = [(247, 251, 255), (197, 219, 239), (158, 202, 225), (146, 195, 222), (126, 184, 218),
            (105, 173, 213), (89, 162, 207), (72, 150, 200), (66, 146, 198), (44, 124, 187), (8, 48, 107)]
    assert ORANGES.shape == BLUES.shape == (100, 3)
    assert [tuple(int(v) for v in ORANGES[i]) for i in idx] == orange
    assert [tuple(int(v) for v in BLUES[i]) for i in idx] == blue


def test_strain_index_follows_spec_rule():
    """Spec: s=1.25 -> 37, s just above 1 -> 49, just below 1 -> 50, s=0.75 -> 62; clamped ends."""
    s = np.array([1.25, 1 + 1e-12, 1 - 1e-12, 0.75, 2.5, 0.6, 1.5, 0.0])
    assert strain_index(s).tolist() == [37, 49, 50, 62, 0, 70, 25, 99]


def _spec_color(body, pts, v):
    """Expected fill of voxel v, computed here from the spec's rule (not the renderer's code)."""
    t = body.voxel_type[v]
    if t in (1, 5):
        return RIGID_COLOR
    if t == 2:
        return SOFT_COLOR
    tl, tr, br, bl = (pts[:, p] for p in body.voxel_points[v])
    pairs = [(tl, tr), (bl, br)] if t == 3 else [(tl, bl), (tr, br)]
    s = np.mean([np.linalg.norm(a - b) for a, b in pairs]) / 0.1
    i = min(max(int((2 - s) * 50), 0), 50) if s > 1 else min(max(int((1 - s) * 50), 0), 50) + 50
    return tuple(int(c) for c in (ORANGES if t == 3 else BLUES)[min(i, 99)])


def test_material_pixel_counts_match_voxel_counts_in_walker_at_reset():
    """Each fill colour covers (voxels of that colour) x (px per voxel)^2 pixels within 20%, inside
    the robot's box; terrain colour lies under the robot, not above it."""
    body = build_body(BODY)
    pts = body.place(*WALKER_ORIGIN)  # BatchSim's reset positions
    r = Renderer(task_world("Walker-v0"), body, 640, 320, view_voxels=20.0)  # 32 px per voxel
    img = r.frame(pts)
    assert img.shape == (320, 640, 3) and img.dtype == np.uint8
    ppv = 32
    (c0, r0), (c1, r1) = np.round(r.to_pixels(np.array([[0.1, 0.6], [0.6, 0.1]]))).astype(int)
    assert (c1 - c0, r1 - r0) == (5 * ppv, 5 * ppv)
    robot = img[r0:r1, c0:c1].reshape(-1, 3)

    expected: dict[tuple, int] = {}
    for v in range(body.n_voxels):
        col = _spec_color(body, pts, v)
        expected[col] = expected.get(col, 0) + 1
    assert len(expected) >= 4  # rigid, soft, some orange, some blue
    for col, n_vox in expected.items():
        n_px = int(np.all(robot == col, axis=1).sum())
        assert abs(n_px - n_vox * ppv * ppv) <= 0.2 * n_vox * ppv * ppv, (col, n_px, n_vox)

    def at(x, y):
        c, row = np.floor(r.to_pixels(np.array([x, y]))).astype(int)
        return tuple(int(v) for v in img[row, c])

    for x in (0.15, 0.35, 0.55, 1.15):  # ground cells (y 0..0.1) under and beside the robot
        assert at(x, 0.05) == RIGID_COLOR
    assert at(0.35, 0.75) != RIGID_COLOR  # air above the robot


def test_write_gif_rejects_empty(tmp_path):
    """No frames is an error, not an empty file."""
    with pytest.raises(ValueError, match="no frames"):
        write_gif([], tmp_path / "x.gif")


def test_camera_follows_robot_smoothly():
    """The view starts centred on the robot, then moves a `follow` fraction of each jump per frame."""
    body = build_body(BODY)
    pts = body.place(*WALKER_ORIGIN)
    r = Renderer(task_world("Walker-v0"), body, 640, 320, follow=0.25)  # 16 px per voxel, 160 px per unit
    r.frame(pts)
    x0 = r.view[0]
    assert abs((x0 + 2.0) - 0.35) <= 1 / 160  # robot centre x 0.35 is mid-view (view 4.0 wide)
    r.frame(pts + np.array([[1.0], [0.0]]))
    assert abs(r.view[0] - (x0 + 0.25)) <= 1 / 160


def test_camera_keeps_the_robot_when_an_object_is_too_far_to_share_the_view():
    """Catcher-v0's package starts ~4 units above the robot, more than the view's 2 units: the
    camera follows the robot alone until both fit, then both."""
    from tsim.sampling import sample_robot

    world = task_world("Catcher-v0")
    body = build_body(sample_robot((5, 5), np.random.default_rng(0)))
    r = Renderer(world, body, 640, 320)
    pts = body.place(22, 1)
    package = world.object("package").body.place(21, 41)
    r.frame(pts, {"package": package})
    px = r.to_pixels(pts.T)
    assert px[:, 0].min() >= 0 and px[:, 0].max() <= 640 and px[:, 1].min() >= 0 and px[:, 1].max() <= 320
    robot_centre = (pts[0].min() + pts[0].max()) / 2
    assert abs(r.view[0] + 2.0 - robot_centre) <= 1 / 160  # view 4 units wide, centred on it
    # beside the robot, within the view's width: both are followed
    near = package + np.array([[2.0], [pts[1].min() - package[1].min()]])
    r.reset()
    r.frame(pts, {"package": near})
    both = np.concatenate([pts, near], axis=1)
    assert abs(r.view[0] + 2.0 - (both[0].min() + both[0].max()) / 2) <= 1 / 160


def test_non_finite_points_do_not_break_a_frame():
    """A blown-up robot (NaN points) is skipped; terrain still renders and the camera stays put."""
    body = build_body(BODY)
    r = Renderer(task_world("Walker-v0"), body, 320, 160)
    r.frame(body.place(1, 1))
    view = r.view
    img = r.frame(np.full((2, body.n_points), np.nan))
    assert r.view == view
    assert np.any(np.all(img == RIGID_COLOR, axis=-1))


@pytest.mark.parametrize("kwargs, words", [
    ({"view_voxels": 0}, "view_voxels must be a positive number"),     # was a ZeroDivisionError
    ({"view_voxels": -40}, "view_voxels must be a positive number"),   # drew a mirrored image
    ({"width": 0.5}, "whole numbers of pixels"),                        # said 0.5 was not positive
    ({"height": float("nan")}, "whole numbers of pixels"),
])
def test_a_renderer_with_a_view_it_cannot_draw_is_refused(kwargs, words):
    with pytest.raises(ValueError, match=words):
        Renderer("Walker-v0", build_body(np.array([[3, 3], [3, 3]])), **kwargs)


def test_a_frame_of_points_not_shaped_as_the_body_is_refused_naming_the_shape():
    """Too few points failed deep in the drawing, too many were left out, (n, 2) drew nonsense."""
    body = build_body(np.array([[3, 3], [3, 3]]))
    r = Renderer("Walker-v0", body, 64, 32)
    pts = body.place(3, 1)
    assert r.frame(pts).shape == (32, 64, 3)
    for bad in (pts[:, :5], pts.T, np.hstack([pts, pts])):
        with pytest.raises(ValueError, match=r"points of the robot must have shape \(2, 9\)"):
            r.frame(bad)


@pytest.mark.parametrize("frames, fps, words", [
    ([np.zeros((4, 4), np.uint8)], float("nan"), "fps must be a positive number"),
    ([np.full((4, 4, 3), 0.5)], 30, r"RGB values \(0..255\) as whole numbers, got 0.5"),
    ([np.zeros(4, np.uint8)], 30, "frames must be images of one size"),  # a 1-D frame was written
    ([np.zeros((4, 4, 3), complex)], 30, "frames must be images of one size"),
    ([np.zeros((4, 4), np.uint8), np.zeros((5, 4), np.uint8)], 30, "of one size"),
    ([np.full((4, 4), 255, np.uint8)], 30, "PALETTE indices"),
    (7, 30, "frames must be a sequence of images"),
])
def test_frames_no_animation_can_be_made_from_are_refused_before_anything_is_written(tmp_path, frames,
                                                                                      fps, words):
    with pytest.raises(ValueError, match=words):
        write_gif(frames, tmp_path / "a.gif", fps=fps)
    assert not (tmp_path / "a.gif").exists()


def test_frames_may_come_from_a_generator_and_be_whole_numbers_of_any_type(tmp_path):
    """int64 palette frames and whole-number float RGB frames were written before the checks came:
    they still are, as their uint8 values."""
    frames = (np.full((4, 6), i % 3, np.uint8) for i in range(5))
    assert write_gif(frames, tmp_path / "a.gif").stat().st_size > 0
    a = write_gif([np.full((4, 6), 1, np.int64)] * 3, tmp_path / "b.gif").read_bytes()
    assert a == write_gif([np.full((4, 6), 1, np.uint8)] * 3, tmp_path / "c.gif").read_bytes()
    rgb = np.zeros((4, 6, 3))
    rgb[:] = PALETTE[2]
    a = write_gif([rgb] * 3, tmp_path / "d.gif").read_bytes()
    assert a == write_gif([rgb.astype(np.uint8)] * 3, tmp_path / "e.gif").read_bytes()
