"""Taichi kernels: one env step of every world in the batch, evogym's substep repeated 30 times.

Layout (all arrays are Taichi ndarrays, so the kernels compile once per process for any batch;
`counts`, `state` and `actions` change between launches, the others are static):
- `counts[b, :]`   int: see the COUNT_* column names below.
- `state[b, p, :]` f64: pos(0:2) vel(2:4) pos_last(4:6) vel_true(6:8) of dynamic point p
  (robot points first, then free objects such as Thrower's package).
- `edge_i[b, e, :]` int: a, b, driver0, driver1 (actuator indices or -1).
- `edge_f[b, e, :]` f64: rest length, k, goal at rest, current rest length at rest (the kernel
  derives each step's goals from the actions and keeps the current rest lengths in local arrays).
- `vox_i[b, v, :]` int: corner points (TL, TR, BR, BL), open sides (top, right, bottom, left),
  material, object id, row, col; `lists[b, i, 0]` surface voxels (robot first),
  `lists[b, i, 1]` rigid voxels, `lists[b, i, 2]` fixed points (corners of a simulated object's
  material-5 voxels: evogym discards their RK4 increment and their edge-constraint moves).
- terrain (shared by the batch, static): `ter_f[t, :]` corners TL, TR, BR, BL as x, y pairs then
  the AABB; `ter_i[t, :]` open sides; `ter_grid[gx, gy]` the surface voxel in that cell or -1.

Design: one parallel loop over worlds with serial inner loops over that world's points, springs and
voxels (cache-friendly, no atomics). Each world does all 30 substeps in one kernel launch, with its
state copied into local arrays (see the note above `capacity`).
"""


from tsim import constants as C
from tsim import portable
from tsim.runtime import PROFILE_SKIP, ti  # ti imported there with its banner sent to stderr

# counts columns
N_PTS, N_EDGES, N_VOX, N_SURF, N_SURF_ROBOT, N_RIGID, N_ACT, STATUS, N_FIXED = range(9)
N_COUNTS = 9
# STATUS values: a world is simulated only while its status is RUNNING
RUNNING, UNSTABLE, NONFINITE, INACTIVE = 0, 1, 2, 3

# vox_i columns
V_PTS, V_OPEN, V_TYPE, V_OBJ, V_ROW, V_COL = 0, 4, 8, 9, 10, 11
N_VOX_I = 12

# edge_f columns
E_REST, E_K, E_GOAL, E_LEQ = range(4)
N_EDGE_F = 4

F64_2 = ti.types.ndarray(dtype=ti.f64, ndim=2)
I32_3 = ti.types.ndarray(dtype=ti.i32, ndim=3)
I32_2 = ti.types.ndarray(dtype=ti.i32, ndim=2)

_HI = 1.0 + C.EDGE_BAND
_LO = 1.0 - C.EDGE_BAND
_HI_R = 1.0 + C.EDGE_BAND_RIGID
_LO_R = 1.0 - C.EDGE_BAND_RIGID

vec2 = ti.types.vector(2, ti.f64)


@ti.func
def _cross(a, b):
    return a[0] * b[1] - a[1] * b[0]


@ti.func
def _point_in_quad(p, tl, tr, br, bl):
    """evogym's point-in-voxel test: triangles (TL,TR,BR) and (TL,BR,BL), boundary inside."""
    a_tl = tl - p
    a_tr = tr - p
    a_br = br - p
    a_bl = bl - p
    ca = _cross(a_tl, a_tr)
    cb = _cross(a_tr, a_br)
    cc = _cross(a_br, a_tl)
    inside = (cc * ca >= 0.0) and (cc * cb >= 0.0)
    if not inside:
        cd = _cross(a_tl, a_bl)
        ce = _cross(a_bl, a_br)
        inside = (cc * cd >= 0.0) and (cc * ce >= 0.0)
    return inside


@ti.func
def _intersects(a1, b1, a2, b2):
    """Closed segment intersection; near-parallel pairs (|det| < 1e-4) never intersect."""
    d1 = b1 - a1
    d2 = b2 - a2
    det = -d1[0] * d2[1] + d2[0] * d1[1]
    hit = False
    if ti.abs(det) >= C.PARALLEL_EPS:
        xd = a2[0] - a1[0]
        yd = a2[1] - a1[1]
        t = (-d2[1] * xd + d2[0] * yd) / det
        s = (-d1[1] * xd + d1[0] * yd) / det
        hit = 0.0 <= t and t <= 1.0 and 0.0 <= s and s <= 1.0
    return hit


@ti.func
def _dist_point_edge(p, a, b):
    base = b - a
    length = ti.sqrt(base[0] * base[0] + base[1] * base[1])
    d = 1000.0
    if length >= C.DEGENERATE_EDGE:
        slant = p - a
        d = ti.abs(base[0] * slant[1] - slant[0] * base[1]) / length
    return d


@ti.func
def _normalized(v):
    return v / ti.sqrt(v[0] * v[0] + v[1] * v[1])


@ti.func
def _in_box(x, y, x0, x1, y0, y1):
    """In the box widened by BOX_MARGIN: the same test as `_resolve`'s candidate corners."""
    return (x0 - C.BOX_MARGIN <= x and x <= x1 + C.BOX_MARGIN and y0 - C.BOX_MARGIN <= y
            and y <= y1 + C.BOX_MARGIN)


