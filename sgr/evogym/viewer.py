"""evogym 2.0's `EvoViewer` on sgr: images of an `EvoSim` drawn by tsim's numpy `Renderer` (no
OpenGL), and a Taichi GUI window for 'screen' / 'human' where a display exists.

The camera is evogym's: `pos` is the view's centre and `view_size` its extent, both in voxels; with
tracked objects it follows their bounding box with evogym's PID, one update per simulation step
(tests/data/evogym_api/camera.npz: the same positions and sizes as evogym's viewer). Drawing
follows tsim's renderer, so colours and the actuator shading are evogym's but pixels are not
identical to evogym's OpenGL output.
"""

from __future__ import annotations

import os
import time

import numpy as np

from sgr.evogym.sim import EvoSim
from sgr.evogym.utils import Timer
from tsim import constants as C
from tsim.render import I_BACKGROUND, I_GRID, PALETTE, Renderer

__all__ = ["EvoViewer"]

MODES = ("screen", "human", "img", "rgb_array")
_WHITE = np.array([255, 255, 255], dtype=np.uint8)


def _pair(value, name: str, kind: type) -> tuple:
    if not isinstance(value, tuple) or len(value) != 2:
        raise TypeError(f"{name} must be a tuple of two values, got {value!r}")
    try:
        return (kind(value[0]), kind(value[1]))
    except (TypeError, ValueError):
        raise TypeError(f"{name} must hold two numbers, got {value!r}") from None


class _FixedCamera:
    """Stands in for tsim's following camera: the viewer decides where the view is."""

    def __init__(self, viewer: EvoViewer):
        self.viewer = viewer

    def reset(self) -> None:
        """Nothing to forget: the viewer holds the position."""

    def update(self, tracked: np.ndarray) -> tuple[float, float]:
        """Top-left corner of the view in world units, from the viewer's centre and size."""
        (cx, cy), (w, h) = self.viewer.pos, self.viewer.view_size
        return (cx - w / 2) * C.CELL, (cy + h / 2) * C.CELL


