"""Voxel bodies: validation, connectivity and the point/spring topology evogym builds from them.

A `Body` is a pure function of its material matrix and connections, so it is built with plain
numpy/Python once per distinct matrix (cached) and can be tested without Taichi; `_build` is also
the oracle of `tsim.bodybatch.build_bodies`, which builds a whole batch at once. Point, edge and
voxel order follow evogym's `ObjectCreator` (spec section 1.2-1.4): the simulator, observations and
actuator order all depend on that order.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import lru_cache

import numpy as np

from tsim import constants as C
from tsim.errors import SgrError

# side indices used for voxel edges: evogym's `Boxel::edges` order
TOP, RIGHT, BOTTOM, LEFT = 0, 1, 2, 3
# corner indices used for voxel points: evogym's `Boxel::points` order (TL, TR, BR, BL)
TL, TR, BR, BL = 0, 1, 2, 3


def as_body_matrix(matrix: object, *, allow_fixed: bool = False) -> np.ndarray:
    """Return `matrix` as a 2-D int array of material codes, or raise SgrError naming the problem."""
    try:
        arr = np.asarray(matrix, dtype=float)
    except (TypeError, ValueError) as exc:
        raise SgrError(f"bad body matrix: not a numeric array ({exc})") from None
    if arr.ndim != 2:
        raise SgrError(f"bad body matrix: must be 2-D, got {arr.ndim}-D with shape {arr.shape}")
    if arr.size == 0:
        raise SgrError(f"bad body matrix: empty (shape {arr.shape})")
    if not np.all(np.isfinite(arr)) or not np.all(arr == np.round(arr)):
        raise SgrError("bad body matrix: entries must be integers")
    top = C.FIXED if allow_fixed else C.V_ACT
    if arr.min() < 0 or arr.max() > top:
        bad = sorted({int(v) for v in arr.ravel() if v < 0 or v > top})
        raise SgrError(f"bad body matrix: material codes must be 0-{top}, got {bad}")
    return arr.astype(np.int64)


def is_connected(matrix: np.ndarray) -> bool:
    """evogym's `is_connected`: 4-neighbour flood fill; an all-empty matrix is not connected."""
    m = np.asarray(matrix)
    if m.ndim != 2:
        raise ValueError(f"is_connected needs a 2-D matrix, got shape {m.shape}")
    filled = list(zip(*np.nonzero(m), strict=False))
    if not filled:
        return False
    seen = {filled[0]}
    stack = [filled[0]]
    h, w = m.shape
    while stack:
        r, c = stack.pop()
        for rr, cc in ((r - 1, c), (r + 1, c), (r, c - 1), (r, c + 1)):
            if 0 <= rr < h and 0 <= cc < w and m[rr, cc] != 0 and (rr, cc) not in seen:
                seen.add((rr, cc))
                stack.append((rr, cc))
    return len(seen) == len(filled)


def is_connected_batch(matrices: np.ndarray) -> np.ndarray:
    """(N,) bool: `is_connected` of each of the (N, H, W) matrices, by flood fills run together:
    on one 64-bit mask per matrix when H * W <= 64, else on boolean arrays."""
    m = np.asarray(matrices)
    if m.ndim != 3:
        raise ValueError(f"is_connected_batch needs an (N, H, W) array, got shape {m.shape}")
    n, h, w = m.shape
    filled = m != 0
    if n == 0 or h * w == 0:
        return np.zeros(n, dtype=bool)
    if h * w <= 64:
        return _connected_bits(filled.reshape(n, h * w), h, w)
    return _connected_bool(filled)