# ------------------------------------------------------------------------------------------------
# The per-point state of a world lives in local arrays (LLVM allocas) for the whole env step.
# Stores to ndarrays force LLVM to reload every ndarray's data pointer and shape after each store
# (they might alias), which made the spring loop ~3x slower than with local accumulators. Hot
# loops here store only to locals; ndarrays are addressed through flat 1-D views with
# compile-time strides. The local arrays have a static capacity (points, edges, surface voxels):
# a batch uses the smallest tier `capacity(k)` that holds its largest world; each tier is its own
# compiled kernel, and results do not depend on the tier (tests/tsim/test_kernels.py).
# ------------------------------------------------------------------------------------------------

# Contact pairs by sweep and prune along x or y: the same pairs in the same order as the plain
# loop, so results do not depend on it. A kernel's `sweep_mode` (compile time): SWEEP_OFF the plain
# loop only (compact bodies, where the sweep's code alone cost ~5 % at 16x16); SWEEP_AUTO per world
# and env step, where it has at least SWEEP_MIN surface voxels and `_choose_sweep` finds an axis
# that pays (long worlds such as BridgeWalker's: +40 %); SWEEP_ALWAYS everywhere (tests)
SWEEP_OFF, SWEEP_AUTO, SWEEP_ALWAYS = 0, 1, 2
SWEEP_MIN = 24
SWEEP_RATIO = 8
# Pair lists (Verlet lists with a skin): a substep that tests every pair also records the pairs
# whose boxes, each widened by SKIN, overlap. Later substeps of the env step test only those, as
# long as no box edge has moved by SKIN / 2 since: a pair left out had a gap above SKIN and each
# of its boxes moved less than SKIN / 2, so its box test would fail. Exact, not approximate:
# the same pairs act, in the same order.
SKIN = 0.05  # half a voxel: a 12x12 body lists ~181 of its 3,583 pairs (158 overlap)
SKIN_SLACK = 1e-9  # far above the rounding of `box + SKIN` (~6e-11 at coordinates below REF_MAX)
REF_MAX = 1e6  # no list for worlds with a coordinate beyond this
# A kernel's `pair_list` (compile time): LIST_OFF never (the kernel that small bodies run: the
# list's code alone cost them 2-5 %), LIST_AUTO in worlds with at least LIST_MIN surface voxels,
# LIST_ALWAYS in every world (tests)
LIST_OFF, LIST_AUTO, LIST_ALWAYS = 0, 1, 2
LIST_MIN = 24
LIST_PER_VOXEL = 8  # list capacity per surface voxel (bodies and bridges need ~2; full: no list)
GPU_BLOCK = 64  # worlds per thread block on a GPU (each world is one thread)
PC, EC, SC = 64, 160, 32  # tier 0: points, edges, surface voxels (a 5x5 robot and Thrower's box)
NS = 8  # state columns


def capacity(k: int) -> tuple[int, int, int]:
    """Local-array capacity (points, edges, surface voxels) of tier k: tier 0 doubled k times."""
    return PC << k, EC << k, SC << k
F64_1 = ti.types.ndarray(dtype=ti.f64, ndim=1)
I32_1 = ti.types.ndarray(dtype=ti.i32, ndim=1)


@ti.func
def _qpt(qf: ti.template(), q, k):
    return vec2(qf[4 * q + k, 0], qf[4 * q + k, 1])


@ti.func
def _qvel(qf: ti.template(), q, k):
    return vec2(qf[4 * q + k, 2], qf[4 * q + k, 3])


@ti.func
def _resolve(fcol: ti.template(), qf: ti.template(), qi: ti.template(), m, r, scale):
    """Contacts of quad m's corner points inside quad r (evogym `resolve_boxel_collisions`).

    Quads live in local scratch: qf[4q + k] = (x, y, vx_true, vy_true) and qi[4q + k] = (point
    id, side k is open) of corner k. Forces go to fcol[2 id : 2 id + 2] for dynamic points
    (id >= 0); terrain points (id < 0) are fixed and their share is dropped, as evogym discards
    the update of fixed points.
    """
    lo = ti.min(ti.min(_qpt(qf, r, 0), _qpt(qf, r, 1)), ti.min(_qpt(qf, r, 2), _qpt(qf, r, 3))) \
        - C.BOX_MARGIN
    hi = ti.max(ti.max(_qpt(qf, r, 0), _qpt(qf, r, 1)), ti.max(_qpt(qf, r, 2), _qpt(qf, r, 3))) \
        + C.BOX_MARGIN
    for i in range(4):
        pid = qi[4 * m + i, 0]
        p = _qpt(qf, m, i)
        # corners outside r's box cannot be inside r; then corners shared with r
        candidate = lo[0] <= p[0] and p[0] <= hi[0] and lo[1] <= p[1] and p[1] <= hi[1]
        if candidate and pid >= 0:
            for j in range(4):
                if qi[4 * r + j, 0] == pid:
                    candidate = False
        inside = False
        if candidate:  # (Taichi's `and` does not short-circuit)
            inside = _point_in_quad(p, _qpt(qf, r, 0), _qpt(qf, r, 1), _qpt(qf, r, 2),
                                    _qpt(qf, r, 3))
        if inside:
            s1 = 0 if i < 2 else 2
            s2 = 3 if (i == 0 or i == 3) else 1
            m1a = _qpt(qf, m, s1)
            m1b = _qpt(qf, m, (s1 + 1) % 4)
            if s1 >= 2 and qi[4 * m + s1, 1] == 0:
                m1a, m1b = m1b, m1a
            m2a = _qpt(qf, m, s2)
            m2b = _qpt(qf, m, (s2 + 1) % 4)
            if s2 >= 2 and qi[4 * m + s2, 1] == 0:
                m2a, m2b = m2b, m2a
            best = -1
            best_d = 0.0
            for s in range(4):
                if qi[4 * r + s, 1] != 0:
                    ra = _qpt(qf, r, s)
                    rb = _qpt(qf, r, (s + 1) % 4)
                    if _intersects(m1a, m1b, ra, rb) or _intersects(m2a, m2b, ra, rb):
                        d = _dist_point_edge(p, ra, rb)
                        if best < 0 or d < best_d:
                            best = s
                            best_d = d
            if best >= 0:
                ka = best
                kb = (best + 1) % 4
                slope = _qpt(qf, r, kb) - _qpt(qf, r, ka)
                normal = _normalized(vec2(-slope[1], slope[0]))
                nf = normal * C.CONTACT_K * (C.CONTACT_OFFSET + best_d)
                un = _normalized(normal)
                vp = _qvel(qf, m, i)
                va = _qvel(qf, r, ka)
                vb = _qvel(qf, r, kb)
                damp_p = un * (-1.0) * (un[0] * vp[0] + un[1] * vp[1]) * C.CONTACT_VEL_DAMPING
                damp_a = un * (un[0] * va[0] + un[1] * va[1]) * C.CONTACT_VEL_DAMPING
                damp_b = un * (un[0] * vb[0] + un[1] * vb[1]) * C.CONTACT_VEL_DAMPING
                ut = _normalized(normal)
                ut = vec2(-ut[1], ut[0])
                proj = ut[0] * vp[0] + ut[1] * vp[1]
                mag = ti.sqrt(nf[0] * nf[0] + nf[1] * nf[1])
                if proj < 0:
                    proj = -proj
                    ut = -ut
                fric = (C.CONTACT_FRICTION * ut * (-1.0) * C.FRICTION_DYN * mag
                        * portable.tanh(proj / (C.FRICTION_DYN * mag)))
                if pid >= 0:
                    fp = scale * (nf + damp_p + fric)
                    fcol[2 * pid] += fp[0]
                    fcol[2 * pid + 1] += fp[1]
                ia = qi[4 * r + ka, 0]
                if ia >= 0:
                    fa = scale * (nf / 2 + damp_a / 2 + fric / 2)
                    fcol[2 * ia] -= fa[0]
                    fcol[2 * ia + 1] -= fa[1]
                ib = qi[4 * r + kb, 0]
                if ib >= 0:
                    fb = scale * (nf / 2 + damp_b / 2 + fric / 2)
                    fcol[2 * ib] -= fb[0]
                    fcol[2 * ib + 1] -= fb[1]


