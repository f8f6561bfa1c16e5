"""Springs: their forces at an RK4 stage, and the scatter of per-edge vectors to the edges' ends."""

from tsim import constants as C
from tsim.runtime import ti


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
    order."""
    for i in range(2 * n_pts):
        s.frc[i] = 0.0
    for e in range(n_edges):
        a = s.ea[e]
        q = s.eb[e]
        dx = s.xs[2 * a] - s.xs[2 * q]
        dy = s.xs[2 * a + 1] - s.xs[2 * q + 1]
        dist = ti.sqrt(dx * dx + dy * dy)
        if ti.static(first):
            s.leq[e] = dist + (s.egoal[e] - dist) * C.REST_CONVERGENCE
        mag = (dist - s.leq[e]) * s.ek[e] / dist
        s.ccx[e] = dx * mag
        s.ccy[e] = dy * mag
    add_to_ends(n_edges, s.frc, s.ea, s.eb, s.ccx, s.ccy, False)