def _connected_bits(filled: np.ndarray, h: int, w: int) -> np.ndarray:
    """Flood fills on bit masks (bit r * w + c is cell (r, c)): grow from each mask's lowest set bit
    by the four shifts until nothing changes."""
    n, hw = filled.shape
    bits = np.zeros((n, 64), dtype=bool)
    bits[:, :hw] = filled
    full = np.packbits(bits, axis=1, bitorder="little").view("<u8").reshape(n).astype(np.uint64)
    col = np.arange(64) % w
    inside = np.arange(64) < hw
    no_first = np.packbits(((col != 0) & inside), bitorder="little").view("<u8")[0].astype(np.uint64)
    no_last = np.packbits(((col != w - 1) & inside), bitorder="little").view("<u8")[0].astype(np.uint64)
    one, sw = np.uint64(1), np.uint64(w)
    out = np.zeros(n, dtype=bool)
    live = np.flatnonzero(full)
    f = full[live]
    x = f & (~f + one)  # the lowest set bit
    while len(live):
        for _ in range(4):
            x = (x | ((x << one) & no_first) | ((x >> one) & no_last) | (x << sw) | (x >> sw)) & f
        nx = (x | ((x << one) & no_first) | ((x >> one) & no_last) | (x << sw) | (x >> sw)) & f
        done = nx == x
        if done.any():
            out[live[done]] = x[done] == f[done]
            keep = ~done
            live, f, x = live[keep], f[keep], nx[keep]
        else:
            x = nx
    return out


def _connected_bool(filled: np.ndarray) -> np.ndarray:
    """Flood fills on (N, H, W) boolean arrays, for matrices of more than 64 cells."""
    n, h, w = filled.shape
    flat = filled.reshape(n, -1)
    out = np.zeros(n, dtype=bool)
    live = np.flatnonzero(flat.any(axis=1))
    f = filled[live]
    x = np.zeros_like(f)
    first = flat[live].argmax(axis=1)
    x.reshape(len(live), -1)[np.arange(len(live)), first] = True
    while len(live):
        nx = x.copy()
        nx[:, 1:] |= x[:, :-1]
        nx[:, :-1] |= x[:, 1:]
        nx[:, :, 1:] |= x[:, :, :-1]
        nx[:, :, :-1] |= x[:, :, 1:]
        nx &= f
        done = (nx == x).all(axis=(1, 2))
        if done.any():
            out[live[done]] = (x[done] == f[done]).all(axis=(1, 2))
            keep = ~done
            live, f, x = live[keep], f[keep], nx[keep]
        else:
            x = nx
    return out


def has_actuator(matrix: np.ndarray) -> bool:
    """Whether any cell of a body matrix is an actuator (3 = H_ACT, 4 = V_ACT).

    A robot without one cannot be driven, so `check_robot` rejects it.

    Args:
        matrix: A body matrix of material codes.

    Returns:
        True when some cell is 3 or 4.
    """
    m = np.asarray(matrix)
    return bool(np.any((m == C.H_ACT) | (m == C.V_ACT)))


def full_connectivity(matrix: np.ndarray) -> np.ndarray:
    """Every pair of 4-adjacent non-empty cells, as evogym's `get_full_connectivity` (2 x k)."""
    m = np.asarray(matrix)
    h, w = m.shape
    pairs = []
    for r in range(h):
        for c in range(w):
            if m[r, c] == 0:
                continue
            if c + 1 < w and m[r, c + 1] != 0:
                pairs.append((r * w + c, r * w + c + 1))
            if r + 1 < h and m[r + 1, c] != 0:
                pairs.append((r * w + c, (r + 1) * w + c))
    return np.array(pairs, dtype=np.int64).T.reshape(2, -1)


def check_robot(matrix: object) -> np.ndarray:
    """Validate a robot body: 2-D, codes 0-4, non-empty, 4-connected, with an actuator."""
    m = as_body_matrix(matrix)
    if not np.any(m):
        raise SgrError("bad body matrix: all voxels are empty")
    if not is_connected(m):
        raise SgrError("bad body matrix: voxels are not 4-connected (disconnected body)")
    if not has_actuator(m):
        raise SgrError("bad body matrix: no actuator voxel (3 or 4); a robot needs one")
    return m