@ti.func
def _load_quad(pos: ti.template(), vt: ti.template(), sv: ti.template(), qf: ti.template(),
               qi: ti.template(), q, i):
    """Copy surface voxel list entry i (corners and open sides in sv) into scratch quad q."""
    for k in range(4):
        p = sv[8 * i + k]
        qi[4 * q + k, 0] = p
        qi[4 * q + k, 1] = sv[8 * i + 4 + k]
        qf[4 * q + k, 0] = pos[2 * p]
        qf[4 * q + k, 1] = pos[2 * p + 1]
        qf[4 * q + k, 2] = vt[2 * p]
        qf[4 * q + k, 3] = vt[2 * p + 1]


@ti.func
def _robot_pair_acts(pos: ti.template(), sv: ti.template(), box: ti.template(), i, j):
    """Whether `_resolve` can act between surface voxels i and j: some corner of one, not shared
    with the other, lies in the other's widened box (elsewhere both resolves do nothing)."""
    hit = False
    for d in range(2):
        m = i if d == 0 else j
        r = j if d == 0 else i
        for k in range(4):
            p = sv[8 * m + k]
            if _in_box(pos[2 * p], pos[2 * p + 1], box[4 * r], box[4 * r + 1], box[4 * r + 2],
                       box[4 * r + 3]):
                shared = False
                for q in range(4):
                    if sv[8 * r + q] == p:
                        shared = True
                if not shared:
                    hit = True
    return hit


@ti.func
def _terrain_pair_acts(pos: ti.template(), sv: ti.template(), box: ti.template(),
                       ter_f: ti.template(), i, t):
    """`_robot_pair_acts` for surface voxel i and terrain voxel t (no shared corners)."""
    hit = False
    for k in range(4):
        p = sv[8 * i + k]
        if _in_box(pos[2 * p], pos[2 * p + 1], ter_f[t, 8], ter_f[t, 9], ter_f[t, 10], ter_f[t, 11]):
            hit = True
        if _in_box(ter_f[t, 2 * k], ter_f[t, 2 * k + 1], box[4 * i], box[4 * i + 1], box[4 * i + 2],
                   box[4 * i + 3]):
            hit = True
    return hit


@ti.func
def _sort_along(n_surf, box: ti.template(), order: ti.template(), rank: ti.template(), a):
    """Insertion sort of `order` (surface voxels) by their box's low edge along axis a (box
    column: 0 x, 2 y), then `rank` = each voxel's place in it. The order of the last substep is
    nearly right, so this is ~n steps."""
    for k in range(1, n_surf):
        v = order[k]
        x = box[4 * v + a]
        m = k
        while m > 0:
            u = order[m - 1]
            if box[4 * u + a] > x:
                order[m] = u
                m -= 1
            else:
                break
        order[m] = v
    for k in range(n_surf):
        rank[order[k]] = k


@ti.func
def _near(n_surf, w, box: ti.template(), order: ti.template(), a):
    """Summed over the voxels (sorted along axis a), the voxels whose low edge lies within w (the
    widest box) of theirs, both sides: about twice the pairs the sweep tests, against the plain
    loop's n^2 / 2."""
    total = 0
    lo = 0
    hi = 0
    for k in range(n_surf):
        x = box[4 * order[k] + a]
        while box[4 * order[lo] + a] < x - w:
            lo += 1
        while hi < n_surf:
            if box[4 * order[hi] + a] > x + w:
                break
            hi += 1
        total += hi - lo
    return total


