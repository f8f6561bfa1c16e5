"""Headless rendering of sgr worlds to RGB frames and GIFs (numpy only: no OpenGL, no display).

Colours and the actuator strain shading follow evogym's viewer (spec section 9) so our GIFs read
like evogym's: voxels are filled quads through their four current corner points, surface edges are
drawn on top as 1-px outlines. The rasterizer is vectorized over all triangles of a frame (two per
voxel, half-plane tests on each triangle's pixel bounding box); where quads overlap the one painted
later (robot over objects over terrain, later voxels over earlier) wins.
"""

from __future__ import annotations

import io
import math
import numbers
import os
from collections.abc import Iterable, Sequence
from functools import cache
from pathlib import Path

import numpy as np

from tsim import constants as C
from tsim.body import Body, build_body
from tsim.files import atomic_write
from tsim.world import World, resolve_world

BACKGROUND = (244, 245, 247)
GRID = (204, 204, 204)
RIGID_COLOR = (38, 38, 38)  # rigid (1) and fixed terrain (5)
SOFT_COLOR = (191, 191, 191)
OUTLINE = (0, 63, 92)

# ColorBrewer's 9-class "Oranges" and "Blues" (the anchors of matplotlib's maps of the same name);
# evogym's 100-entry actuator tables are these interpolated linearly at i/99 and rounded.
_ORANGE_ANCHORS = ("fff5eb", "fee6ce", "fdd0a2", "fdae6b", "fd8d3c", "f16913", "d94801", "a63603",
                   "7f2704")
_BLUE_ANCHORS = ("f7fbff", "deebf7", "c6dbef", "9ecae1", "6baed6", "4292c6", "2171b5", "08519c",
                 "08306b")


def _table(anchors: Sequence[str], n: int = 100) -> np.ndarray:
    rgb = np.array([[int(h[i:i + 2], 16) for i in (0, 2, 4)] for h in anchors], dtype=np.float64)
    x = np.linspace(0.0, 1.0, n)
    knots = np.linspace(0.0, 1.0, len(anchors))
    return np.round(np.stack([np.interp(x, knots, rgb[:, j]) for j in range(3)], axis=1)).astype(np.uint8)


ORANGES = _table(_ORANGE_ANCHORS)  # (100, 3) uint8, H actuators
BLUES = _table(_BLUE_ANCHORS)  # (100, 3) uint8, V actuators

# Every colour a frame can hold (205 < 256): frames are rasterized as indices into this palette,
# which makes RGB conversion one lookup and GIF writing free of colour quantization.
PALETTE = np.concatenate([np.array([BACKGROUND, GRID, RIGID_COLOR, SOFT_COLOR, OUTLINE], dtype=np.uint8),
                          ORANGES, BLUES])
I_BACKGROUND, I_GRID, I_RIGID, I_SOFT, I_OUTLINE, I_ORANGES, I_BLUES = 0, 1, 2, 3, 4, 5, 105

# sides of a voxel as corner slots (TL=0, TR=1, BR=2, BL=3): top, right, bottom, left
_SIDE_CORNERS = np.array([[0, 1], [1, 2], [2, 3], [3, 0]])
_MAX_CELLS = 1 << 21  # pixel tests per vectorized chunk (bounds memory for huge triangles)


def strain_index(s: np.ndarray) -> np.ndarray:
    """evogym's colour-table index for actuator strain s: stretched (s > 1) lighter, compressed darker.

    evogym reuses the previous voxel's colour when s == 1 exactly; we use index 50 instead.
    """
    s = np.nan_to_num(np.asarray(s, dtype=np.float64), nan=1.0)  # clamping before the cast = after it
    stretched = np.clip((2.0 - s) * 50.0, 0, 50).astype(np.int64)
    compressed = np.clip((1.0 - s) * 50.0, 0, 50).astype(np.int64) + 50
    return np.clip(np.where(s > 1.0, stretched, compressed), 0, 99)


