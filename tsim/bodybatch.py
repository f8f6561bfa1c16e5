"""Many bodies' topology at once: `build_bodies` gives, for a batch of matrices with evogym's full
connectivity, exactly what `tsim.body.build_body` gives for each (the same points, edges, voxels
and drivers in the same order, bit for bit), as one `BodyBatch` of concatenated arrays.

How (`tsim.body._build` is the reference and the test oracle): with full connectivity every rule
of evogym's `ObjectCreator` is local.
- A lattice corner is shared by the filled cells around it that are joined through its 4-cycle of
  cells (NW-NE-SE-SW); the point is made by the first of them in row-major order, at that cell's
  corner slot, and points are numbered in the order (cell, slot TL, TR, BL, BR) they are made. A
  16-entry table gives each corner's component makers.
- A cell makes its top edge unless it has a top neighbour (then it is that cell's bottom), its
  bottom, its left unless it has a left neighbour, and its right, in that order; then every cell's
  two diagonals follow. A shared main edge takes the spring constant of its later non-rigid owner,
  and is driven by its owners' actuators in actuator order.
"""

from __future__ import annotations

from collections.abc import Iterator, Sequence

import numpy as np

from tsim import constants as C
from tsim.body import Body

# a corner's four cells, in row-major order: NW, NE, SW, SE; their corner slot (cell points are
# TL, TR, BL, BR here, `_build`'s pts order) and cell offset from the corner's (y, x) in the padded
# cell grid (cell (r, c) at (r + 1, c + 1))
_NW, _NE, _SW, _SE = 0, 1, 2, 3
_SLOT_OF = (3, 2, 1, 0)  # NW's BR, NE's BL, SW's TR, SE's TL
_CYCLE = ((_NW, _NE), (_NE, _SE), (_SE, _SW), (_SW, _NW))


def _root(comp: list[int], q: int) -> int:
    while comp[q] != q:
        q = comp[q]
    return q


def _maker_table() -> np.ndarray:
    """(16, 4): for each filled pattern (bit q = cell q filled) and cell q, the first cell of q's
    component around the corner (cells joined along the 4-cycle), -1 for an empty cell."""
    table = -np.ones((16, 4), dtype=np.int64)
    for pat in range(16):
        filled = [bool(pat >> q & 1) for q in range(4)]
        comp = list(range(4))

        for a, b in _CYCLE:
            if filled[a] and filled[b]:
                ra, rb = _root(comp, a), _root(comp, b)
                comp[max(ra, rb)] = min(ra, rb)
        for q in range(4):
            if filled[q]:
                table[pat, q] = _root(comp, q)
    return table


_MAKER = _maker_table()
_MAKER_INT8 = _MAKER.astype(np.int8)