@ti.func
def _choose_sweep(n_surf, wx, wy, box: ti.template(), order: ti.template(), rank: ti.template(),
                  sweep: ti.template(), always: ti.template()):
    """At the env step's first substep: sweep[0] = 1 and sweep[1] = the axis (box column 0 x, 2
    y) along which the sweep tests fewest pairs, if that is at least SWEEP_RATIO times fewer than
    the plain loop's (or `always`), else sweep[0] = 0. Long, flat worlds pass (BridgeWalker's
    bridge ~19 along x, Climber-v1's wall ~21 along y); compact bodies do not (16x16: ~5.6)."""
    _sort_along(n_surf, box, order, rank, 2)
    near_y = _near(n_surf, wy, box, order, 2)
    _sort_along(n_surf, box, order, rank, 0)
    near_x = _near(n_surf, wx, box, order, 0)
    sweep[0] = 1
    sweep[1] = 0
    best = near_x
    if near_y < near_x:
        sweep[1] = 2
        best = near_y
        _sort_along(n_surf, box, order, rank, 2)
    if ti.static(not always):
        if best * SWEEP_RATIO > n_surf * n_surf:
            sweep[0] = 0


@ti.func
def _candidates(i, n_surf, w, box: ti.template(), order: ti.template(), rank: ti.template(),
                cand: ti.template(), a, skin):
    """Surface voxels j > i whose box may overlap voxel i's along axis a (box column 0 x, 2 y),
    ascending (into cand; returns their number): those whose low edge lies in [lo_i - w - skin -
    1e-6, hi_i + skin], found from i's place in `order`. A superset of the j whose boxes lie
    within skin of i's (w is the widest box along a), so the box tests that follow see every pair
    the plain loop over j > i would, in its order (skin = 0: the overlapping ones)."""
    lo = box[4 * i + a] - w - skin - 1e-6
    hi = box[4 * i + a + 1] + skin
    nc = 0
    k = rank[i] - 1
    while k >= 0:
        j = order[k]
        if box[4 * j + a] < lo:
            break
        if j > i:
            cand[nc] = j
            nc += 1
        k -= 1
    k = rank[i] + 1
    while k < n_surf:
        j = order[k]
        if box[4 * j + a] > hi:
            break
        if j > i:
            cand[nc] = j
            nc += 1
        k += 1
    for c in range(1, nc):
        v = cand[c]
        m = c
        while m > 0:
            if cand[m - 1] > v:
                cand[m] = cand[m - 1]
                m -= 1
            else:
                break
        cand[m] = v
    return nc