@dataclass(frozen=True)
class Body:
    """Topology of one object (robot, box or terrain) in evogym's order.

    Corner lattice coordinates are integers: `corner_cx` counts columns from the matrix's left
    edge, `corner_ry` counts rows from its top edge; `place` turns them into evogym's exact doubles.
    """

    matrix: np.ndarray  # (H, W) material codes
    n_points: int
    corner_cx: np.ndarray  # (n_points,) int
    corner_ry: np.ndarray  # (n_points,) int
    edge_a: np.ndarray  # (n_edges,) int, oriented as evogym after the surface swap
    edge_b: np.ndarray
    edge_rest: np.ndarray  # init_length_eq
    edge_k: np.ndarray
    edge_is_diag: np.ndarray  # bool
    voxel_rc: np.ndarray  # (n_voxels, 2) row, col; voxels in row-major order
    voxel_type: np.ndarray  # (n_voxels,)
    voxel_points: np.ndarray  # (n_voxels, 4) TL, TR, BR, BL
    voxel_edges: np.ndarray  # (n_voxels, 4) top, right, bottom, left
    voxel_open: np.ndarray  # (n_voxels, 4) bool: side has no connection (surface edge)
    actuator_voxels: np.ndarray  # (n_act,) voxel indices (into voxel arrays), evogym action order
    actuator_flat: np.ndarray  # (n_act,) flat index row * W + col (evogym's actuator indices)
    edge_drivers: np.ndarray  # (n_edges, 2) actuator indices driving each edge, -1 for none

    @property
    def n_edges(self) -> int:
        """Spring count: each voxel's main edges (shared sides counted once) plus its two diagonals."""
        return len(self.edge_a)

    @property
    def n_voxels(self) -> int:
        """Non-empty cells: the length of the voxel_* arrays (row-major order)."""
        return len(self.voxel_type)

    @property
    def n_actuators(self) -> int:
        """Length of this body's action vector (its H_ACT and V_ACT voxels)."""
        return len(self.actuator_voxels)

    @property
    def voxel_is_surface(self) -> np.ndarray:
        """(n_voxels,) bool: the voxels with at least one unconnected side.

        They are the only ones collision checks visit.
        """
        return self.voxel_open.any(axis=1)

    @property
    def edge_is_surface(self) -> np.ndarray:
        """(n_edges,) bool: edges on an unconnected voxel side (the outline); diagonals never are."""
        surf = np.zeros(self.n_edges, dtype=bool)
        surf[self.voxel_edges[self.voxel_open]] = True
        return surf

    def place(self, x: int, y: int) -> np.ndarray:
        """Initial point positions (2, n) with the bottom-left matrix cell at grid cell (x, y).

        Evaluated exactly as evogym does (`x*0.1 + cx*0.1`, `(y*0.1 + H*0.1) - ry*0.1`): the
        ~1e-17 rounding of these values decides contact ties at reset.
        """
        h = self.matrix.shape[0]
        start_x = x * C.CELL
        max_y = y * C.CELL + h * C.CELL
        px = start_x + self.corner_cx * C.CELL
        py = max_y - self.corner_ry * C.CELL
        return np.stack([px, py]).astype(np.float64)


def _connection_sets(matrix: np.ndarray, connections: np.ndarray) -> tuple[set, set]:
    """Horizontal and vertical glued pairs (flat indices, smaller first), as the C++ loader reads them."""
    h, w = matrix.shape
    horiz, vert = set(), set()
    for i, j in connections.T:
        a, b = (int(i), int(j)) if i < j else (int(j), int(i))
        if b - a == 1 and w > 1:
            horiz.add((a, b))
        elif b - a == w:
            vert.add((a, b))
    return horiz, vert


def as_connections(connections: object) -> np.ndarray:
    """`connections` as evogym's (2, k) int64 array of flat cell-index pairs, or ValueError: a (k, 2)
    array of pairs (a common mix-up) would otherwise be re-paired into another body."""
    c = np.asarray(connections)
    if c.size == 0:
        return np.zeros((2, 0), dtype=np.int64)
    if c.ndim != 2 or c.shape[0] != 2:
        raise ValueError(f"connections must be a (2, k) array of flat cell-index pairs (evogym's "
                         f"layout: row 0 the first cells, row 1 the second), got shape {c.shape}")
    if c.dtype.kind in "iu":
        return c.astype(np.int64)
    try:
        f = c.astype(np.float64)  # whole floats, and Python ints in an object array
    except (TypeError, ValueError):
        f = np.full(c.shape, np.nan)
    whole = np.isfinite(f) & (f == np.round(f))
    if not whole.all():
        raise ValueError(f"connections must hold whole cell indices, got {c.dtype} values such as "
                         f"{c[~whole].tolist()[0]!r}")
    return f.astype(np.int64)


