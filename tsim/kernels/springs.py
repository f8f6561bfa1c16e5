"""Springs: their forces at an RK4 stage, and the scatter of per-edge vectors to the edges' ends."""

from tsim import constants as C
from tsim.backend.runtime import ti
from tsim.kernels.layout import pairs


@ti.func
def add_to_ends(n_edges, v: ti.template(), ea: ti.template(), eb: ti.template(), fx: ti.template(),
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
def spring_forces(n_pts, n_edges, s: ti.template(), first: ti.template()):
    """The springs' forces at the RK4 stage state s.xs into s.frc (zeroed first, n_pts points).
    `first`: stage 0, which also sets the current rest lengths s.leq from the goals (evogym's
    rest-length update).

    The forces are computed in a loop without stores to shared points, which LLVM vectorises
    (square roots and divisions 4 at a time), into s.ccx, s.ccy; then scattered in evogym's
    order.

    f32 (`pairs`): the same force, k (dist - leq) / dist with leq = d0 + (goal - d0) c (d0 the
    length at stage 0), written as k ((dist - d0) + (d0 - goal) c) / dist, so that no length is
    subtracted from a nearly equal one: float32 would round each at ~4e-9 (at 0.1), and times
    k ~5e7 that is ~0.2 force units, against the ~0.03 a 1e-6 action change makes (k c 1e-7).
    The stretch also leaves out s.leq, the rounding of the spring's initial length and rest length
    (edge_f's E_LEQ column): a spring starts as strained as evogym's float64 placement makes it,
    not as float32's rounding of it does (~4e-8 at 0.6, ~0.02 force units: enough to move points
    that evogym holds still to the last bit off the terrain corners they touch).
    Stage 0 keeps its edge vector, length and stretch (d0 - goal) c in s.e0; a later stage's
    edge vector is that plus the difference of its ends' stage offsets s.xlo, and dist - d0 =
    (dist^2 - d0^2) / (dist + d0) is computed from those small differences."""
    for i in range(2 * n_pts):
        s.frc[i] = 0.0
    for e in range(n_edges):
        edge_force(e, s, first)
    add_to_ends(n_edges, s.frc, s.ea, s.eb, s.ccx, s.ccy, False)


@ti.func
def edge_force(e, s: ti.template(), first: ti.template()):
    """Spring e's force vector on its first end, into s.ccx[e], s.ccy[e] (`spring_forces`, which
    says how; the lanes kernel calls it for each lane's edges)."""
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