@ti.func
def _contacts(b, n_pts, counts: ti.template(), pos: ti.template(), vt: ti.template(),
              fcol: ti.template(), box: ti.template(), sv: ti.template(), sm: ti.template(),
              ter_f: ti.template(), ter_i: ti.template(), ter_grid: ti.template(),
              order: ti.template(), rank: ti.template(), cand: ti.template(), sweep: ti.template(),
              sweep_mode: ti.template(), ter_top, nbr: ti.template(), nstart: ti.template(),
              refbox: ti.template(), plist: ti.template(), pair_list: ti.template()):
    """Recompute AABBs and contact forces (into fcol); return evogym's robot self-collision count
    (-1 when a coordinate is not finite). Surface voxel i has corners sv[8i:8i+4], open sides
    sv[8i+4:8i+8] and object, row, col sm[4i:4i+3]. Pairs of surface voxels are those with
    overlapping boxes, in the order of the loop over i < j (evogym's), found by the plain loop or
    by sweep and prune along x or y as `sweep_mode` says (`order`, `rank`, `cand`, `sweep`:
    scratch), or from the pair list (see SKIN) while it holds: plist[0] = 1 when nbr[nstart[i]:
    nstart[i + 1]] lists voxel i's partners j > i within SKIN of its box when the boxes were
    refbox."""
    n_surf = counts[b, N_SURF]
    n_surf_robot = counts[b, N_SURF_ROBOT]
    for i in range(2 * n_pts):
        fcol[i] = 0.0
    finite = True
    wx = 0.0  # the widest box along x and along y
    wy = 0.0
    for i in range(n_surf):
        p0 = sv[8 * i]
        x0 = pos[2 * p0]
        y0 = pos[2 * p0 + 1]
        x1 = x0
        y1 = y0
        for k in range(1, 4):
            p = sv[8 * i + k]
            x = pos[2 * p]
            y = pos[2 * p + 1]
            x0 = ti.min(x0, x)
            x1 = ti.max(x1, x)
            y0 = ti.min(y0, y)
            y1 = ti.max(y1, y)
        box[4 * i] = x0
        box[4 * i + 1] = x1
        box[4 * i + 2] = y0
        box[4 * i + 3] = y1
        wx = ti.max(wx, x1 - x0)
        wy = ti.max(wy, y1 - y0)
        if not (ti.abs(x0) < 1e30 and ti.abs(x1) < 1e30 and ti.abs(y0) < 1e30
                and ti.abs(y1) < 1e30):
            finite = False
    count = 0
    if finite:
        qf = ti.Matrix.zero(ti.f64, 8, 4)
        qi = ti.Matrix.zero(ti.i32, 8, 2)
        gw = ter_grid.shape[0]
        gh = ter_grid.shape[1]
        use_list = False
        listing = ti.static(pair_list == LIST_ALWAYS) or n_surf >= LIST_MIN
        if ti.static("pairs" not in PROFILE_SKIP and pair_list != LIST_OFF):
            if plist[0] == 1:
                moved = 0.0
                for k in range(4 * n_surf):
                    moved = ti.max(moved, ti.abs(box[k] - refbox[k]))
                use_list = 2.0 * moved < SKIN - SKIN_SLACK
        if ti.static(sweep_mode != SWEEP_OFF):
            # sweep[0]: -1 undecided (the env step's first substep), 0 plain loop, 1 sweep along
            # axis sweep[1]
            if n_surf < SWEEP_MIN and ti.static(sweep_mode == SWEEP_AUTO):
                sweep[0] = 0
            if sweep[0] < 0:
                _choose_sweep(n_surf, wx, wy, box, order, rank, sweep,
                              ti.static(sweep_mode == SWEEP_ALWAYS))
            elif sweep[0] == 1 and not use_list:
                _sort_along(n_surf, box, order, rank, sweep[1])
        n_list = 0  # building the list: its length, and whether it fits
        fits = True
        for i in range(n_surf):
            loaded = False
            bx0 = box[4 * i]
            bx1 = box[4 * i + 1]
            by0 = box[4 * i + 2]
            by1 = box[4 * i + 3]
            if ti.static("pairs" not in PROFILE_SKIP):
                # i's partners j, ascending: j = c for c in [lo, hi) (the plain loop), or listed
                # at nbr[c] (the pair list) or at cand[c] (sweep and prune)
                lo = i + 1
                hi = n_surf
                src = 0
                if ti.static(pair_list != LIST_OFF):
                    if use_list:
                        lo = nstart[i]
                        hi = nstart[i + 1]
                        src = 1
                    else:
                        nstart[i] = n_list
                if ti.static(sweep_mode != SWEEP_OFF):
                    if sweep[0] == 1 and not use_list:
                        w = wx if sweep[1] == 0 else wy
                        lo = 0
                        hi = _candidates(i, n_surf, w, box, order, rank, cand, sweep[1],
                                         SKIN if ti.static(pair_list != LIST_OFF) else 0.0)
                        src = 2
                for c in range(lo, hi):
                    j = c
                    if ti.static(pair_list != LIST_OFF):
                        if src == 1:
                            j = nbr[c]
                    if ti.static(sweep_mode != SWEEP_OFF):
                        if src == 2:
                            j = cand[c]
                    if ti.static(pair_list != LIST_OFF):
                        if src != 1 and listing and not (
                                bx0 > box[4 * j + 1] + SKIN or bx1 + SKIN < box[4 * j]
                                or by0 > box[4 * j + 3] + SKIN or by1 + SKIN < box[4 * j + 2]):
                            if n_list < nbr.n:
                                nbr[n_list] = j
                                n_list += 1
                            else:
                                fits = False
                    if not (bx0 > box[4 * j + 1] or bx1 < box[4 * j]
                            or by0 > box[4 * j + 3] or by1 < box[4 * j + 2]):
                        same = sm[4 * i] == sm[4 * j]
                        scale = 2.0 if same else 1.0
                        if same and i < n_surf_robot and j < n_surf_robot:
                            dr = ti.abs(sm[4 * i + 1] - sm[4 * j + 1])
                            dc = ti.abs(sm[4 * i + 2] - sm[4 * j + 2])
                            if dr > 1 or dc > 1:  # evogym's self-collision count
                                count += 2
                        if _robot_pair_acts(pos, sv, box, i, j):
                            if not loaded:
                                _load_quad(pos, vt, sv, qf, qi, 0, i)
                                loaded = True
                            _load_quad(pos, vt, sv, qf, qi, 1, j)
                            for d in range(2):
                                _resolve(fcol, qf, qi, d, 1 - d, scale)
            # no terrain box reaches above ter_top, so no terrain test can pass for a box above it
            if by0 <= ter_top:
                gx0 = ti.max(0, ti.cast(ti.ceil(bx0 / C.CELL - 1.0 - 1e-6), ti.i32))
                gx1 = ti.min(gw - 1, ti.cast(ti.floor(bx1 / C.CELL + 1e-6), ti.i32))
                gy0 = ti.max(0, ti.cast(ti.ceil(by0 / C.CELL - 1.0 - 1e-6), ti.i32))
                gy1 = ti.min(gh - 1, ti.cast(ti.floor(by1 / C.CELL + 1e-6), ti.i32))
                for gx in range(gx0, gx1 + 1 if ti.static("terrain" not in PROFILE_SKIP) else gx0):
                    for gy in range(gy0, gy1 + 1):
                        t = ter_grid[gx, gy]
                        if t >= 0:
                            acts = False
                            if not (bx0 > ter_f[t, 9] or bx1 < ter_f[t, 8]
                                    or by0 > ter_f[t, 11] or by1 < ter_f[t, 10]):
                                acts = _terrain_pair_acts(pos, sv, box, ter_f, i, t)
                            if acts:
                                if not loaded:
                                    _load_quad(pos, vt, sv, qf, qi, 0, i)
                                    loaded = True
                                for k in range(4):
                                    qf[4 + k, 0] = ter_f[t, 2 * k]
                                    qf[4 + k, 1] = ter_f[t, 2 * k + 1]
                                    qf[4 + k, 2] = 0.0
                                    qf[4 + k, 3] = 0.0
                                    qi[4 + k, 0] = -1
                                    qi[4 + k, 1] = ter_i[t, k]
                                for d in range(2):
                                    _resolve(fcol, qf, qi, d, 1 - d, 1.0)
        if ti.static("pairs" not in PROFILE_SKIP and pair_list != LIST_OFF):
            if not use_list:
                nstart[n_surf] = n_list
                plist[0] = 1 if fits and listing else 0
                for k in range(4 * n_surf):
                    refbox[k] = box[k]
                    if not ti.abs(box[k]) < REF_MAX:
                        plist[0] = 0
    if not finite:
        count = -1
    return count


