"""EvoViewer: images of the view (H, W, 3) uint8, evogym's camera (recorded), bad input, and the window
of render('screen') under Xvfb: a screenshot of the X display shows the frame render('img') gives
(skipped where Xvfb and xwd, Debian's xvfb and x11-apps, are not installed)."""

import shutil
import subprocess
from pathlib import Path

import numpy as np
import pytest

from sgr.evogym import EvoSim, EvoViewer, EvoWorld

DATA = Path(__file__).resolve().parents[2] / "data" / "evogym_api"


def _sim() -> EvoSim:
    w = EvoWorld.from_json(str(DATA / "simple_environment.json"))
    w.add_from_array("robot", np.array([[3, 3, 3], [3, 0, 3]]), 3, 1)
    return EvoSim(w)


def test_img_is_the_view_at_the_resolution_and_moves_with_the_camera():
    sim = _sim()
    v = EvoViewer(sim, target_rps=None, resolution=(320, 160))
    a = v.render("img")
    assert a.shape == (160, 320, 3) and a.dtype == np.uint8
    v.set_pos((30, 4))
    b = v.render("rgb_array")
    assert not np.array_equal(a, b)
    v.set_pos((12, 4))
    np.testing.assert_array_equal(v.render("img"), a)  # the same view draws the same picture
    white = v.render("img", hide_background=True, hide_grid=True)
    assert (white == 255).all(axis=2).mean() > (a == 255).all(axis=2).mean() + 0.3
    outline = np.array([0, 63, 92])  # evogym's edge colour
    edges = (a == outline).all(axis=2).sum()
    assert edges > 100
    assert (v.render("img", hide_edges=True) == outline).all(axis=2).sum() == 0
    only_edges = v.render("img", hide_voxels=True)
    assert (only_edges == outline).all(axis=2).sum() > 0.8 * edges
    rigid = np.array([38, 38, 38])  # evogym's rigid / fixed fill, drawn only with voxels
    assert (a == rigid).all(axis=2).sum() > 500 and (only_edges == rigid).all(axis=2).sum() == 0


def test_tracking_brings_the_robot_into_view_and_locks_hold():
    sim = _sim()
    v = EvoViewer(sim, target_rps=None, pos=(-30, 20))
    v.track_objects("robot")
    for _ in range(60):
        sim.step()
        v.render("img")
    com = sim.object_pos_at_time(sim.get_time(), "robot").mean(axis=1)
    assert abs(v.pos[0] - com[0]) < v.view_size[0] / 4 and abs(v.pos[1] - com[1]) < v.view_size[1] / 4
    v.set_tracking_settings(lock_y=2.0, padding=(1, 1))
    sim.step()
    v.render("img")
    assert v.pos[1] == 2.0


def test_bad_viewer_input_is_one_clear_error(monkeypatch):
    v = EvoViewer(_sim(), target_rps=None)
    with pytest.raises(ValueError, match="mode 'movie' is not one of"):
        v.render("movie")
    with pytest.raises(ValueError, match="nope is not a valid object name"):
        v.track_objects("nope")
    with pytest.raises(ValueError, match="unknown tracking setting 'zoom'"):
        v.set_tracking_settings(zoom=2)
    with pytest.raises(TypeError, match="resolution must be a tuple"):
        v.set_resolution([3, 4])
    monkeypatch.delenv("DISPLAY", raising=False)
    monkeypatch.delenv("WAYLAND_DISPLAY", raising=False)
    with pytest.raises(RuntimeError, match="needs a display"):
        v.render("screen")


def _read_xwd(path: Path) -> np.ndarray:
    """(H, W, 3) RGB of a 24/32-bit TrueColor XWD screenshot (X's own dump format)."""
    raw = path.read_bytes()
    h = np.frombuffer(raw[:100], dtype=">u4")
    header, width, height, bpp, bpl, ncolors = h[0], h[4], h[5], h[11], h[12], h[19]
    assert bpp == 32, f"expected a 32-bit dump, got {bpp}"
    start = int(header) + 12 * int(ncolors)
    px = np.frombuffer(raw[start:start + int(height) * int(bpl)], dtype=np.uint8)
    px = px.reshape(int(height), int(bpl))[:, :4 * int(width)].reshape(int(height), int(width), 4)
    little = h[7] == 0  # LSBFirst: B, G, R, X in memory
    return px[..., [2, 1, 0]] if little else px[..., [1, 2, 3]]


@pytest.mark.slow
@pytest.mark.subprocess
@pytest.mark.skipif(not shutil.which("xwd"), reason="needs xwd (Debian package x11-apps)")
def test_screen_mode_opens_a_window_showing_the_frame_under_xvfb(tmp_path, xvfb_display):
    sim = _sim()
    v = EvoViewer(sim, target_rps=None, resolution=(400, 200))
    sim.step()
    for _ in range(3):
        v.render("screen")
    frame = v.render("img")
    shot = tmp_path / "shot.xwd"
    subprocess.run(["xwd", "-root", "-display", xvfb_display, "-out", str(shot)], check=True, timeout=30)
    v.close()
    screen = _read_xwd(shot)
    lit = np.nonzero(screen.any(axis=2))
    y0, x0 = lit[0].min(), lit[1].min()
    window = screen[y0:y0 + 200, x0:x0 + 400]
    assert window.shape == frame.shape
    match = (window == frame).all(axis=2).mean()
    print(f"window pixels equal to the frame: {match:.4f}")
    assert match > 0.99


def test_camera_follows_as_evogyms():
    """evogym's camera (tests/data/evogym_api/camera.npz, recorded from evogym's viewer): the
    robot and box of the tutorial world tracked with padding (4, 2) and scale (0.3, 0.1), the
    view's centre and size after each step's render within 1e-9 of evogym's."""
    import importlib.util
    root = DATA.parents[2]
    spec = importlib.util.spec_from_file_location("ref", root / "references" / "evogym_api_reference.py")
    ref = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(ref)
    d = np.load(DATA / "camera.npz", allow_pickle=False)
    w = EvoWorld.from_json(str(DATA / "simple_environment.json"))
    w.add_from_array("robot", d["body"], 3, 1, connections=d["connections"])
    sim = EvoSim(w)
    v = EvoViewer(sim, target_rps=None, resolution=(120, 60))  # evogym's aspect, fewer pixels
    v.track_objects("robot", "box")
    v.set_tracking_settings(padding=(4, 2), scale=(0.3, 0.1))
    got = []
    for t in range(len(d["track"])):
        sim.set_action("robot", ref.actions(t, sim.get_dim_action_space("robot")))
        sim.step()
        v.render("img")
        got.append([*v.pos, *v.view_size])
    assert np.abs(np.array(got) - d["track"]).max() < 1e-9
    assert np.ptp(d["track"][:, 0]) > 3  # the camera moves: the comparison has content