def actuator_strain(body: Body, points: np.ndarray) -> np.ndarray:
    """(n_act,) mean current length of each actuator's driven edges / 0.1 (evogym's shading input)."""
    d = points[:, body.edge_b] - points[:, body.edge_a]
    length = np.hypot(d[0], d[1])
    total = np.zeros(body.n_actuators)
    count = np.zeros(body.n_actuators)
    for slot in range(body.edge_drivers.shape[1]):
        drv = body.edge_drivers[:, slot]
        on = drv >= 0
        np.add.at(total, drv[on], length[on])
        np.add.at(count, drv[on], 1.0)
    return total / np.maximum(count, 1.0) / C.MAIN_REST


def voxel_palette_index(body: Body, points: np.ndarray) -> np.ndarray:
    """(n_voxels,) uint8 `PALETTE` index of each voxel's fill with the body's points at `points` (2, n)."""
    t = body.voxel_type
    out = np.full(body.n_voxels, I_RIGID, dtype=np.uint8)
    out[t == C.SOFT] = I_SOFT
    if body.n_actuators:
        idx = strain_index(actuator_strain(body, points))
        v = body.actuator_voxels
        out[v] = np.where(t[v] == C.H_ACT, I_ORANGES + idx, I_BLUES + idx)
    return out


def voxel_colors(body: Body, points: np.ndarray) -> np.ndarray:
    """(n_voxels, 3) uint8 RGB fill colour of each voxel (see `voxel_palette_index`)."""
    return PALETTE[voxel_palette_index(body, points)]