@ti.func
def _add_to_ends(n_edges, v: ti.template(), ea: ti.template(), eb: ti.template(), fx: ti.template(),
                 fy: ti.template(), skip_zero: ti.template()):
    """v[a] -= (fx[e], fy[e]) and v[b] += (fx[e], fy[e]) for every edge e = (a, b), in evogym's
    order: Eigen's `v(:, a_index) -= f` then `v(:, b_index) += f`, i.e. every edge's first end in
    edge order, then every second end (one interleaved pass rounds differently wherever a point is
    the first end of one edge and the second of an earlier one). `skip_zero`: leave out zero
    vectors, which change nothing (x - 0.0 and x + 0.0 are x; only evogym's -0.0 + 0.0 gives +0.0,
    a sign of zero)."""
    for half in ti.static(range(2)):
        for e in range(n_edges):
            x = fx[e]
            y = fy[e]
            if ti.static(not skip_zero) or x != 0.0 or y != 0.0:
                if ti.static(half == 0):
                    a = ea[e]
                    v[2 * a] -= x
                    v[2 * a + 1] -= y
                else:
                    q = eb[e]
                    v[2 * q] += x
                    v[2 * q + 1] += y


@ti.func
def _rk4(n_pts, n_edges, pos: ti.template(), vel: ti.template(), fcol: ti.template(),
         xs: ti.template(), vs: ti.template(), frc: ti.template(), adx: ti.template(),
         adv: ti.template(), leq: ti.template(), ea: ti.template(), eb: ti.template(),
         ek: ti.template(), egoal: ti.template(), sfx: ti.template(), sfy: ti.template()):
    """Rest-length update, then classical RK4 on (pos, vel) with dt = 1e-4 (springs, drag,
    gravity, ground plane, contact forces frozen across the stages); x, y interleaved. The 4
    stages are unrolled; stage 0 (stage state = substep state) also sets the current rest lengths,
    and each stage's point loop prepares the next stage's state."""
    for i in range(2 * n_pts):
        xs[i] = pos[i]
        vs[i] = vel[i]
    for stage in ti.static(range(4)):
        for i in range(2 * n_pts):
            frc[i] = 0.0
        # the springs' forces in a loop without stores to shared points, which LLVM vectorises
        # (square roots and divisions 4 at a time), then their scatter in evogym's order
        for e in range(n_edges):
            a = ea[e]
            q = eb[e]
            dx = xs[2 * a] - xs[2 * q]
            dy = xs[2 * a + 1] - xs[2 * q + 1]
            dist = ti.sqrt(dx * dx + dy * dy)
            if ti.static(stage == 0):
                leq[e] = dist + (egoal[e] - dist) * C.REST_CONVERGENCE
            mag = (dist - leq[e]) * ek[e] / dist
            sfx[e] = dx * mag
            sfy[e] = dy * mag
        _add_to_ends(n_edges, frc, ea, eb, sfx, sfy, False)
        # the ground plane's force (a branch and a tanh call) keeps LLVM from vectorising the
        # point loop, so that loop has a second copy without it for stages with no point below
        below = 0
        for p in range(n_pts):
            if xs[2 * p + 1] < 0:
                below += 1
        for ground in ti.static((False, True)):
            if (below > 0) == ground:
                for p in range(n_pts):
                    vx = vs[2 * p]
                    vy = vs[2 * p + 1]
                    fx = frc[2 * p] + vx * (-C.VISCOUS_DRAG)
                    fy = frc[2 * p + 1] + vy * (-C.VISCOUS_DRAG)
                    fy += C.POINT_MASS * (-C.GRAVITY)
                    fx += fcol[2 * p]
                    fy += fcol[2 * p + 1]
                    if ti.static(ground):
                        y = xs[2 * p + 1]
                        if y < 0:
                            normal = y * (-C.GROUND_K)
                            fy += normal
                            fx += ((-10.0 * C.FRICTION_DYN) * normal
                                   * portable.tanh(vx * normal * C.FRICTION_DYN))
                    acc = vec2(fx / C.POINT_MASS, fy / C.POINT_MASS)
                    for d in ti.static(range(2)):
                        i = 2 * p + d
                        kx = vs[i] * C.DT
                        kv = acc[d] * C.DT
                        if ti.static(stage == 0):
                            adx[i] = kx
                            adv[i] = kv
                        elif ti.static(stage < 3):
                            adx[i] += 2 * kx
                            adv[i] += 2 * kv
                        else:
                            adx[i] += kx
                            adv[i] += kv
                        if ti.static(stage < 3):
                            h = 0.5 if ti.static(stage < 2) else 1.0
                            xs[i] = pos[i] + kx * h
                            vs[i] = vel[i] + kv * h
    for i in range(2 * n_pts):
        pos[i] += adx[i] / 6
        vel[i] += adv[i] / 6


@ti.func
def _hold_fixed(b, counts: ti.template(), lists: ti.template(), pos: ti.template(),
                vel: ti.template(), pl: ti.template()):
    """Put the fixed points back where they were at the start of the substep (pos_last), at rest:
    the same bits as evogym's discarded update (its RK4 increment and edge corrections of fixed
    points are zeroed). Their forces and intermediate RK4 stages are computed as for any point,
    as in evogym, since the stages feed the springs of their free neighbours."""
    for i in range(counts[b, N_FIXED]):
        p = lists[b, i, 2]
        for d in ti.static(range(2)):
            pos[2 * p + d] = pl[2 * p + d]
            vel[2 * p + d] = 0.0