class BodyBatch(Sequence):
    """N bodies as concatenated arrays (`Body`'s fields, each body's rows after the previous
    body's) with per-body counts; indexing gives a `Body` (made on first use, then kept)."""

    FIELDS_P = ("corner_cx", "corner_ry")
    FIELDS_E = ("edge_a", "edge_b", "edge_rest", "edge_k", "edge_is_diag", "edge_drivers")
    FIELDS_V = ("voxel_rc", "voxel_type", "voxel_points", "voxel_edges", "voxel_open")
    FIELDS_A = ("actuator_voxels", "actuator_flat")

    def __init__(self, matrices: Sequence[np.ndarray], n_points: np.ndarray, n_edges: np.ndarray,
                 n_voxels: np.ndarray, n_actuators: np.ndarray, arrays: dict[str, np.ndarray],
                 n_rows: np.ndarray | None = None):
        self.matrices = matrices
        self.n_points = np.asarray(n_points, dtype=np.int64)
        self.n_edges = np.asarray(n_edges, dtype=np.int64)
        self.n_voxels = np.asarray(n_voxels, dtype=np.int64)
        self.n_actuators = np.asarray(n_actuators, dtype=np.int64)
        self.arrays = arrays
        self.n_rows = np.array([np.shape(m)[0] for m in matrices], dtype=np.int64) if n_rows is None \
            else np.asarray(n_rows, dtype=np.int64)  # each matrix's height (`Body.place`)
        self._cache: dict[int, Body] = {}
        self._starts = None

    def __len__(self) -> int:
        return len(self.n_points)

    def _offsets(self) -> tuple[np.ndarray, ...]:
        if self._starts is None:
            self._starts = tuple(np.concatenate(([0], np.cumsum(n)))
                                 for n in (self.n_points, self.n_edges, self.n_voxels, self.n_actuators))
        return self._starts

    def __getitem__(self, i):  # noqa: ANN001 - Sequence's int or slice
        if isinstance(i, slice):
            return [self[j] for j in range(*i.indices(len(self)))]
        i = int(i)
        if i < 0:
            i += len(self)
        if not 0 <= i < len(self):
            raise IndexError(f"body {i} of {len(self)}")
        hit = self._cache.get(i)
        if hit is not None:
            return hit
        sp, se, sv, sa = self._offsets()
        a = self.arrays
        kw = {f: a[f][sp[i]:sp[i + 1]] for f in self.FIELDS_P}
        kw |= {f: a[f][se[i]:se[i + 1]] for f in self.FIELDS_E}
        kw |= {f: a[f][sv[i]:sv[i + 1]] for f in self.FIELDS_V}
        kw |= {f: a[f][sa[i]:sa[i + 1]] for f in self.FIELDS_A}
        body = Body(matrix=np.asarray(self.matrices[i]), n_points=int(self.n_points[i]), **kw)
        self._cache[i] = body
        return body

    def __iter__(self) -> Iterator[Body]:
        return (self[i] for i in range(len(self)))

    @classmethod
    def from_bodies(cls, bodies: Sequence[Body]) -> BodyBatch:
        """The batch of these `Body`s (their arrays concatenated; indexing gives them back)."""
        arrays = {f: np.concatenate([getattr(b, f) for b in bodies])
                  for f in cls.FIELDS_P + cls.FIELDS_E + cls.FIELDS_V + cls.FIELDS_A}
        out = cls([b.matrix for b in bodies], [b.n_points for b in bodies], [b.n_edges for b in bodies],
                  [b.n_voxels for b in bodies], [b.n_actuators for b in bodies], arrays)
        out._cache = dict(enumerate(bodies))
        return out

    def take(self, order: np.ndarray) -> BodyBatch:
        """The bodies in `order` (indices into this batch) as a new batch."""
        order = np.asarray(order, dtype=np.int64)
        starts = self._offsets()
        counts = (self.n_points, self.n_edges, self.n_voxels, self.n_actuators)
        groups = (self.FIELDS_P, self.FIELDS_E, self.FIELDS_V, self.FIELDS_A)
        arrays = {}
        for start, n, fields in zip(starts, counts, groups, strict=True):
            idx = _ranges(start[order], n[order])
            for f in fields:
                arrays[f] = self.arrays[f][idx]
        mats = [self.matrices[i] for i in order]
        return BodyBatch(mats, *(n[order] for n in counts), arrays, self.n_rows[order])

    @classmethod
    def concatenate(cls, batches: Sequence[BodyBatch]) -> BodyBatch:
        """One batch of these batches' bodies, in order."""
        names = cls.FIELDS_P + cls.FIELDS_E + cls.FIELDS_V + cls.FIELDS_A
        arrays = {f: np.concatenate([b.arrays[f] for b in batches]) for f in names}
        mats = [m for b in batches for m in b.matrices]
        return cls(mats, *(np.concatenate([getattr(b, c) for b in batches])
                           for c in ("n_points", "n_edges", "n_voxels", "n_actuators")), arrays,
                   np.concatenate([b.n_rows for b in batches]))


def _ranges(starts: np.ndarray, counts: np.ndarray) -> np.ndarray:
    """Concatenated aranges start[i] .. start[i] + count[i]."""
    total = int(counts.sum())
    if total == 0:
        return np.zeros(0, dtype=np.int64)
    ends = np.cumsum(counts)
    out = np.ones(total, dtype=np.int64)
    nz = counts > 0
    first = (ends - counts)[nz]
    out[first] = starts[nz] - np.concatenate(([0], (starts + counts)[nz][:-1] - 1))
    out[0] = starts[nz][0]
    return np.cumsum(out)


