"""Broad phase: which pairs of surface voxels (and voxel-terrain pairs) the narrow phase tests.

Contact pairs by sweep and prune along x or y: the same pairs in the same order as the plain
loop, so results do not depend on it. A kernel's `sweep_mode` (compile time): SWEEP_OFF the plain
loop only (compact bodies, where the sweep's code alone cost ~5 % at 16x16); SWEEP_AUTO per world
and env step, where it has at least SWEEP_MIN surface voxels and `choose_sweep` finds an axis
that pays (long worlds such as BridgeWalker's: +40 %); SWEEP_ALWAYS everywhere (tests).

Pair lists (Verlet lists with a skin): a substep that tests every pair also records the pairs
whose boxes, each widened by SKIN, overlap. Later substeps of the env step test only those, as
long as no box edge has moved by SKIN / 2 since: a pair left out had a gap above SKIN and each
of its boxes moved less than SKIN / 2, so its box test would fail. Exact, not approximate:
the same pairs act, in the same order (the slack and the coordinate limit follow the real type:
`layout.Tolerances`).
"""

from tsim.backend.runtime import ti
from tsim.kernels import layout as L
from tsim.kernels.geometry import in_box

SWEEP_OFF, SWEEP_AUTO, SWEEP_ALWAYS = 0, 1, 2
SWEEP_MIN = 24
SWEEP_RATIO = 8
SKIN = 0.05  # half a voxel: a 12x12 body lists ~181 of its 3,583 pairs (158 overlap)
# A kernel's `pair_list` (compile time): LIST_OFF never (the kernel that small bodies run: the
# list's code alone cost them 2-5 %), LIST_AUTO in worlds with at least LIST_MIN surface voxels,
# LIST_ALWAYS in every world (tests)
LIST_OFF, LIST_AUTO, LIST_ALWAYS = 0, 1, 2
LIST_MIN = 24
LIST_PER_VOXEL = 8  # list capacity per surface voxel (bodies and bridges need ~2; full: no list)


@ti.func
def robot_pair_acts(pos: ti.template(), sv: ti.template(), box: ti.template(), i, j):
    """Whether `narrowphase.resolve` can act between surface voxels i and j: some corner of one,
    not shared with the other, lies in the other's widened box (elsewhere both resolves do
    nothing)."""
    hit = False
    for d in range(2):
        m = i if d == 0 else j
        r = j if d == 0 else i
        for k in range(4):
            p = sv[8 * m + k]
            if in_box(pos[2 * p], pos[2 * p + 1], box[4 * r], box[4 * r + 1], box[4 * r + 2],
                      box[4 * r + 3]):
                shared = False
                for q in range(4):
                    if sv[8 * r + q] == p:
                        shared = True
                if not shared:
                    hit = True
    return hit


@ti.func
def terrain_pair_acts(pos: ti.template(), sv: ti.template(), box: ti.template(),
                      ter_f: ti.template(), i, t):
    """`robot_pair_acts` for surface voxel i and terrain voxel t (no shared corners)."""
    hit = False
    for k in range(4):
        p = sv[8 * i + k]
        if in_box(pos[2 * p], pos[2 * p + 1], ter_f[t, 8], ter_f[t, 9], ter_f[t, 10], ter_f[t, 11]):
            hit = True
        if in_box(ter_f[t, 2 * k], ter_f[t, 2 * k + 1], box[4 * i], box[4 * i + 1], box[4 * i + 2],
                  box[4 * i + 3]):
            hit = True
    return hit


@ti.func
def sort_along(n_surf, box: ti.template(), order: ti.template(), rank: ti.template(), a):
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
def near(n_surf, w, box: ti.template(), order: ti.template(), a):
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
def choose_sweep(n_surf, wx, wy, box: ti.template(), order: ti.template(), rank: ti.template(),
                 sweep: ti.template(), always: ti.template()):
    """At the env step's first substep: sweep[0] = 1 and sweep[1] = the axis (box column 0 x, 2
    y) along which the sweep tests fewest pairs, if that is at least SWEEP_RATIO times fewer than
    the plain loop's (or `always`), else sweep[0] = 0. Long, flat worlds pass (BridgeWalker's
    bridge ~19 along x, Climber-v1's wall ~21 along y); compact bodies do not (16x16: ~5.6)."""
    sort_along(n_surf, box, order, rank, 2)
    near_y = near(n_surf, wy, box, order, 2)
    sort_along(n_surf, box, order, rank, 0)
    near_x = near(n_surf, wx, box, order, 0)
    sweep[0] = 1
    sweep[1] = 0
    best = near_x
    if near_y < near_x:
        sweep[1] = 2
        best = near_y
        sort_along(n_surf, box, order, rank, 2)
    if ti.static(not always):
        if best * SWEEP_RATIO > n_surf * n_surf:
            sweep[0] = 0


@ti.func
def candidates(i, n_surf, w, box: ti.template(), order: ti.template(), rank: ti.template(),
               cand: ti.template(), a, skin):
    """Surface voxels j > i whose box may overlap voxel i's along axis a (box column 0 x, 2 y),
    ascending (into cand; returns their number): those whose low edge lies in [lo_i - w - skin -
    slack, hi_i + skin], found from i's place in `order`. A superset of the j whose boxes lie
    within skin of i's (w is the widest box along a), so the box tests that follow see every pair
    the plain loop over j > i would, in its order (skin = 0: the overlapping ones)."""
    lo = box[4 * i + a] - w - skin - ti.static(L.tol().sort_slack)
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