class EvoViewer:
    """Images and windows of an `EvoSim` (evogym's EvoViewer)."""

    def __init__(self, sim_to_view: EvoSim, target_rps: int | None = 50,
                 pos: tuple[float, float] = (12, 4), view_size: tuple[float, float] = (40, 20),
                 resolution: tuple[int, int] = (1200, 600)) -> None:
        if not hasattr(sim_to_view, "_render_scene"):  # an EvoSim (or a bare-id env's scene)
            raise TypeError(f"EvoViewer needs an EvoSim, got {type(sim_to_view).__name__}")
        self._sim = sim_to_view
        self._tracking_objects: list[str] = []
        self._tracking_padding = (5, 3)
        self._tracking_multiplier = (0.2, 0.2)
        self._tracking_lock = {"x": False, "y": False, "width": False, "height": False}
        self._old_targets = None  # evogym's camera state (see _update_tracking)
        self._history = self._history2 = None
        self._sum = [0.0, 0.0, 0.0, 0.0]
        self._last_rendered = -1
        self._renderer: Renderer | None = None
        self._gui = None
        self.set_target_rps(target_rps)
        self.set_pos(pos)
        self.set_view_size(view_size)
        self.set_resolution(resolution)

    # ------------------------------------------------------------------ settings
    def set_pos(self, pos: tuple[float, float]) -> None:
        """Centre of the view, in voxels."""
        self.pos = _pair(pos, "pos", float)

    def set_view_size(self, view_size: tuple[float, float]) -> None:
        """Extent of the view (width, height), in voxels."""
        self.view_size = _pair(view_size, "view_size", float)
        if min(self.view_size) <= 0:
            raise ValueError(f"view_size must be positive, got {view_size}")

    def set_resolution(self, resolution: tuple[int, int]) -> None:
        """Image size (width, height) in pixels."""
        self.resolution = _pair(resolution, "resolution", int)
        if min(self.resolution) < 1:
            raise ValueError(f"resolution must be positive, got {resolution}")
        self._renderer = None

    def set_target_rps(self, target_rps: int | None) -> None:
        """Renders per second that `render` paces itself to (None: as fast as possible)."""
        self._target_rps = int(target_rps) if target_rps is not None else None
        self._timer = Timer(self._target_rps)

    def track_objects(self, *objects: str) -> None:
        """Keep these objects in view (names of the simulation's objects)."""
        for name in objects:
            self._sim._check_object(name)
        self._tracking_objects = list(objects)

    def set_tracking_settings(self, **settings) -> None:
        """Set how the view follows the tracked objects, one keyword per setting.

        The settings are `padding`, (x, y) voxels; `scale`, (x, y) multiplier of the tracked span;
        and `lock_x`, `lock_y`, `lock_width`, `lock_height`, where a number fixes that value of the
        view and False frees it.

        Raises:
            ValueError: An unknown setting.
            TypeError: `padding` or `scale` is not a tuple of two numbers.
        """
        for key, value in settings.items():
            if key in ("padding", "scale"):
                v = _pair(value, key, float)
                if key == "padding":
                    self._tracking_padding = v
                else:
                    self._tracking_multiplier = v
            elif key in ("lock_x", "lock_y", "lock_width", "lock_height"):
                self._tracking_lock[key[5:]] = value
            else:
                raise ValueError(f"unknown tracking setting {key!r}; known: padding, scale, lock_x, "
                                 "lock_y, lock_width, lock_height")

    def show_debug_window(self) -> None:
        """Open the window (as render('screen') does)."""
        self._window()

    def hide_debug_window(self) -> None:
        """Close the window if open."""
        self.close()

    def close(self) -> None:
        """Close the window if open."""
        if self._gui is not None:
            self._gui.close()
            self._gui = None

    # ------------------------------------------------------------------ drawing
    def _update_tracking(self) -> None:
        """One step of evogym's camera: the tracked objects' bounding box, padded by `padding`
        voxels and widened by `scale` of its span, is the target (centre and size, each held while
        it moves by less than 1 voxel or 30 %); the view follows it with evogym's PID (kp 0.04,
        ki 0.005 on a sum decaying by 0.9, kd 0.08), then widens to the image's aspect."""
        if not self._tracking_objects:
            return
        t = self._sim.get_time()
        pts = np.concatenate([self._sim.object_pos_at_time(t, n) for n in self._tracking_objects], axis=1)
        px, py = self._tracking_padding
        mx, my = self._tracking_multiplier
        x0, y0 = float(np.min(pts[0])) - px, float(np.min(pts[1])) - py
        x1, y1 = float(np.max(pts[0])) + px, float(np.max(pts[1])) + py
        x0 -= mx * (x1 - x0) / 2  # evogym widens the low side first, then the high side from it
        y0 -= my * (y1 - y0) / 2
        x1 += mx * (x1 - x0) / 2
        y1 += my * (y1 - y0) / 2
        target = [(x0 + x1) / 2.0, (y0 + y1) / 2.0, x1 - x0, y1 - y0]
        if self._old_targets is None:
            self.pos, self.view_size = (target[0], target[1]), (target[2], target[3])
            self._old_targets = tuple(target)
        old = self._old_targets
        for i in (0, 1):  # hold the centre while it moves less than a voxel
            if abs(old[i] - target[i]) < 1.0:
                target[i] = old[i]
        for i in (2, 3):  # and the size while it changes by less than 30 %
            if abs(1 - old[i] / target[i]) < 0.3:
                target[i] = old[i]
        self._old_targets = tuple(target)
        if self._history is None:
            self._history = tuple(target)
        if self._history2 is None:
            self._history2 = tuple(target)
        now = (self.pos[0], self.pos[1], self.view_size[0], self.view_size[1])
        out = []
        for i in range(4):
            self._sum[i] += target[i] - self._history[i]
        for i in range(4):
            self._sum[i] *= 0.9
        for i in range(4):
            rate = self._history[i] - self._history2[i]
            out.append(now[i] + 0.04 * (target[i] - self._history[i]) + 0.08 * rate + 0.005 * self._sum[i])
        for i, key in enumerate(("x", "y", "width", "height")):
            if not isinstance(self._tracking_lock[key], bool):
                out[i] = self._tracking_lock[key]
        self._history2 = self._history
        self._history = tuple(out)
        w, h = out[2], out[3]
        aspect = self.resolution[0] / self.resolution[1]
        if w / h < aspect:
            w *= (h / w) * aspect
        elif w / h > aspect:
            h /= (h / w) * aspect
        self.pos, self.view_size = (out[0], out[1]), (w, h)

    def _follow(self) -> None:
        """Advance the camera one tracking step per simulation step since the last render (50
        after the simulation went back in time), as evogym's render does."""
        now = self._sim.get_time()
        if now < self._last_rendered:
            self._last_rendered = now - 50
        while self._last_rendered < now:
            self._update_tracking()
            self._last_rendered += 1

    def _image(self, hide_background: bool, hide_grid: bool, hide_edges: bool,
               hide_voxels: bool) -> np.ndarray:
        world, body, lead, objects = self._sim._render_scene()
        w_px, h_px = self.resolution
        r = self._renderer
        if r is None:
            r = self._renderer = Renderer(world, body, w_px, h_px, view_voxels=40.0)
            r.camera = _FixedCamera(self)
        r.scale = w_px / (self.view_size[0] * C.CELL)
        r.grid = not hide_grid
        r.draw_edges = not hide_edges
        r.draw_voxels = not hide_voxels
        idx = r.frame_indexed(lead, objects)
        pal = PALETTE.copy()
        if hide_background:
            pal[I_BACKGROUND] = _WHITE
            pal[I_GRID] = _WHITE if hide_grid else pal[I_GRID]
        return np.take(pal, idx, axis=0)

    def render(self, mode: str = "screen", verbose: bool = False, hide_background: bool = False,
               hide_grid: bool = False, hide_edges: bool = False,
               hide_voxels: bool = False) -> np.ndarray | None:
        """Draw the view, as an image array or in a window; paced to the target rps.

        Args:
            mode: 'img' / 'rgb_array' returns the view as an image; 'screen' / 'human' draws it in a
                window.
            verbose: Print the rate of renders and its mean, each second.
            hide_background: Draw the background white.
            hide_grid: Draw no grid lines.
            hide_edges: Draw no voxel edges.
            hide_voxels: Draw no voxels.

        Returns:
            The view as an (H, W, 3) uint8 array for 'img' / 'rgb_array'; None for 'screen' / 'human'.

        Raises:
            ValueError: An unknown mode.
            RuntimeError: 'screen' / 'human' where no display exists.
        """
        if mode not in MODES:
            raise ValueError(f"mode {mode!r} is not one of {', '.join(MODES)}")
        self._follow()
        img = self._image(hide_background, hide_grid, hide_edges, hide_voxels)
        out = None
        if mode in ("img", "rgb_array"):
            out = img
        else:
            gui = self._window()
            gui.set_image(np.ascontiguousarray(img.transpose(1, 0, 2)[:, ::-1]))
            gui.show()
        self._timer.step(verbose=verbose)
        while not self._timer.should_step():
            time.sleep(0.001)
        return out

    def _window(self):
        if self._gui is None:
            if not (os.environ.get("DISPLAY") or os.environ.get("WAYLAND_DISPLAY")):
                raise RuntimeError("render('screen') needs a display (DISPLAY is not set); "
                                   "use render('img') for an image array")
            from tsim.backend import runtime
            self._gui = runtime.ti.GUI("sgr.evogym", res=self.resolution)
        return self._gui
