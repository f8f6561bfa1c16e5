"""A substep's second half (integration, fixed points, constraints, snapshot) spread over a world's
L lanes: the lanes kernel's stages (tsim/backend/lanes.py; GPU and Vulkan only, issue #48 item 1).

`integrate.rk4`, `springs.spring_forces`, `constraints.constraints` and `step.move`, element by
element, with the elements dealt to lanes: point p and edge e to lane
p % L and e % L (`own`). Each phase ends at a barrier (`sync`), after which every lane reads
what the others wrote. Where the CPU's code scatters per-edge vectors to the edges' ends
(`springs.add_to_ends`), a point here gathers them over its incidence list (`incidence`): the
edges whose first end it is, ascending, then those whose second end it is, ascending. That is
the order in which the scatter adds into that point, so each point's sum is the same sum, the
same bits. The rigid voxels' pass moves corners that voxels share, in voxel order: it runs on
lane 0 alone, between barriers.

A scratch entry is updated as `x[i] = x[i] + v`, never `x[i] += v`: Taichi compiles an augmented
assignment to an array as an atomic add, which on the lanes kernel's shared or global arrays is a
compare-and-swap loop on SPIR-V (Taichi's SPIR-V code generator cannot make one for an f32 shared
array: "at_buffer failed"; with f64 ones lavapipe crashed) and an atomic on CUDA. Each entry here has
one writer, so the value is the same.

The per-element code is the CPU's own (`springs.edge_force`, `integrate.stage_start`,
`point_stage`, `stage_end`, `hold_point`, `constraints.edge_correction`, `rigid_voxels`,
`integrate.snapshot`): the serial kernels call it in loops over a world's elements, this module over a
lane's. Only the sums that the CPU scatters are gathered here. The CPU's kernels do not call this
module (Taichi's CPU backend has no block barrier); tests/tsim/backend/test_lanes.py compares the two on
every task.
"""

from tsim.backend.runtime import PROFILE_SKIP, ti
from tsim.kernels.constraints import edge_correction, rigid_voxels
from tsim.kernels.integrate import hold_point, point_stage, snapshot, stage_end, stage_start
from tsim.kernels.layout import N_FIXED, pairs
from tsim.kernels.springs import edge_force


def incidence_sizes(pc: int, ec: int) -> dict[str, int]:
    """A world's incidence lists (capacity pc points, ec edges; `tsim.backend.lanes.incidence_lists`
    makes them): point p's edges are inc[ist[p]:imid[p]] (those whose first end it is) then
    inc[imid[p]:ist[p + 1]] (whose second end it is), each ascending."""
    return {"ist": pc + 1, "imid": pc, "inc": 2 * ec}


@ti.func
def sync():
    """The lanes' barrier (a thread block's: every lane of a world is in its block)."""
    ti.simt.block.sync()


@ti.func
def own(n, lane, lanes: ti.template()):
    """How many of n elements lane `lane` holds (element lane + k * lanes for k below it)."""
    return (n - lane + lanes - 1) // lanes


@ti.func
def gather(p, v0, w0, inc: ti.template(), fx: ti.template(), fy: ti.template(),
           skip_zero: ti.template()):
    """Point p's (v0, w0) after `springs.add_to_ends` of (fx, fy): minus its first ends' vectors,
    then plus its second ends', each in edge order (the scatter's order into p)."""
    v = v0
    w = w0
    for c in range(inc.ist[p], inc.imid[p]):
        e = inc.inc[c]
        x = fx[e]
        y = fy[e]
        if ti.static(not skip_zero) or x != 0.0 or y != 0.0:
            v -= x
            w -= y
    for c in range(inc.imid[p], inc.ist[p + 1]):
        e = inc.inc[c]
        x = fx[e]
        y = fy[e]
        if ti.static(not skip_zero) or x != 0.0 or y != 0.0:
            v += x
            w += y
    return v, w


