"""Contacts of one substep: voxel boxes, the pairs the broad phase finds, the narrow phase on each.

The order in which pairs act is evogym's (surface voxel i < j, then voxel i against the terrain
cells its box reaches), whichever way the pairs are found (`broadphase`).
"""

from tsim import constants as C
from tsim.backend.runtime import PROFILE_SKIP, ti
from tsim.kernels import layout as L
from tsim.kernels.broadphase import (
    LIST_ALWAYS,
    LIST_MIN,
    LIST_OFF,
    SKIN,
    SWEEP_ALWAYS,
    SWEEP_AUTO,
    SWEEP_MIN,
    SWEEP_OFF,
    candidates,
    choose_sweep,
    robot_pair_acts,
    sort_along,
    terrain_pair_acts,
)
from tsim.kernels.layout import N_SURF, N_SURF_ROBOT
from tsim.kernels.narrowphase import Q_LO, load_quad, n_qf, resolve
from tsim.kernels.scratch import P_COUNT, P_FINITE, P_FITS, P_N_LIST, P_WX, P_WY, pieced


@ti.func
def contacts(b, n_pts, counts: ti.template(), s: ti.template(), ter: ti.template(),
             sweep_mode: ti.template(), pair_list: ti.template(), part: ti.template()):
    """Recompute the surface voxels' boxes and the contact forces (into s.fcol); return evogym's
    robot self-collision count (-1 when a coordinate is not finite). Surface voxel i has corners
    s.sv[8i:8i+4], open sides s.sv[8i+4:8i+8] and object, row, col s.sm[4i:4i+3]. Pairs of surface
    voxels are those with overlapping boxes, in the order of the loop over i < j (evogym's), found
    by the plain loop or by sweep and prune along x or y as `sweep_mode` says, or from the pair
    list (see `broadphase.SKIN`) while it holds: s.plist[0] = 1 when s.nbr[s.nstart[i]:
    s.nstart[i + 1]] lists voxel i's partners j > i within SKIN of its box when the boxes were
    s.refbox. `ter`: a `scratch.Terrain`.

    `part`: None, all of it (the CPU's kernels); or a `scratch.Part`: the surface voxels i of
    piece part.piece of part.pieces (SPIR-V, tsim/backend/spirv.py: a driver that bounds a shader's loops
    may need a substep's contacts in several launches), in the order of one call, with what one
    piece hands the next (its count, the list's length, the boxes' widths) in part's slots; the
    boxes are made and the sweep decided in the first piece, the list closed in the last."""
    grid_slack = ti.static(L.tol().grid_slack)
    n_surf = counts[b, N_SURF]
    n_surf_robot = counts[b, N_SURF_ROBOT]
    i0 = 0
    i1 = n_surf
    first = True
    last = True
    if ti.static(pieced(part)):
        i0 = n_surf * part.piece // part.pieces
        i1 = n_surf * (part.piece + 1) // part.pieces
        first = part.piece == 0
        last = part.piece == part.pieces - 1
    if first:
        for i in range(2 * n_pts):
            s.fcol[i] = 0.0
    finite = True
    wx = 0.0  # the widest box along x and along y
    wy = 0.0
    for i in range(n_surf if first else 0):
        p0 = s.sv[8 * i]
        x0 = s.pos[2 * p0]
        y0 = s.pos[2 * p0 + 1]
        x1 = x0
        y1 = y0
        for k in range(1, 4):
            p = s.sv[8 * i + k]
            x = s.pos[2 * p]
            y = s.pos[2 * p + 1]
            x0 = ti.min(x0, x)
            x1 = ti.max(x1, x)
            y0 = ti.min(y0, y)
            y1 = ti.max(y1, y)
        s.box[4 * i] = x0
        s.box[4 * i + 1] = x1
        s.box[4 * i + 2] = y0
        s.box[4 * i + 3] = y1
        wx = ti.max(wx, x1 - x0)
        wy = ti.max(wy, y1 - y0)
        if not (ti.abs(x0) < 1e30 and ti.abs(x1) < 1e30 and ti.abs(y0) < 1e30
                and ti.abs(y1) < 1e30):
            finite = False
    count = 0
    if ti.static(pieced(part)):
        if first:
            part.i[P_FINITE] = 1 if finite else 0
            part.f[P_WX] = wx
            part.f[P_WY] = wy
        else:
            finite = part.i[P_FINITE] == 1
            wx = part.f[P_WX]
            wy = part.f[P_WY]
            count = part.i[P_COUNT]
    if finite:
        qf = ti.Matrix.zero(float, 8, ti.static(n_qf()))
        qi = ti.Matrix.zero(ti.i32, 8, 2)
        gw = ter.grid.shape[0]
        gh = ter.grid.shape[1]
        use_list = False
        listing = ti.static(pair_list == LIST_ALWAYS) or n_surf >= LIST_MIN
        if ti.static("pairs" not in PROFILE_SKIP and pair_list != LIST_OFF):
            if s.plist[0] == 1:
                moved = 0.0
                for k in range(4 * n_surf):
                    moved = ti.max(moved, ti.abs(s.box[k] - s.refbox[k]))
                use_list = 2.0 * moved < SKIN - ti.static(L.tol().skin_slack)
        if ti.static(sweep_mode != SWEEP_OFF):
            # s.sweep[0]: -1 undecided (the env step's first substep), 0 plain loop, 1 sweep along
            # axis s.sweep[1]
            if first:
                if n_surf < SWEEP_MIN and ti.static(sweep_mode == SWEEP_AUTO):
                    s.sweep[0] = 0
                if s.sweep[0] < 0:
                    choose_sweep(n_surf, wx, wy, s.box, s.order, s.rank, s.sweep,
                                  ti.static(sweep_mode == SWEEP_ALWAYS))
                elif s.sweep[0] == 1 and not use_list:
                    sort_along(n_surf, s.box, s.order, s.rank, s.sweep[1])
        n_list = 0  # building the list: its length, and whether it fits
        fits = True
        if ti.static(pieced(part)):
            if not first:
                n_list = part.i[P_N_LIST]
                fits = part.i[P_FITS] == 1
        for i in range(i0, i1):
            loaded = False
            bx0 = s.box[4 * i]
            bx1 = s.box[4 * i + 1]
            by0 = s.box[4 * i + 2]
            by1 = s.box[4 * i + 3]
            if ti.static("pairs" not in PROFILE_SKIP):
                # i's partners j, ascending: j = c for c in [lo, hi) (the plain loop), or listed
                # at s.nbr[c] (the pair list) or at s.cand[c] (sweep and prune)
                lo = i + 1
                hi = n_surf
                src = 0
                if ti.static(pair_list != LIST_OFF):
                    if use_list:
                        lo = s.nstart[i]
                        hi = s.nstart[i + 1]
                        src = 1
                    else:
                        s.nstart[i] = n_list
                if ti.static(sweep_mode != SWEEP_OFF):
                    if s.sweep[0] == 1 and not use_list:
                        w = wx if s.sweep[1] == 0 else wy
                        lo = 0
                        hi = candidates(i, n_surf, w, s.box, s.order, s.rank, s.cand, s.sweep[1],
                                         SKIN if ti.static(pair_list != LIST_OFF) else 0.0)
                        src = 2
                for c in range(lo, hi):
                    j = c
                    if ti.static(pair_list != LIST_OFF):
                        if src == 1:
                            j = s.nbr[c]
                    if ti.static(sweep_mode != SWEEP_OFF):
                        if src == 2:
                            j = s.cand[c]
                    if ti.static(pair_list != LIST_OFF):
                        if src != 1 and listing and not (
                                bx0 > s.box[4 * j + 1] + SKIN or bx1 + SKIN < s.box[4 * j]
                                or by0 > s.box[4 * j + 3] + SKIN or by1 + SKIN < s.box[4 * j + 2]):
                            if n_list < s.nbr.n:
                                s.nbr[n_list] = j
                                n_list += 1
                            else:
                                fits = False
                    if not (bx0 > s.box[4 * j + 1] or bx1 < s.box[4 * j]
                            or by0 > s.box[4 * j + 3] or by1 < s.box[4 * j + 2]):
                        same = s.sm[4 * i] == s.sm[4 * j]
                        scale = 2.0 if same else 1.0
                        if same and i < n_surf_robot and j < n_surf_robot:
                            dr = ti.abs(s.sm[4 * i + 1] - s.sm[4 * j + 1])
                            dc = ti.abs(s.sm[4 * i + 2] - s.sm[4 * j + 2])
                            if dr > 1 or dc > 1:  # evogym's self-collision count
                                count += 2
                        if robot_pair_acts(s.pos, s.sv, s.box, i, j):
                            if not loaded:
                                load_quad(s, qf, qi, 0, i)
                                loaded = True
                            load_quad(s, qf, qi, 1, j)
                            for d in range(2):
                                resolve(s.fcol, qf, qi, d, 1 - d, scale)
            # no terrain box reaches above ter.top, so no terrain test can pass for a box above it
            if by0 <= ter.top:
                gx0 = ti.max(0, ti.cast(ti.ceil(bx0 / C.CELL - 1.0 - grid_slack), ti.i32))
                gx1 = ti.min(gw - 1, ti.cast(ti.floor(bx1 / C.CELL + grid_slack), ti.i32))
                gy0 = ti.max(0, ti.cast(ti.ceil(by0 / C.CELL - 1.0 - grid_slack), ti.i32))
                gy1 = ti.min(gh - 1, ti.cast(ti.floor(by1 / C.CELL + grid_slack), ti.i32))
                for gx in range(gx0, gx1 + 1 if ti.static("terrain" not in PROFILE_SKIP) else gx0):
                    for gy in range(gy0, gy1 + 1):
                        t = ter.grid[gx, gy]
                        if t >= 0:
                            acts = False
                            if not (bx0 > ter.f[t, 9] or bx1 < ter.f[t, 8]
                                    or by0 > ter.f[t, 11] or by1 < ter.f[t, 10]):
                                acts = terrain_pair_acts(s.pos, s.sv, s.box, ter.f, i, t)
                            if acts:
                                if not loaded:
                                    load_quad(s, qf, qi, 0, i)
                                    loaded = True
                                for k in range(4):
                                    qf[4 + k, 0] = ter.f[t, 2 * k]
                                    qf[4 + k, 1] = ter.f[t, 2 * k + 1]
                                    if ti.static(L.pairs()):
                                        qf[4 + k, Q_LO] = ter.f[t, L.TER_LO + 2 * k]
                                        qf[4 + k, Q_LO + 1] = ter.f[t, L.TER_LO + 2 * k + 1]
                                    qf[4 + k, 2] = 0.0
                                    qf[4 + k, 3] = 0.0
                                    qi[4 + k, 0] = -1
                                    qi[4 + k, 1] = ter.i[t, k]
                                for d in range(2):
                                    resolve(s.fcol, qf, qi, d, 1 - d, 1.0)
        if ti.static(pieced(part)):
            part.i[P_COUNT] = count
            part.i[P_N_LIST] = n_list
            part.i[P_FITS] = 1 if fits else 0
        if ti.static("pairs" not in PROFILE_SKIP and pair_list != LIST_OFF):
            if not use_list and last:
                s.nstart[n_surf] = n_list
                s.plist[0] = 1 if fits and listing else 0
                for k in range(4 * n_surf):
                    s.refbox[k] = s.box[k]
                    if not ti.abs(s.box[k]) < ti.static(L.tol().ref_max):
                        s.plist[0] = 0
    if not finite:
        count = -1
    return count