def build_body(matrix: object, connections: np.ndarray | None = None, *,
               allow_fixed: bool = False) -> Body:
    """Build (and cache) the topology of a body matrix with evogym's default full connectivity."""
    m = as_body_matrix(matrix, allow_fixed=allow_fixed)
    if connections is None:
        return _build_full(m.tobytes(), m.shape, allow_fixed)
    return _build(m, as_connections(connections))


# ~4.5 KB per 5x5 body: 1,024 bodies (8 generations of 128 distinct ones) hold ~5 MB; 4,096 let a
# long run's memory grow by ~18 MB before the cache was full. A miss costs ~0.4 ms.
@lru_cache(maxsize=1024)
def _build_full(data: bytes, shape: tuple, allow_fixed: bool) -> Body:
    m = np.frombuffer(data, dtype=np.int64).reshape(shape).copy()
    return _build(m, full_connectivity(m))


def _build(m: np.ndarray, connections: np.ndarray) -> Body:  # noqa: C901 - mirrors ObjectCreator
    h, w = m.shape
    horiz, vert = _connection_sets(m, connections)

    def filled(r: int, c: int) -> bool:
        return 0 <= r < h and 0 <= c < w and m[r, c] != 0

    def glued(r1: int, c1: int, r2: int, c2: int) -> bool:
        if not (filled(r1, c1) and filled(r2, c2)):
            return False
        a, b = r1 * w + c1, r2 * w + c2
        a, b = min(a, b), max(a, b)
        return (a, b) in horiz if r1 == r2 else (a, b) in vert

    # orthogonal neighbour flags: top, bottom, left, right
    def nb(r: int, c: int) -> dict:
        return {"t": glued(r, c, r - 1, c), "b": glued(r, c, r + 1, c),
                "l": glued(r, c, r, c - 1), "r": glued(r, c, r, c + 1)}

    nbs = {(r, c): nb(r, c) for r in range(h) for c in range(w) if m[r, c] != 0}
    pts: dict = {}  # (r, c) -> [tl, tr, bl, br]
    eds: dict = {}  # (r, c) -> [top, bot, left, right]
    cx, ry = [], []
    ea, eb, erest, ek, ediag = [], [], [], [], []

    def new_point(x: int, y: int) -> int:
        cx.append(x)
        ry.append(y)
        return len(cx) - 1

    def new_edge(a: int, b: int, rest: float, k: float, diag: bool = False) -> int:
        ea.append(a)
        eb.append(b)
        erest.append(rest)
        ek.append(k)
        ediag.append(diag)
        return len(ea) - 1

    for r in range(h):
        for c in range(w):
            if m[r, c] == 0:
                continue
            n = nbs[(r, c)]
            top = (r - 1, c) if n["t"] else None
            left = (r, c - 1) if n["l"] else None
            # diagonal neighbours reachable through one glued orthogonal neighbour
            tl = tr = None
            if n["t"] and nbs[(r - 1, c)]["l"]:
                tl = (r - 1, c - 1)
            if n["l"] and nbs[(r, c - 1)]["t"]:
                tl = (r - 1, c - 1)
            if n["t"] and nbs[(r - 1, c)]["r"]:
                tr = (r - 1, c + 1)
            if n["r"] and nbs[(r, c + 1)]["t"]:
                tr = (r - 1, c + 1)

            def got(cell, k):
                return pts[cell][k] if cell is not None and cell in pts else None

            p_tl = None
            for cand in (got(top, 2), got(left, 1), got(tl, 3)):  # later wins, as in evogym
                if cand is not None:
                    p_tl = cand
            if p_tl is None:
                p_tl = new_point(c, r)
            p_tr = None
            for cand in (got(top, 3), got(tr, 2)):
                if cand is not None:
                    p_tr = cand
            if p_tr is None:
                p_tr = new_point(c + 1, r)
            p_bl = got(left, 3)
            if p_bl is None:
                p_bl = new_point(c, r + 1)
            p_br = new_point(c + 1, r + 1)
            pts[(r, c)] = [p_tl, p_tr, p_bl, p_br]

            e_top = eds[top][1] if top is not None else new_edge(p_tl, p_tr, C.MAIN_REST, C.K_RIGID_MAIN)
            e_bot = new_edge(p_bl, p_br, C.MAIN_REST, C.K_RIGID_MAIN)
            e_left = eds[left][3] if left is not None else new_edge(p_tl, p_bl, C.MAIN_REST, C.K_RIGID_MAIN)
            e_right = new_edge(p_tr, p_br, C.MAIN_REST, C.K_RIGID_MAIN)
            eds[(r, c)] = [e_top, e_bot, e_left, e_right]

    # second pass: spring constants of main edges (last non-rigid owner wins) and diagonals
    for r in range(h):
        for c in range(w):
            t = m[r, c]
            if t == 0:
                continue
            p_tl, p_tr, p_bl, p_br = pts[(r, c)]
            if t in (C.RIGID, C.FIXED):
                kd = C.K_RIGID_DIAG
            else:
                km, kd = ((C.K_SOFT_MAIN, C.K_SOFT_DIAG) if t == C.SOFT
                          else (C.K_ACT_MAIN, C.K_ACT_DIAG))
                for e in eds[(r, c)]:
                    ek[e] = km
            new_edge(p_tr, p_bl, C.DIAG_REST, kd, True)
            new_edge(p_tl, p_br, C.DIAG_REST, kd, True)

    cells = [(r, c) for r in range(h) for c in range(w) if m[r, c] != 0]
    nv = len(cells)
    voxel_points = np.zeros((nv, 4), dtype=np.int64)
    voxel_edges = np.zeros((nv, 4), dtype=np.int64)
    voxel_open = np.zeros((nv, 4), dtype=bool)
    ea_arr, eb_arr = np.array(ea, dtype=np.int64), np.array(eb, dtype=np.int64)
    for i, (r, c) in enumerate(cells):
        p_tl, p_tr, p_bl, p_br = pts[(r, c)]
        e_top, e_bot, e_left, e_right = eds[(r, c)]
        voxel_points[i] = (p_tl, p_tr, p_br, p_bl)
        voxel_edges[i] = (e_top, e_right, e_bot, e_left)
        n = nbs[(r, c)]
        voxel_open[i] = (not n["t"], not n["r"], not n["b"], not n["l"])
        # surface edges point so that (b - a) rotated +90 deg is the outward normal
        if not n["b"]:
            ea_arr[e_bot], eb_arr[e_bot] = p_br, p_bl
        if not n["l"]:
            ea_arr[e_left], eb_arr[e_left] = p_bl, p_tl

    vtype = np.array([m[r, c] for r, c in cells], dtype=np.int64)
    act_vox = np.array([i for i, t in enumerate(vtype) if t in (C.H_ACT, C.V_ACT)], dtype=np.int64)
    drivers = -np.ones((len(ea), 2), dtype=np.int64)
    for j, v in enumerate(act_vox):
        sides = (TOP, BOTTOM) if vtype[v] == C.H_ACT else (LEFT, RIGHT)
        for s in sides:
            e = voxel_edges[v, s]
            slot = 0 if drivers[e, 0] < 0 else 1
            drivers[e, slot] = j
    rc = np.array(cells, dtype=np.int64).reshape(-1, 2)
    return Body(
        matrix=m, n_points=len(cx), corner_cx=np.array(cx, dtype=np.int64),
        corner_ry=np.array(ry, dtype=np.int64), edge_a=ea_arr, edge_b=eb_arr,
        edge_rest=np.array(erest), edge_k=np.array(ek), edge_is_diag=np.array(ediag, dtype=bool),
        voxel_rc=rc, voxel_type=vtype, voxel_points=voxel_points, voxel_edges=voxel_edges,
        voxel_open=voxel_open, actuator_voxels=act_vox,
        actuator_flat=(rc[act_vox, 0] * w + rc[act_vox, 1]) if len(act_vox) else act_vox,
        edge_drivers=drivers,
    )


def describe_body(body: object) -> str:
    """A body in a few words: "5x5 body, 21 voxels, 9 actuators" (for reprs and messages)."""
    m = np.asarray(body)
    if m.ndim != 2:
        return f"body of shape {m.shape}"
    filled = int(np.count_nonzero(m))
    actuators = int(np.count_nonzero((m == 3) | (m == 4)))
    return f"{m.shape[0]}x{m.shape[1]} body, {filled} voxels, {actuators} actuators"
