"""A substep's second half (integration, fixed points, constraints, snapshot) spread over a world's
L lanes: the lanes kernel's stages (tsim/lanes.py; GPU and Vulkan only, issue #48 item 1).

The same arithmetic as `integrate.rk4`, `springs.spring_forces`, `constraints.constraints` and
`step.move`, element by element, with the elements dealt to lanes: point p and edge e to lane
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

The CPU's kernels do not call this module (Taichi's CPU backend has no block barrier): their
code, and so f64's bits on the CPU, are what they were. The per-element code is a copy of the
CPU's; a change to one must be made to both (tests/tsim/test_lanes.py compares them on every task).
"""

from tsim import constants as C
from tsim import portable
from tsim.kernels.constraints import _HI, _HI_R, _LO, _LO_R
from tsim.kernels.integrate import stage_y
from tsim.kernels.layout import N_FIXED, N_RIGID, V_PTS, pairs
from tsim.kernels.pairs import renormalize
from tsim.runtime import PROFILE_SKIP, ti


def incidence_sizes(pc: int, ec: int) -> dict[str, int]:
    """A world's incidence lists (capacity pc points, ec edges; `tsim.lanes.incidence_lists`
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
        e = lane + k * lanes
        a = s.ea[e]
        q = s.eb[e]
        if ti.static(pairs()):
            dx = 0.0
            dy = 0.0
            dist = 0.0
            stretch = 0.0
            if ti.static(first):
                dx = (s.pos[2 * a] - s.pos[2 * q]) + (s.plo[2 * a] - s.plo[2 * q])
                dy = (s.pos[2 * a + 1] - s.pos[2 * q + 1]) + (s.plo[2 * a + 1] - s.plo[2 * q + 1])
                dist = ti.sqrt(dx * dx + dy * dy)
                stretch = ((dist - s.egoal[e]) - s.leq[e]) * C.REST_CONVERGENCE
                s.e0[4 * e] = dx
                s.e0[4 * e + 1] = dy
                s.e0[4 * e + 2] = dist
                s.e0[4 * e + 3] = stretch
            else:
                dx0 = s.e0[4 * e]
                dy0 = s.e0[4 * e + 1]
                ddx = s.xlo[2 * a] - s.xlo[2 * q]
                ddy = s.xlo[2 * a + 1] - s.xlo[2 * q + 1]
                dx = dx0 + ddx
                dy = dy0 + ddy
                dist = ti.sqrt(dx * dx + dy * dy)
                stretch = ((ddx * (dx0 + dx) + ddy * (dy0 + dy)) / (dist + s.e0[4 * e + 2])
                           + s.e0[4 * e + 3])
            mag = stretch * s.ek[e] / dist
            s.ccx[e] = dx * mag
            s.ccy[e] = dy * mag
        else:
            dx = s.xs[2 * a] - s.xs[2 * q]
            dy = s.xs[2 * a + 1] - s.xs[2 * q + 1]
            dist = ti.sqrt(dx * dx + dy * dy)
            if ti.static(first):
                s.leq[e] = dist + (s.egoal[e] - dist) * C.REST_CONVERGENCE
            mag = (dist - s.leq[e]) * s.ek[e] / dist
            s.ccx[e] = dx * mag
            s.ccy[e] = dy * mag
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
            i = 2 * p + d
            s.xs[i] = s.pos[i]
            s.vs[i] = s.vel[i]
            if ti.static(pairs()):
                s.xlo[i] = 0.0
    for stage in ti.static(range(4)):
        sync()
        spring_forces_lanes(n_pts, n_edges, lane, lanes, s, inc, stage == 0)
        for k in range(own(n_pts, lane, lanes)):
            p = lane + k * lanes
            vx = s.vs[2 * p]
            vy = s.vs[2 * p + 1]
            fx = s.frc[2 * p] + vx * (-C.VISCOUS_DRAG)
            fy = s.frc[2 * p + 1] + vy * (-C.VISCOUS_DRAG)
            fy += C.POINT_MASS * (-C.GRAVITY)
            fx += s.fcol[2 * p]
            fy += s.fcol[2 * p + 1]
            y = stage_y(s, p)
            if y < 0:
                normal = y * (-C.GROUND_K)
                fy += normal
                fx += ((-10.0 * C.FRICTION_DYN) * normal
                       * portable.tanh(vx * normal * C.FRICTION_DYN))
            acc = ti.Vector([fx / C.POINT_MASS, fy / C.POINT_MASS])
            for d in ti.static(range(2)):
                i = 2 * p + d
                kx = s.vs[i] * C.DT
                kv = acc[d] * C.DT
                if ti.static(stage == 0):
                    s.adx[i] = kx
                    s.adv[i] = kv
                elif ti.static(stage < 3):
                    s.adx[i] = s.adx[i] + 2 * kx
                    s.adv[i] = s.adv[i] + 2 * kv
                else:
                    s.adx[i] = s.adx[i] + kx
                    s.adv[i] = s.adv[i] + kv
                if ti.static(stage < 3):
                    h = 0.5 if ti.static(stage < 2) else 1.0
                    if ti.static(pairs()):
                        s.xlo[i] = kx * h
                        s.vs[i] = s.vel[i] + (s.vlo[i] + kv * h)
                    else:
                        s.xs[i] = s.pos[i] + kx * h
                        s.vs[i] = s.vel[i] + kv * h
    for k in range(own(n_pts, lane, lanes)):
        p = lane + k * lanes
        for d in ti.static(range(2)):
            i = 2 * p + d
            if ti.static(pairs()):
                s.plo[i] = s.plo[i] + s.adx[i] / 6
                s.vlo[i] = s.vlo[i] + s.adv[i] / 6
                renormalize(s.vel, s.vlo, i, s.one)
            else:
                s.pos[i] = s.pos[i] + s.adx[i] / 6
                s.vel[i] = s.vel[i] + s.adv[i] / 6


@ti.func
def hold_fixed_lanes(b, lane, lanes: ti.template(), counts: ti.template(), lists: ti.template(),
                     s: ti.template()):
    """`integrate.hold_fixed`, the fixed points dealt to lanes (a point listed twice is written
    twice with the same values)."""
    for k in range(own(counts[b, N_FIXED], lane, lanes)):
        p = lists[b, lane + k * lanes, 2]
        for d in ti.static(range(2)):
            s.pos[2 * p + d] = s.pl[2 * p + d]
            s.vel[2 * p + d] = 0.0
            if ti.static(pairs()):
                s.plo[2 * p + d] = s.pllo[2 * p + d]
                s.vlo[2 * p + d] = 0.0


@ti.func
def constraints_lanes(b, n_pts, n_edges, lane, lanes: ti.template(), counts: ti.template(),
                      vox_i: ti.template(), lists: ti.template(), s: ti.template(), inc: ti.template()):
    """`constraints.constraints`: each lane its edges' corrections, a barrier, each lane its
    points' sums (`gather`, zero vectors left out as the scatter leaves them out), the fixed
    points, then the rigid voxels' pass on lane 0. Starts and ends at a barrier."""
    sync()
    for k in range(own(n_edges, lane, lanes)):
        e = lane + k * lanes
        a = s.ea[e]
        q = s.eb[e]
        dx = s.pos[2 * a] - s.pos[2 * q]
        dy = s.pos[2 * a + 1] - s.pos[2 * q + 1]
        if ti.static(pairs()):
            dx += s.plo[2 * a] - s.plo[2 * q]
            dy += s.plo[2 * a + 1] - s.plo[2 * q + 1]
        dist = ti.sqrt(dx * dx + dy * dy)
        rest = s.erest[e]
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
        s.ccx[e] = cx * 0.8
        s.ccy[e] = cy * 0.8
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
        for i in range(counts[b, N_RIGID]):
            v = lists[b, i, 1]
            for k in ti.static(range(4)):
                a = vox_i[b, v, V_PTS + k]
                q = vox_i[b, v, V_PTS + (k + 1) % 4]
                dx = s.pos[2 * a] - s.pos[2 * q]
                dy = s.pos[2 * a + 1] - s.pos[2 * q + 1]
                if ti.static(pairs()):
                    dx += s.plo[2 * a] - s.plo[2 * q]
                    dy += s.plo[2 * a + 1] - s.plo[2 * q + 1]
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
                if ti.static(pairs()):
                    s.plo[2 * a] = s.plo[2 * a] - ox * 0.5
                    s.plo[2 * a + 1] = s.plo[2 * a + 1] - oy * 0.5
                    s.plo[2 * q] = s.plo[2 * q] + ox * 0.5
                    s.plo[2 * q + 1] = s.plo[2 * q + 1] + oy * 0.5
                else:
                    s.pos[2 * a] = s.pos[2 * a] - ox * 0.5
                    s.pos[2 * a + 1] = s.pos[2 * a + 1] - oy * 0.5
                    s.pos[2 * q] = s.pos[2 * q] + ox * 0.5
                    s.pos[2 * q + 1] = s.pos[2 * q + 1] + oy * 0.5
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
            i = 2 * p + d
            if ti.static(pairs()):
                renormalize(s.pos, s.plo, i, s.one)
                s.vt[i] = ((s.pos[i] - s.pl[i]) + (s.plo[i] - s.pllo[i])) / C.DT
                s.pllo[i] = s.plo[i]
            else:
                s.vt[i] = (s.pos[i] - s.pl[i]) / C.DT
            s.pl[i] = s.pos[i]
    sync()