def build_bodies(matrices: Sequence[np.ndarray] | np.ndarray) -> BodyBatch:
    """Topology of every body (validated int matrices, codes 0-5, any shapes) with evogym's full
    connectivity: body i equals `build_body(matrices[i])` field for field, bit for bit."""
    if isinstance(matrices, np.ndarray) and matrices.ndim == 3:
        return _build_same_shape(matrices.astype(np.int64, copy=False))
    mats = [np.asarray(m, dtype=np.int64) for m in matrices]
    shapes = {}
    for i, m in enumerate(mats):
        shapes.setdefault(m.shape, []).append(i)
    if len(shapes) == 1:
        return _build_same_shape(np.stack(mats), mats)
    parts, order = [], []
    for idx in shapes.values():
        parts.append(_build_same_shape(np.stack([mats[i] for i in idx]), [mats[i] for i in idx]))
        order += idx
    inverse = np.empty(len(order), dtype=np.int64)
    inverse[np.asarray(order)] = np.arange(len(order))
    return BodyBatch.concatenate(parts).take(inverse)


def _build_same_shape(M: np.ndarray, mats: Sequence[np.ndarray] | None = None) -> BodyBatch:
    """`build_bodies` of an (N, H, W) array, in chunks that keep the work arrays in cache."""
    if mats is None:
        mats = list(M)
    N, H, W = M.shape
    chunk = max(1, _CHUNK_CELLS // max(H * W, 1))
    if N <= chunk:
        return _build_chunk(M, mats)
    return BodyBatch.concatenate([_build_chunk(M[i:i + chunk], mats[i:i + chunk])
                                  for i in range(0, N, chunk)])


_CHUNK_CELLS = 32_768  # cells per chunk (1,310 bodies of 5x5): measured best at 16k-64k


def _build_chunk(M: np.ndarray, mats: Sequence[np.ndarray]) -> BodyBatch:  # noqa: PLR0915
    N, H, W = M.shape
    HW = H * W
    i64 = np.int64
    F = M != 0
    Fp = np.zeros((N, H + 2, W + 2), dtype=bool)
    Fp[:, 1:-1, 1:-1] = F
    t = F & Fp[:, :-2, 1:-1]
    b = F & Fp[:, 2:, 1:-1]
    lft = F & Fp[:, 1:-1, :-2]
    rgt = F & Fp[:, 1:-1, 2:]

    # ---- points: a corner's pattern, its makers, the new points (cell row-major, TL TR BL BR)
    pat = (Fp[:, :-1, :-1].astype(np.uint8) | (Fp[:, :-1, 1:].astype(np.uint8) << 1)
           | (Fp[:, 1:, :-1].astype(np.uint8) << 2) | (Fp[:, 1:, 1:].astype(np.uint8) << 3))
    # cell slot s of cell (r, c) is corner (r + s // 2, c + s % 2) seen as that corner's cell 3 - s
    new = np.empty((N, H, W, 4), dtype=bool)
    makers = []
    for s in range(4):
        dy, dx = s // 2, s % 2
        mk = _MAKER_INT8[:, 3 - s][pat[:, dy:dy + H, dx:dx + W]]
        makers.append(mk)
        new[..., s] = mk == 3 - s
    new &= F[..., None]
    ids = np.cumsum(new.reshape(N, -1), axis=1, dtype=i64) - 1
    n_points = ids[:, -1] + 1
    # the id at each corner seen from each of its cells (that cell's slot), then the maker's
    idp = np.zeros((N, H + 2, W + 2, 4), dtype=i64)
    idp[:, 1:-1, 1:-1] = ids.reshape(N, H, W, 4)
    cand = np.stack([idp[:, :-1, :-1, 3], idp[:, :-1, 1:, 2], idp[:, 1:, :-1, 1], idp[:, 1:, 1:, 0]],
                    axis=-1)  # (N, H+1, W+1, 4): the point each corner cell would make
    P = np.empty((N, H, W, 4), dtype=i64)
    for s in range(4):
        dy, dx = s // 2, s % 2
        c = cand[:, dy:dy + H, dx:dx + W]
        which = np.maximum(makers[s], 0)[..., None].astype(np.intp)
        P[..., s] = np.take_along_axis(c, which, axis=-1)[..., 0]
    p_tl, p_tr, p_bl, p_br = P[..., 0], P[..., 1], P[..., 2], P[..., 3]
    fp = np.flatnonzero(new) % (4 * HW)  # (cell, slot) of each new point
    corner_cx = (fp >> 2) % W + (fp & 1)
    corner_ry = (fp >> 2) // W + ((fp >> 1) & 1)

    # ---- edges: main ones (top?, bottom, left?, right per cell), then two diagonals per cell
    made = np.empty((N, H, W, 4), dtype=bool)
    made[..., 0] = F & ~t
    made[..., 1] = F
    made[..., 2] = F & ~lft
    made[..., 3] = F
    vox_id = np.cumsum(F.reshape(N, -1), axis=1, dtype=i64).reshape(N, H, W) - 1
    n_vox = F.reshape(N, -1).sum(axis=1, dtype=i64)
    eid = np.cumsum(made.reshape(N, -1), axis=1, dtype=i64).reshape(N, H, W, 4) - 1
    n_main = made.reshape(N, -1).sum(axis=1, dtype=i64)
    e_bot, e_right = eid[..., 1], eid[..., 3]
    e_top = eid[..., 0].copy()
    e_top[:, 1:] = np.where(t[:, 1:], e_bot[:, :-1], e_top[:, 1:])
    e_left = eid[..., 2].copy()
    e_left[:, :, 1:] = np.where(lft[:, :, 1:], e_right[:, :, :-1], e_left[:, :, 1:])
    n_edges = n_main + 2 * n_vox

    # every body's edge slots: 4 main per cell (top, bottom, left, right), then 2 diagonals per
    # cell; the made ones, in this order, are its edges
    keep = np.empty((N, 6 * HW), dtype=bool)
    keep[:, :4 * HW] = made.reshape(N, -1)
    keep[:, 4 * HW:].reshape(N, HW, 2)[:] = F.reshape(N, HW, 1)

    def slots(dtype: type) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        a = np.empty((N, 6 * HW), dtype=dtype)
        return a, a[:, :4 * HW].reshape(N, H, W, 4), a[:, 4 * HW:].reshape(N, H, W, 2)

    # endpoints, with the surface swap (an open bottom runs br -> bl, a made left bl -> tl)
    open_b = ~b
    ea, ea_m, ea_d = slots(i64)
    ea_m[..., 0], ea_m[..., 1], ea_m[..., 2], ea_m[..., 3] = p_tl, np.where(open_b, p_br, p_bl), p_bl, p_tr
    ea_d[..., 0], ea_d[..., 1] = p_tr, p_tl
    eb, eb_m, eb_d = slots(i64)
    eb_m[..., 0], eb_m[..., 1], eb_m[..., 2], eb_m[..., 3] = p_tr, np.where(open_b, p_bl, p_br), p_tl, p_br
    eb_d[..., 0], eb_d[..., 1] = p_bl, p_br

    # spring constants: a main edge keeps K_RIGID_MAIN unless an owner is non-rigid, the later
    # one (below, right) winning; diagonals by their voxel's material
    km_of = np.array([np.nan, np.nan, C.K_SOFT_MAIN, C.K_ACT_MAIN, C.K_ACT_MAIN, np.nan])
    kd_of = np.array([0.0, C.K_RIGID_DIAG, C.K_SOFT_DIAG, C.K_ACT_DIAG, C.K_ACT_DIAG, C.K_RIGID_DIAG])
    km = km_of[M]
    own = np.where(np.isnan(km), C.K_RIGID_MAIN, km)
    ek, ek_m, ek_d = slots(np.float64)
    ek_m[..., 0] = own
    ek_m[..., 2] = own
    ek_m[..., 1] = own
    ek_m[:, :-1, :, 1] = np.where(b[:, :-1] & ~np.isnan(km[:, 1:]), km[:, 1:], own[:, :-1])
    ek_m[..., 3] = own
    ek_m[:, :, :-1, 3] = np.where(rgt[:, :, :-1] & ~np.isnan(km[:, :, 1:]), km[:, :, 1:], own[:, :, :-1])
    ek_d[:] = kd_of[M][..., None]

    # drivers: actuator index j of the edge's owners that drive that side (H: top/bottom, V: sides)
    is_h, is_v = M == C.H_ACT, M == C.V_ACT
    act = is_h | is_v
    j = np.cumsum(act.reshape(N, -1), axis=1, dtype=i64).reshape(N, H, W) - 1
    n_act = act.reshape(N, -1).sum(axis=1, dtype=i64)
    jh = np.where(is_h, j, -1)
    jv = np.where(is_v, j, -1)
    jh_below = np.full((N, H, W), -1, dtype=i64)
    jh_below[:, :-1] = np.where(b[:, :-1], jh[:, 1:], -1)
    jv_right = np.full((N, H, W), -1, dtype=i64)
    jv_right[:, :, :-1] = np.where(rgt[:, :, :-1], jv[:, :, 1:], -1)
    dr = np.full((N, 6 * HW, 2), -1, dtype=i64)
    dr_m = dr[:, :4 * HW].reshape(N, H, W, 4, 2)
    dr_m[..., 0, 0] = jh
    dr_m[..., 1, 0] = np.where(jh >= 0, jh, jh_below)
    dr_m[..., 1, 1] = np.where(jh >= 0, jh_below, -1)
    dr_m[..., 2, 0] = jv
    dr_m[..., 3, 0] = np.where(jv >= 0, jv, jv_right)
    dr_m[..., 3, 1] = np.where(jv >= 0, jv_right, -1)

    # the packing: np.take of flat indices (boolean masks and fancy indices of several dimensions
    # are up to 50x slower here)
    fk = np.flatnonzero(keep)
    fv = np.flatnonzero(F)
    diag = (fk % (6 * HW)) >= 4 * HW
    edge_rest = np.where(diag, C.DIAG_REST, C.MAIN_REST)
    cell = fv % HW

    def pick(a: np.ndarray, idx: np.ndarray, k: int = 0) -> np.ndarray:
        return np.take(a.reshape(-1, k) if k else a.reshape(-1), idx, axis=0)

    # voxels, row-major per body
    ve = np.empty((N, H, W, 4), dtype=i64)
    ve[..., 0], ve[..., 1], ve[..., 2], ve[..., 3] = e_top, e_right, e_bot, e_left
    op = np.empty((N, H, W, 4), dtype=bool)
    op[..., 0], op[..., 1], op[..., 2], op[..., 3] = ~t, ~rgt, ~b, ~lft
    vp = np.empty((N, H, W, 4), dtype=i64)
    vp[..., 0], vp[..., 1], vp[..., 2], vp[..., 3] = p_tl, p_tr, p_br, p_bl
    voxel_rc = np.empty((len(fv), 2), dtype=i64)
    voxel_rc[:, 0] = cell // W
    voxel_rc[:, 1] = cell % W
    fa = np.flatnonzero(act)
    edge_a = pick(ea, fk)
    edge_b = pick(eb, fk)
    edge_k = pick(ek, fk)
    edge_drivers = pick(dr, fk, 2)
    voxel_type = pick(M, fv)
    voxel_points = pick(vp, fv, 4)
    voxel_edges = pick(ve, fv, 4)
    voxel_open = pick(op, fv, 4)
    actuator_voxels = pick(vox_id, fa)
    actuator_flat = fa % HW
    arrays = {"corner_cx": corner_cx, "corner_ry": corner_ry, "edge_a": edge_a, "edge_b": edge_b,
              "edge_rest": edge_rest, "edge_k": edge_k, "edge_is_diag": diag, "edge_drivers": edge_drivers,
              "voxel_rc": voxel_rc, "voxel_type": voxel_type, "voxel_points": voxel_points,
              "voxel_edges": voxel_edges, "voxel_open": voxel_open, "actuator_voxels": actuator_voxels,
              "actuator_flat": actuator_flat}
    return BodyBatch(mats, n_points, n_edges, n_vox, n_act, arrays, np.full(N, H, dtype=np.int64))