@ti.func
def _constraints(b, n_edges, counts: ti.template(), ea: ti.template(), eb: ti.template(),
                 erest: ti.template(), vox_i: ti.template(), lists: ti.template(),
                 pos: ti.template(), vel: ti.template(), pl: ti.template(), ccx: ti.template(),
                 ccy: ti.template()):
    """Pass 1: Jacobi projection of every edge into +-25 % (fixed points stay: their position
    this substep is still pos_last), applied in evogym's order (`_add_to_ends`); pass 2: rigid
    voxels into +-3 % (evogym's rigid pass ignores the fixed flag)."""
    for e in range(n_edges):
        a = ea[e]
        q = eb[e]
        dx = pos[2 * a] - pos[2 * q]
        dy = pos[2 * a + 1] - pos[2 * q + 1]
        dist = ti.sqrt(dx * dx + dy * dy)
        rest = erest[e]
        stress = dist / rest
        cx = 0.0
        cy = 0.0
        if stress > _HI:
            m = (dist - rest * _HI) / (dist * 2)
            cx += dx * m
            cy += dy * m
        if stress < _LO:
            m = (dist - rest * _LO) / (dist * 2)
            cx += dx * m
            cy += dy * m
        ccx[e] = cx * 0.8
        ccy[e] = cy * 0.8
    _add_to_ends(n_edges, pos, ea, eb, ccx, ccy, True)
    _hold_fixed(b, counts, lists, pos, vel, pl)
    for i in range(counts[b, N_RIGID]):
        v = lists[b, i, 1]
        for k in ti.static(range(4)):
            a = vox_i[b, v, V_PTS + k]
            q = vox_i[b, v, V_PTS + (k + 1) % 4]
            dx = pos[2 * a] - pos[2 * q]
            dy = pos[2 * a + 1] - pos[2 * q + 1]
            dist = ti.sqrt(dx * dx + dy * dy)
            stress = dist / C.MAIN_REST
            ox = 0.0
            oy = 0.0
            if stress >= _HI_R:
                m = (dist - C.MAIN_REST * _HI_R) / (dist * 2)
                ox += dx * m
                oy += dy * m
            if stress <= _LO_R:
                m = (dist - C.MAIN_REST * _LO_R) / (dist * 2)
                ox += dx * m
                oy += dy * m
            pos[2 * a] -= ox * 0.5
            pos[2 * a + 1] -= oy * 0.5
            pos[2 * q] += ox * 0.5
            pos[2 * q + 1] += oy * 0.5