def _fill_triangles(owner: np.ndarray, tris: np.ndarray, ids: np.ndarray) -> None:
    """Write max(id) into `owner` (H, W) for every pixel whose centre lies in a triangle (T, 3, 2)."""
    H, W = owner.shape
    finite = np.isfinite(tris).all(axis=(1, 2))
    tris, ids = tris[finite], ids[finite]
    lo = np.ceil(tris.min(axis=1) - 0.5).astype(np.int64)
    hi = np.floor(tris.max(axis=1) - 0.5).astype(np.int64)
    lo = np.maximum(lo, 0)
    hi = np.minimum(hi, [W - 1, H - 1])
    area = ((tris[:, 1, 0] - tris[:, 0, 0]) * (tris[:, 2, 1] - tris[:, 0, 1])
            - (tris[:, 1, 1] - tris[:, 0, 1]) * (tris[:, 2, 0] - tris[:, 0, 0]))
    keep = np.all(hi >= lo, axis=1) & (area != 0)
    if not keep.any():
        return
    tris, lo, hi, ids, sign = tris[keep], lo[keep], hi[keep], ids[keep], np.sign(area[keep])
    sx, sy = (hi - lo + 1).max(axis=0)
    step = max(1, _MAX_CELLS // int(sx * sy))
    flat = owner.reshape(-1)
    for k in range(0, len(tris), step):
        tri, first, last, sgn = tris[k:k + step], lo[k:k + step], hi[k:k + step], sign[k:k + step]
        xs = first[:, 0:1] + np.arange(sx)  # (t, sx) pixel columns
        ys = first[:, 1:2] + np.arange(sy)  # (t, sy) pixel rows
        px = (xs + 0.5)[:, None, :]
        py = (ys + 0.5)[:, :, None]
        inside = (xs <= last[:, 0:1])[:, None, :] & (ys <= last[:, 1:2])[:, :, None]
        for a, b in ((0, 1), (1, 2), (2, 0)):
            ax, ay = tri[:, a, 0, None, None], tri[:, a, 1, None, None]
            ex, ey = tri[:, b, 0, None, None] - ax, tri[:, b, 1, None, None] - ay
            inside &= (ex * (py - ay) - ey * (px - ax)) * sgn[:, None, None] >= 0
        pix = ys[:, :, None] * W + xs[:, None, :]
        tid = np.broadcast_to(ids[k:k + step, None, None], inside.shape)
        np.maximum.at(flat, pix[inside], tid[inside])


def _draw_segments(img: np.ndarray, seg: np.ndarray, color: int) -> None:
    """1-px lines for segments (E, 2, 2) in pixel coordinates, sampled at <= 1 px spacing."""
    seg = seg[np.isfinite(seg).all(axis=(1, 2))]
    if len(seg) == 0:
        return
    H, W = img.shape[:2]
    d = seg[:, 1] - seg[:, 0]
    n = int(min(np.ceil(np.abs(d).max()) + 1, 4 * (H + W)))
    t = np.linspace(0.0, 1.0, max(n, 2))
    p = seg[:, None, 0, :] + t[None, :, None] * d[:, None, :]  # (E, n, 2)
    x = np.floor(p[..., 0]).astype(np.int64).ravel()
    y = np.floor(p[..., 1]).astype(np.int64).ravel()
    ok = (x >= 0) & (x < W) & (y >= 0) & (y < H)
    img[y[ok], x[ok]] = color


class _Part:
    """One drawable body: its voxel quads and its surface-edge outline segments."""

    def __init__(self, body: Body):
        self.body = body
        open_v, open_s = np.nonzero(body.voxel_open)
        self.seg_voxel = open_v
        self.seg_points = body.voxel_points[open_v[:, None], _SIDE_CORNERS[open_s]]  # (E, 2)

    def quads(self, points: np.ndarray) -> np.ndarray:
        """World-space voxel quads (V, 4, 2), corners TL, TR, BR, BL."""
        return points.T[self.body.voxel_points]

    def outline(self, points: np.ndarray) -> np.ndarray:
        """(E, 2, 4): each surface segment's two endpoints (x, y) with its voxel's centre (x, y); the
        centre lets the drawing inset the line so it stays on its own voxel's pixels."""
        centres = self.quads(points).mean(axis=1)[self.seg_voxel]
        return np.concatenate([points.T[self.seg_points], np.repeat(centres[:, None, :], 2, axis=1)],
                              axis=2)


class Camera:
    """Follows the tracked points' bounding-box centre with exponential smoothing, at a fixed scale.

    The view never shows more than `floor_margin` voxels below y = 0, so the ground stays near the
    bottom edge instead of the robot sitting mid-frame above empty space.
    """

    def __init__(self, width: int, height: int, px_per_unit: float, follow: float = 0.15,
                 floor_margin: float = 2.0):
        self.width, self.height, self.scale = width, height, px_per_unit
        self.follow = follow
        self.floor_y = -floor_margin * C.CELL
        self.centre: np.ndarray | None = None

    def reset(self) -> None:
        """Forget the position: the next `update` centres on its points at once instead of easing
        toward them."""
        self.centre = None

    def update(self, tracked: np.ndarray) -> tuple[float, float]:
        """Move toward the points (2, K); return the view's top-left corner in world units, snapped
        to whole pixels so static terrain does not shimmer."""
        tracked = tracked[:, np.isfinite(tracked).all(axis=0)]
        if tracked.shape[1] == 0:  # nothing sensible to follow: stay put
            tracked = self.centre[:, None] if self.centre is not None else np.zeros((2, 1))
        target = (tracked.min(axis=1) + tracked.max(axis=1)) / 2.0
        half_h = self.height / (2.0 * self.scale)
        target[1] = max(target[1], self.floor_y + half_h)
        if self.centre is None:
            self.centre = target.copy()
        else:
            self.centre = self.centre + self.follow * (target - self.centre)
        x0 = np.round((self.centre[0] - self.width / (2.0 * self.scale)) * self.scale) / self.scale
        y1 = np.round((self.centre[1] + half_h) * self.scale) / self.scale
        return float(x0), float(y1)


class Renderer:
    """Draws one robot in a world, with the world's static terrain and free objects.

    Free objects are such as Thrower's package. The scale is fixed: `view_voxels` voxels across
    the image width (evogym shows 40 x 20 voxels). The camera follows the robot.

    Args:
        world: A `World`, a world file, or a task id such as "Walker-v0" (its world, once
            `import tasks` ran).
        body: The robot: a `Body` or a body matrix.
        width: The image's width in pixels.
        height: The image's height in pixels.
        view_voxels: How many voxels the image's width spans.
        grid: Draw the grid of cells.
        follow: The fraction of the way to its target that the camera moves at each frame
            (exponential smoothing).
        track_objects: Let the camera follow the loose free objects too (those without fixed
            voxels), the nearest ones first, as long as they fit the view with the robot.

    Raises:
        ValueError: When the image size is not whole numbers of pixels >= 1, or `view_voxels` is
            not a positive number.
    """

    def __init__(self, world: World | str | Path, body: Body | object, width: int = 640, height: int = 320, *,
                 view_voxels: float = 40.0, grid: bool = True, follow: float = 0.15,
                 track_objects: bool = True):
        if not all(isinstance(v, numbers.Real) and math.isfinite(v) and v >= 1 and v == int(v)
                   for v in (width, height)):
            raise ValueError(f"image size must be whole numbers of pixels >= 1, got {width!r}x{height!r}")
        if not (isinstance(view_voxels, numbers.Real) and math.isfinite(view_voxels) and view_voxels > 0):
            raise ValueError(f"view_voxels must be a positive number, got {view_voxels!r}")
        self.world = resolve_world(world)
        self.body = body if isinstance(body, Body) else build_body(body)
        self.width, self.height = int(width), int(height)
        self.scale = self.width / (view_voxels * C.CELL)  # pixels per world unit
        self.grid = grid
        self.draw_voxels = True  # fill voxels (evogym's hide_voxels turns this off)
        self.draw_edges = True  # outline surface edges (evogym's hide_edges turns this off)
        self.track_objects = track_objects
        self.camera = Camera(self.width, self.height, self.scale, follow)
        fixed = [(_Part(o.body), o.pos0) for o in self.world.fixed_objects]
        self._static_quads = np.concatenate([p.quads(x) for p, x in fixed] + [np.zeros((0, 4, 2))])
        self._static_colors = np.concatenate([voxel_palette_index(p.body, x) for p, x in fixed]
                                             + [np.zeros(0, np.uint8)])
        self._static_seg = np.concatenate([p.outline(x) for p, x in fixed] + [np.zeros((0, 2, 4))])
        self._objects = {o.name: (_Part(o.body), o.pos0) for o in self.world.free_objects}
        # the camera follows loose objects only: one with fixed voxels is terrain that happens to
        # be simulated (BridgeWalker-v0's soft bridge, Catcher-v0's pegs)
        self._loose = {o.name for o in self.world.free_objects
                       if not np.any(o.body.voxel_type == C.FIXED)}
        self._robot = _Part(self.body)
        self.view: tuple[float, float] | None = None  # (left x, top y) of the last frame, world units

    def reset(self) -> None:
        """Forget the camera position (next frame centres on the robot at once)."""
        self.camera.reset()
        self.view = None

    def _fits(self, points: np.ndarray) -> bool:
        """Whether points (2, K) fit in 96 % of the view: the camera follows the robot and the
        loose objects together only then, so the robot never leaves the picture."""
        pts = points[:, np.isfinite(points).all(axis=0)]
        if pts.shape[1] == 0:
            return True
        span = pts.max(axis=1) - pts.min(axis=1)
        return bool(span[0] <= 0.96 * self.width / self.scale and span[1] <= 0.96 * self.height / self.scale)

    def _followed(self, robot: np.ndarray, loose: list[np.ndarray]) -> np.ndarray:
        """The points the camera follows: the robot's, with the loose objects nearest to it (by the
        distance between their centres) as long as all of them fit the view (`_fits`). So a task's
        objects stay in the picture where they can (Traverser-v0's blocks ahead of the robot), and
        the robot always does (Catcher-v0's package high above is left out until it comes near)."""
        followed = robot
        if not loose:
            return followed
        centre = np.nanmean(robot, axis=1) if np.isfinite(robot).any() else np.zeros(2)
        with np.errstate(invalid="ignore"):
            dist = [float(np.hypot(*(np.nanmean(p, axis=1) - centre))) for p in loose]
        for i in np.argsort(np.nan_to_num(dist, nan=np.inf), kind="stable"):
            both = np.concatenate([followed, loose[i]], axis=1)
            if self._fits(both):
                followed = both
        return followed

    def to_pixels(self, xy: np.ndarray) -> np.ndarray:
        """Pixel (column, row) coordinates (..., 2) of world points (..., 2) in the last frame."""
        if self.view is None:
            raise RuntimeError("no frame rendered yet: the camera has no position")
        return self._to_px(np.asarray(xy, dtype=np.float64), *self.view)

    def _to_px(self, xy: np.ndarray, x0: float, y1: float) -> np.ndarray:
        out = np.empty_like(xy)
        out[..., 0] = (xy[..., 0] - x0) * self.scale
        out[..., 1] = (y1 - xy[..., 1]) * self.scale
        return out

    def _background(self, x0: float, y1: float) -> np.ndarray:
        img = np.full((self.height, self.width), I_BACKGROUND, dtype=np.uint8)
        if self.grid:
            step = C.CELL * self.scale
            cols = np.floor((np.ceil(x0 / C.CELL) * C.CELL - x0) * self.scale
                            + step * np.arange(int(self.width / step) + 2)).astype(np.int64)
            rows = np.floor((y1 - np.floor(y1 / C.CELL) * C.CELL) * self.scale
                            + step * np.arange(int(self.height / step) + 2)).astype(np.int64)
            img[:, cols[(cols >= 0) & (cols < self.width)]] = I_GRID
            img[rows[(rows >= 0) & (rows < self.height)], :] = I_GRID
        return img

    def frame(self, robot_points: np.ndarray, object_points: dict[str, np.ndarray] | None = None
              ) -> np.ndarray:
        """An RGB image of the robot and the free objects at the points given.

        Args:
            robot_points: (2, n) the robot's point positions, world units.
            object_points: (2, m) the points of free objects, by name; objects not given are drawn
                at their initial position.

        Returns:
            A (height, width, 3) uint8 image.

        Raises:
            ValueError: When a body's points are not of shape (2, its point count).
        """
        return to_rgb(self.frame_indexed(robot_points, object_points))

    def frame_indexed(self, robot_points: np.ndarray, object_points: dict[str, np.ndarray] | None = None
                      ) -> np.ndarray:
        """As `frame`, but a (height, width) uint8 image of `PALETTE` indices (cheaper; GIF-ready)."""
        object_points = object_points or {}
        robot_points = _points("the robot", robot_points, self._robot.body.n_points)
        objs = [(part, _points(f"object {name!r}", object_points.get(name, pos0), part.body.n_points))
                for name, (part, pos0) in self._objects.items()]
        loose = [p for name, (_, p) in zip(self._objects, objs, strict=True)
                 if name in self._loose] if self.track_objects else []
        x0, y1 = self.view = self.camera.update(self._followed(robot_points, loose))
        x_lo, x_hi = x0 - C.CELL, x0 + self.width / self.scale + C.CELL
        y_lo, y_hi = y1 - self.height / self.scale - C.CELL, y1 + C.CELL

        # static terrain culled to the view, then objects, then the robot on top
        sq = self._static_quads
        vis = ((sq[:, :, 0].max(1) >= x_lo) & (sq[:, :, 0].min(1) <= x_hi)
               & (sq[:, :, 1].max(1) >= y_lo) & (sq[:, :, 1].min(1) <= y_hi))
        quads, colors = [sq[vis]], [self._static_colors[vis]]
        ss = self._static_seg
        seg_vis = ((ss[:, :2, 0].max(1) >= x_lo) & (ss[:, :2, 0].min(1) <= x_hi)
                   & (ss[:, :2, 1].max(1) >= y_lo) & (ss[:, :2, 1].min(1) <= y_hi))
        segs = [ss[seg_vis]]
        for part, pts in [*objs, (self._robot, robot_points)]:
            quads.append(part.quads(pts))
            colors.append(voxel_palette_index(part.body, pts))
            segs.append(part.outline(pts))
        quads_px = self._to_px(np.concatenate(quads), x0, y1)
        palette = np.concatenate(colors)

        img = self._background(x0, y1)
        if self.draw_voxels:
            owner = np.full((self.height, self.width), -1, dtype=np.int64)
            tris = np.concatenate([quads_px[:, [0, 1, 2]], quads_px[:, [0, 2, 3]]])
            ids = np.tile(np.arange(len(quads_px)), 2)
            _fill_triangles(owner, tris, ids)
            hit = owner >= 0
            img[hit] = palette[owner[hit]]
        if not self.draw_edges:
            return img

        seg = np.concatenate(segs)  # (E, 2, 4): endpoint xy and its voxel centre xy
        ends = self._to_px(seg[..., :2], x0, y1)
        d = self._to_px(seg[..., 2:], x0, y1) - ends  # inset by half a pixel toward the centre
        norm = np.maximum(np.abs(d).max(axis=-1, keepdims=True), 1e-9)
        _draw_segments(img, ends + 0.5 * d / norm, I_OUTLINE)
        return img


def to_rgb(indexed: np.ndarray) -> np.ndarray:
    """RGB uint8 (..., 3) from `PALETTE` indices."""
    return np.take(PALETTE, indexed, axis=0)


@cache
def _rgb_lookup() -> np.ndarray:
    """24-bit RGB -> `PALETTE` index, 255 for colours outside the palette (16 MiB, built once)."""
    lut = np.full(1 << 24, 255, dtype=np.uint8)
    key = (PALETTE[:, 0].astype(np.int64) << 16) | (PALETTE[:, 1].astype(np.int64) << 8) | PALETTE[:, 2]
    lut[key[::-1]] = np.arange(len(PALETTE))[::-1]  # first entry wins for repeated colours
    return lut


def _as_indexed(frame: np.ndarray) -> np.ndarray | None:
    """`PALETTE` indices of an RGB frame, or None if it holds a colour outside the palette."""
    f = frame.astype(np.uint32)
    idx = _rgb_lookup()[(f[..., 0] << 16) | (f[..., 1] << 8) | f[..., 2]]
    return None if np.any(idx == 255) else idx


def _points(what: str, points: object, n: int) -> np.ndarray:
    """`points` as (2, n) float64, or ValueError: fewer points failed deep in the drawing, more
    were silently left out, and (n, 2) drew another shape."""
    p = np.asarray(points, dtype=np.float64)
    if p.shape != (2, n):
        raise ValueError(f"points of {what} must have shape (2, {n}) (x row, y row), got {p.shape}")
    return p


def _frames(frames: Iterable[np.ndarray], fps: float) -> list[np.ndarray]:
    """The frames as a list of arrays, or ValueError for what no animation can be written from: no
    frames, a rate that is not a positive number, or frames that are not `PALETTE` index images
    (H, W) or RGB images (H, W, 3), uint8, all of one size."""
    try:
        frames = [np.asarray(f) for f in frames]
    except TypeError:
        raise ValueError(f"frames must be a sequence of images, got {type(frames).__name__}") from None
    if not frames:
        raise ValueError("no frames to write")
    if not (isinstance(fps, numbers.Real) and math.isfinite(fps) and fps > 0):
        raise ValueError(f"fps must be a positive number, got {fps!r}")
    size = frames[0].shape[:2]
    for i, f in enumerate(frames):
        if (f.dtype.kind not in "uif" or not (f.ndim == 2 or f.ndim == 3 and f.shape[2] == 3)
                or f.shape[:2] != size or 0 in f.shape):
            raise ValueError(f"frame {i}: frames must be images of one size, (H, W) palette "
                             f"indices or (H, W, 3) RGB, got {f.dtype} {f.shape} "
                             f"(frame 0: {frames[0].shape})")
        top = len(PALETTE) - 1 if f.ndim == 2 else 255
        if f.dtype == np.uint8 and (f.ndim == 3 or f.max() <= top):  # every frame Renderer makes
            continue
        what = f"PALETTE indices (0..{top})" if f.ndim == 2 else "RGB values (0..255)"
        bad = ~((f >= 0) & (f <= top) & (f == np.round(f)))
        if bad.any():  # e.g. RGB in 0..1 from a plotting library: scale it first
            raise ValueError(f"frame {i}: a {f.shape} frame holds {what} as whole numbers, "
                             f"got {f[bad].flat[0].item()!r}")
        frames[i] = f.astype(np.uint8)
    return frames


@cache
def _caption_font(size: int):  # noqa: ANN202 (PIL's font type)
    from PIL import ImageFont

    return ImageFont.load_default(size=size)


def caption(frame: np.ndarray, text: str) -> np.ndarray:
    """`frame` with `text` written in its top-left corner, in the outline colour, on a band of the
    background colour (so the text reads over the grid and a passing robot).

    Args:
        frame: an RGB frame (H, W, 3) uint8, or `PALETTE` indices (H, W) as `Renderer.frame_indexed`
            draws them.
        text: one line.

    Returns:
        A new frame of the same kind and shape.
    """
    from PIL import Image, ImageDraw

    h, w = frame.shape[:2]
    size = max(9, min(h // 14, 28))
    font = _caption_font(size)
    mask = Image.new("L", (w, h), 0)
    draw = ImageDraw.Draw(mask)
    left, top, right, bottom = draw.textbbox((0, 0), text, font=font)
    pad = max(2, size // 4)
    draw.rectangle((0, 0, min(w, right + 2 * pad), min(h, bottom + 2 * pad)), fill=1)
    draw.text((pad - left, pad), text, fill=2, font=font)
    m = np.asarray(mask)
    out = frame.copy()
    if frame.ndim == 2:
        out[m == 1], out[m == 2] = I_BACKGROUND, I_OUTLINE
    else:
        out[m == 1], out[m == 2] = PALETTE[I_BACKGROUND], PALETTE[I_OUTLINE]
    return out


def write_gif(frames: Sequence[np.ndarray], path: str | Path, fps: float = 30.0) -> Path:
    """Write frames as a looping GIF; returns the path.

    Written whole or not at all (tsim/files.py). Frames whose colours all lie in `PALETTE` (every
    frame `Renderer` makes) are written losslessly with that palette through Pillow directly, which
    skips imageio's per-frame colour quantization; other RGB frames go through imageio's GIF writer.

    Args:
        frames: RGB (H, W, 3) uint8 images or `PALETTE` index images (H, W), all of one size.
        path: The GIF file to write; its folder is made if needed.
        fps: Frames per second.

    Returns:
        `path`, as a `Path`.

    Raises:
        ValueError: When there are no frames, frames are not images of one size, or `fps` is not
            a positive number.
    """
    frames = _frames(frames, fps)
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    indexed = [f if f.ndim == 2 else _as_indexed(f) for f in frames]
    duration = 1000.0 / fps
    buf = io.BytesIO()  # made in memory, then written whole or not at all (a full disk cuts no GIF)
    if any(f is None for f in indexed):
        import imageio.v3 as iio

        rgb = [to_rgb(f) if f.ndim == 2 else f for f in frames]
        iio.imwrite(buf, np.stack(rgb), extension=".gif",
                    duration=duration, loop=0)
        atomic_write(path, buf.getvalue())
        return path
    from PIL import Image

    palette = np.zeros((256, 3), dtype=np.uint8)
    palette[:len(PALETTE)] = PALETTE
    images = []
    for f in indexed:
        h, w = f.shape
        im = Image.frombytes("P", (w, h), np.ascontiguousarray(f, dtype=np.uint8).tobytes())
        im.putpalette(palette.tobytes())
        images.append(im)
    images[0].save(buf, format="GIF", save_all=True, append_images=images[1:], duration=duration,
                   loop=0, optimize=False)
    atomic_write(path, buf.getvalue())
    return path


VIDEO_EXTRA = "pip install 'sgr[video]' (or: pip install imageio-ffmpeg)"


def video_available() -> bool:
    """Whether MP4s can be written: imageio's ffmpeg plugin (imageio-ffmpeg, the `video` extra,
    which ships an ffmpeg binary) is installed."""
    try:
        import imageio_ffmpeg

        imageio_ffmpeg.get_ffmpeg_exe()
    except (ImportError, RuntimeError):
        return False
    return True


def write_mp4(frames: Sequence[np.ndarray], path: str | Path, fps: float = 30.0) -> Path:
    """Write frames as an H.264 MP4 (one video frame per frame; about a fifth of the GIF's size);
    returns the path. Written whole or not at all, the frames streamed to ffmpeg one by one. Frames
    as for `write_gif`; an odd width or height is padded with the background by one pixel (H.264's
    4:2:0 needs even sides). Raises SgrError without imageio's ffmpeg plugin (`video_available`)."""
    if not video_available():
        from tsim.errors import SgrError
        raise SgrError(f"writing {Path(path).name} needs imageio's ffmpeg plugin: {VIDEO_EXTRA}")
    frames = _frames(frames, fps)
    import tempfile

    import imageio_ffmpeg

    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    h, w = np.asarray(frames[0]).shape[:2]
    canvas = np.empty((h + h % 2, w + w % 2, 3), dtype=np.uint8)
    canvas[:] = BACKGROUND
    fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=f".{path.name}.", suffix=".mp4")
    os.close(fd)
    try:
        writer = imageio_ffmpeg.write_frames(tmp, canvas.shape[1::-1], fps=fps, macro_block_size=1,
                                             ffmpeg_log_level="error", output_params=["-preset", "veryfast"])
        writer.send(None)  # starts ffmpeg
        try:
            for f in frames:
                f = np.asarray(f)
                canvas[:h, :w] = to_rgb(f) if f.ndim == 2 else f
                writer.send(canvas.tobytes())
        finally:
            writer.close()
        atomic_write(path, Path(tmp).read_bytes())
    finally:
        Path(tmp).unlink(missing_ok=True)
    return path


def write_animation(frames: Sequence[np.ndarray], path: str | Path, fps: float = 30.0,
                    mp4_beside: bool = False) -> Path:
    """`write_mp4` for a path ending in .mp4, else `write_gif`; returns the path. With `mp4_beside`
    a GIF gets the same frames as an MP4 beside it (same name, .mp4) where imageio's ffmpeg plugin
    is installed; where it is not, an MP4 left there before is removed (it would show another
    episode than the GIF)."""
    path = Path(path)
    if path.suffix.lower() == ".mp4":
        return write_mp4(frames, path, fps=fps)
    frames = _frames(frames, fps)  # a generator is read once, for both files
    write_gif(frames, path, fps=fps)
    if mp4_beside:
        if video_available():
            write_mp4(frames, path.with_suffix(".mp4"), fps=fps)
        else:
            path.with_suffix(".mp4").unlink(missing_ok=True)
    return path
