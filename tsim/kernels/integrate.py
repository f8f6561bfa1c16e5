"""Integration: classical RK4 of one substep (springs, drag, gravity, the ground plane, contact
forces frozen across the stages), and the fixed points held where they were."""

from tsim import constants as C
from tsim import portable
from tsim.kernels.layout import N_FIXED
from tsim.kernels.springs import spring_forces
from tsim.runtime import ti


@ti.func
def rk4(n_pts, n_edges, s: ti.template()):
    """Rest-length update, then classical RK4 on (s.pos, s.vel) with dt = 1e-4; x, y interleaved.
    The 4 stages are unrolled; stage 0 (stage state = substep state) also sets the current rest
    lengths, and each stage's point loop prepares the next stage's state."""
    for i in range(2 * n_pts):
        s.xs[i] = s.pos[i]
        s.vs[i] = s.vel[i]
    for stage in ti.static(range(4)):
        spring_forces(n_pts, n_edges, s, stage == 0)
        # the ground plane's force (a branch and a tanh call) keeps LLVM from vectorising the
        # point loop, so that loop has a second copy without it for stages with no point below
        below = 0
        for p in range(n_pts):
            if s.xs[2 * p + 1] < 0:
                below += 1
        for ground in ti.static((False, True)):
            if (below > 0) == ground:
                for p in range(n_pts):
                    vx = s.vs[2 * p]
                    vy = s.vs[2 * p + 1]
                    fx = s.frc[2 * p] + vx * (-C.VISCOUS_DRAG)
                    fy = s.frc[2 * p + 1] + vy * (-C.VISCOUS_DRAG)
                    fy += C.POINT_MASS * (-C.GRAVITY)
                    fx += s.fcol[2 * p]
                    fy += s.fcol[2 * p + 1]
                    if ti.static(ground):
                        y = s.xs[2 * p + 1]
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
                            s.adx[i] += 2 * kx
                            s.adv[i] += 2 * kv
                        else:
                            s.adx[i] += kx
                            s.adv[i] += kv
                        if ti.static(stage < 3):
                            h = 0.5 if ti.static(stage < 2) else 1.0
                            s.xs[i] = s.pos[i] + kx * h
                            s.vs[i] = s.vel[i] + kv * h
    for i in range(2 * n_pts):
        s.pos[i] += s.adx[i] / 6
        s.vel[i] += s.adv[i] / 6


@ti.func
def hold_fixed(b, counts: ti.template(), lists: ti.template(), s: ti.template()):
    """Put the fixed points back where they were at the start of the substep (pos_last), at rest:
    the same bits as evogym's discarded update (its RK4 increment and edge corrections of fixed
    points are zeroed). Their forces and intermediate RK4 stages are computed as for any point,
    as in evogym, since the stages feed the springs of their free neighbours."""
    for i in range(counts[b, N_FIXED]):
        p = lists[b, i, 2]
        for d in ti.static(range(2)):
            s.pos[2 * p + d] = s.pl[2 * p + d]
            s.vel[2 * p + d] = 0.0