@ti.func
def _step_world(b, counts: ti.template(), state: ti.template(), edge_i: ti.template(),
                      edge_f: ti.template(), vox_i: ti.template(), lists: ti.template(),
                      actions: ti.template(), ter_f: ti.template(), ter_i: ti.template(),
                      ter_grid: ti.template(), n_sub, P, E, pc: ti.template(), ec: ti.template(),
                      sc: ti.template(), sweep_mode: ti.template(), pair_list: ti.template()):
    """One env step of world b (see `step_kernel`), with local arrays of capacity pc, ec, sc."""
    if counts[b, STATUS] == RUNNING:
        n_pts = counts[b, N_PTS]
        n_edges = counts[b, N_EDGES]
        so = b * P * NS
        eio = b * E * 4
        efo = b * E * N_EDGE_F
        pos = ti.Vector.zero(ti.f64, 2 * pc)
        vel = ti.Vector.zero(ti.f64, 2 * pc)
        pl = ti.Vector.zero(ti.f64, 2 * pc)  # pos_last
        vt = ti.Vector.zero(ti.f64, 2 * pc)  # vel_true
        xs = ti.Vector.zero(ti.f64, 2 * pc)
        vs = ti.Vector.zero(ti.f64, 2 * pc)
        frc = ti.Vector.zero(ti.f64, 2 * pc)
        fcol = ti.Vector.zero(ti.f64, 2 * pc)
        adx = ti.Vector.zero(ti.f64, 2 * pc)
        adv = ti.Vector.zero(ti.f64, 2 * pc)
        leq = ti.Vector.zero(ti.f64, ec)
        ea = ti.Vector.zero(ti.i32, ec)  # the springs' ends, stiffness, goal and rest, contiguous
        eb = ti.Vector.zero(ti.i32, ec)
        ek = ti.Vector.zero(ti.f64, ec)
        egoal = ti.Vector.zero(ti.f64, ec)
        erest = ti.Vector.zero(ti.f64, ec)
        for e in range(n_edges):
            ea[e] = edge_i[eio + 4 * e]
            eb[e] = edge_i[eio + 4 * e + 1]
            ek[e] = edge_f[efo + N_EDGE_F * e + E_K]
            erest[e] = edge_f[efo + N_EDGE_F * e + E_REST]
            egoal[e] = edge_f[efo + N_EDGE_F * e + E_GOAL]  # the rest length, unless driven:
            d0 = edge_i[eio + 4 * e + 2]
            if d0 >= 0:  # the mean of its actuators' targets times its rest length
                d1 = edge_i[eio + 4 * e + 3]
                total = actions[b, d0]
                cnt = 1.0
                if d1 >= 0:
                    total += actions[b, d1]
                    cnt = 2.0
                egoal[e] = total * (erest[e] / cnt)
        ccx = ti.Vector.zero(ti.f64, ec)
        ccy = ti.Vector.zero(ti.f64, ec)
        box = ti.Vector.zero(ti.f64, 4 * sc)
        sv = ti.Vector.zero(ti.i32, 8 * sc)
        sm = ti.Vector.zero(ti.i32, 4 * sc)
        order = ti.Vector.zero(ti.i32, sc)  # sweep and prune scratch (see _contacts)
        rank = ti.Vector.zero(ti.i32, sc)
        cand = ti.Vector.zero(ti.i32, sc)
        nbr = ti.Vector.zero(ti.i32, LIST_PER_VOXEL * sc)  # the pair list (see SKIN)
        nstart = ti.Vector.zero(ti.i32, sc + 1)
        refbox = ti.Vector.zero(ti.f64, 4 * sc)
        plist = ti.Vector([0])
        for i in range(counts[b, N_SURF]):
            order[i] = i
        sweep = ti.Vector([-1, 0])  # see _contacts
        for i in range(counts[b, N_SURF]):
            v = lists[b, i, 0]
            for k in ti.static(range(4)):
                sv[8 * i + k] = vox_i[b, v, V_PTS + k]
                sv[8 * i + 4 + k] = vox_i[b, v, V_OPEN + k]
            sm[4 * i] = vox_i[b, v, V_OBJ]
            sm[4 * i + 1] = vox_i[b, v, V_ROW]
            sm[4 * i + 2] = vox_i[b, v, V_COL]
        for p in range(n_pts):
            for d in ti.static(range(2)):
                pos[2 * p + d] = state[so + NS * p + d]
                vel[2 * p + d] = state[so + NS * p + 2 + d]
                pl[2 * p + d] = state[so + NS * p + 4 + d]
                vt[2 * p + d] = state[so + NS * p + 6 + d]
        ter_top = ter_f[0, 11]  # the highest top of a terrain voxel's box
        for t in range(1, ter_f.shape[0]):
            ter_top = ti.max(ter_top, ter_f[t, 11])
        status = RUNNING
        for _ in range(n_sub):
            if status == RUNNING:
                count = 0
                if ti.static("contacts" not in PROFILE_SKIP):
                    count = _contacts(b, n_pts, counts, pos, vt, fcol, box, sv, sm, ter_f,
                                      ter_i, ter_grid, order, rank, cand, sweep,
                                      sweep_mode, ter_top, nbr, nstart, refbox, plist,
                                      pair_list)
                if count < 0:
                    status = NONFINITE
                else:
                    _rk4(n_pts, n_edges, pos, vel, fcol, xs, vs, frc, adx, adv, leq, ea, eb, ek,
                         egoal, ccx, ccy)
                    _hold_fixed(b, counts, lists, pos, vel, pl)
                    if ti.static("constraints" not in PROFILE_SKIP):
                        _constraints(b, n_edges, counts, ea, eb, erest, vox_i, lists, pos, vel,
                                     pl, ccx, ccy)
                    for i in range(2 * n_pts):
                        vt[i] = (pos[i] - pl[i]) / C.DT
                        pl[i] = pos[i]
                    if count > counts[b, N_SURF_ROBOT]:
                        status = UNSTABLE
        if status == RUNNING:
            for i in range(2 * n_pts):
                if not (ti.abs(pos[i]) < 1e30 and ti.abs(vel[i]) < 1e30):
                    status = NONFINITE
        if status == RUNNING:
            for p in range(n_pts):
                for d in ti.static(range(2)):
                    state[so + NS * p + d] = pos[2 * p + d]
                    state[so + NS * p + 2 + d] = vel[2 * p + d]
                    state[so + NS * p + 4 + d] = pl[2 * p + d]
                    state[so + NS * p + 6 + d] = vt[2 * p + d]
        else:
            # evogym keeps the last snapshot: the step never happened for observers
            for p in range(n_pts):
                for d in ti.static(range(2)):
                    state[so + NS * p + 4 + d] = state[so + NS * p + d]
                    state[so + NS * p + 6 + d] = 0.0
            counts[b, STATUS] = status


@ti.kernel
def step_kernel(counts: I32_2, state: F64_1, edge_i: I32_1, edge_f: F64_1, vox_i: I32_3,
                lists: I32_3, actions: F64_2, ter_f: F64_2, ter_i: I32_2, ter_grid: I32_2,
                n_sub: ti.i32, P: ti.i32, E: ti.i32, pc: ti.template(), ec: ti.template(),
                sc: ti.template(), sweep_mode: ti.template(), pair_list: ti.template(),
                block: ti.template()):
    """One env step (n_sub substeps) of every running world, worlds in parallel (`block` worlds
    per thread block: 1 on a CPU, where Taichi deals blocks to its threads, a warp's multiple on
    a GPU). state, edge_i and edge_f are flat views of the (B, P, 8), (B, E, 4) and (B, E, 4)
    arrays; every world fits the capacity (pc points, ec edges, sc surface voxels)."""
    ti.loop_config(block_dim=block)
    for b in range(counts.shape[0]):
        _step_world(b, counts, state, edge_i, edge_f, vox_i, lists, actions, ter_f, ter_i,
                          ter_grid, n_sub, P, E, pc, ec, sc, sweep_mode, pair_list)


@ti.kernel
def step_kernel_serial(counts: I32_2, state: F64_1, edge_i: I32_1, edge_f: F64_1, vox_i: I32_3,
                       lists: I32_3, actions: F64_2, ter_f: F64_2, ter_i: I32_2, ter_grid: I32_2,
                       n_sub: ti.i32, P: ti.i32, E: ti.i32, pc: ti.template(), ec: ti.template(),
                       sc: ti.template(), sweep_mode: ti.template(), pair_list: ti.template()):
    """`step_kernel` on the calling thread: for single-threaded processes, where handing the loop
    to Taichi's thread pool costs ~0.15 ms per launch (measured on the 2-vCPU VM)."""
    ti.loop_config(serialize=True)
    for b in range(counts.shape[0]):
        _step_world(b, counts, state, edge_i, edge_f, vox_i, lists, actions, ter_f, ter_i,
                          ter_grid, n_sub, P, E, pc, ec, sc, sweep_mode, pair_list)