@ti.func
def spring_forces_lanes(n_pts, n_edges, lane, lanes: ti.template(), s: ti.template(),
                        inc: ti.template(), first: ti.template()):
    """`springs.spring_forces`: each lane its edges' forces, a barrier, then each lane its
    points' sums (`gather`) into s.frc."""
    for k in range(own(n_edges, lane, lanes)):
        edge_force(lane + k * lanes, s, first)
    sync()
    for k in range(own(n_pts, lane, lanes)):
        p = lane + k * lanes
        fx, fy = gather(p, 0.0, 0.0, inc, s.ccx, s.ccy, False)
        s.frc[2 * p] = fx
        s.frc[2 * p + 1] = fy


@ti.func
def rk4_lanes(n_pts, n_edges, lane, lanes: ti.template(), s: ti.template(), inc: ti.template()):
    """`integrate.rk4` over the lanes (a lane integrates its own points; the springs read every
    point's stage state, so each stage starts after a barrier). The ground's force is tested per
    point: `rk4`'s two copies of the point loop differ only in LLVM's vectorising, not in value."""
    for k in range(own(n_pts, lane, lanes)):
        p = lane + k * lanes
        for d in ti.static(range(2)):
            stage_start(2 * p + d, s)
    for stage in ti.static(range(4)):
        sync()
        spring_forces_lanes(n_pts, n_edges, lane, lanes, s, inc, stage == 0)
        for k in range(own(n_pts, lane, lanes)):
            point_stage(lane + k * lanes, s, stage, True)
    for k in range(own(n_pts, lane, lanes)):
        p = lane + k * lanes
        for d in ti.static(range(2)):
            stage_end(2 * p + d, s)


@ti.func
def hold_fixed_lanes(b, lane, lanes: ti.template(), counts: ti.template(), lists: ti.template(),
                     s: ti.template()):
    """`integrate.hold_fixed`, the fixed points dealt to lanes (a point listed twice is written
    twice with the same values)."""
    for k in range(own(counts[b, N_FIXED], lane, lanes)):
        hold_point(lists[b, lane + k * lanes, 2], s)


@ti.func
def constraints_lanes(b, n_pts, n_edges, lane, lanes: ti.template(), counts: ti.template(),
                      vox_i: ti.template(), lists: ti.template(), s: ti.template(), inc: ti.template()):
    """`constraints.constraints`: each lane its edges' corrections, a barrier, each lane its
    points' sums (`gather`, zero vectors left out as the scatter leaves them out), the fixed
    points, then the rigid voxels' pass on lane 0. Starts and ends at a barrier."""
    sync()
    for k in range(own(n_edges, lane, lanes)):
        edge_correction(lane + k * lanes, s)
    sync()
    for k in range(own(n_pts, lane, lanes)):
        p = lane + k * lanes
        if ti.static(pairs()):
            v, w = gather(p, s.plo[2 * p], s.plo[2 * p + 1], inc, s.ccx, s.ccy, True)
            s.plo[2 * p] = v
            s.plo[2 * p + 1] = w
        else:
            v, w = gather(p, s.pos[2 * p], s.pos[2 * p + 1], inc, s.ccx, s.ccy, True)
            s.pos[2 * p] = v
            s.pos[2 * p + 1] = w
    sync()
    hold_fixed_lanes(b, lane, lanes, counts, lists, s)
    sync()
    if lane == 0:
        rigid_voxels(b, counts, vox_i, lists, s)
    sync()


@ti.func
def move_lanes(b, n_pts, n_edges, lane, lanes: ti.template(), counts: ti.template(),
               vox_i: ti.template(), lists: ti.template(), s: ti.template(), inc: ti.template()):
    """`step.move` over the lanes (every lane calls it; it ends at a barrier)."""
    rk4_lanes(n_pts, n_edges, lane, lanes, s, inc)
    sync()
    hold_fixed_lanes(b, lane, lanes, counts, lists, s)
    if ti.static("constraints" not in PROFILE_SKIP):
        constraints_lanes(b, n_pts, n_edges, lane, lanes, counts, vox_i, lists, s, inc)
    else:
        sync()
    for k in range(own(n_pts, lane, lanes)):
        p = lane + k * lanes
        for d in ti.static(range(2)):
            snapshot(2 * p + d, s)
    sync()
