"""Integration: classical RK4 of one substep (springs, drag, gravity, the ground plane, contact
forces frozen across the stages), and the fixed points held where they were."""

from tsim import constants as C
from tsim.backend.runtime import ti
from tsim.kernels import portable
from tsim.kernels.layout import N_FIXED, pairs
from tsim.kernels.pairs import renormalize
from tsim.kernels.springs import spring_forces


@ti.func
def stage_y(s: ti.template(), p):
    """Point p's height at the RK4 stage state (in f32 its pair rounded: near the ground, where
    it is read, float32 resolves it to ~1e-9 or better)."""
    y = s.xs[2 * p + 1]
    if ti.static(pairs()):
        y = s.pos[2 * p + 1] + (s.plo[2 * p + 1] + s.xlo[2 * p + 1])
    return y


@ti.func
def rk4(n_pts, n_edges, s: ti.template()):
    """Rest-length update, then classical RK4 on (s.pos, s.vel) with dt = 1e-4; x, y interleaved.
    The 4 stages are unrolled; stage 0 (stage state = substep state) also sets the current rest
    lengths, and each stage's point loop prepares the next stage's state.

    f32 (`pairs`): a stage's position is the substep's s.pos + s.plo plus the stage's offset
    s.xlo (k h; s.xs is unused), its velocity s.vel + s.vlo + k h rounded; the substep's
    increments add to the low parts (s.plo unnormalised until the constraints are done, s.vlo
    renormalised here)."""
    for i in range(2 * n_pts):
        stage_start(i, s)
    for stage in ti.static(range(4)):
        spring_forces(n_pts, n_edges, s, stage == 0)
        # the ground plane's force (a branch and a tanh call) keeps LLVM from vectorising the
        # point loop, so that loop has a second copy without it for stages with no point below
        below = 0
        for p in range(n_pts):
            if stage_y(s, p) < 0:
                below += 1
        for ground in ti.static((False, True)):
            if (below > 0) == ground:
                for p in range(n_pts):
                    point_stage(p, s, stage, ground)
    for i in range(2 * n_pts):
        stage_end(i, s)


# Per element: what `rk4` does to one coordinate or point, called by its loops and by the lanes
# kernel's (tsim/kernels/lanes.py) for each lane's own. A scratch entry is updated as
# x[i] = x[i] + v, never x[i] += v: the same value, but Taichi compiles an augmented assignment to
# an array as an atomic add, which the lanes kernel's shared arrays cannot take on SPIR-V.


@ti.func
def stage_start(i, s: ti.template()):
    """Coordinate i's stage-0 state: the substep's own."""
    s.xs[i] = s.pos[i]
    s.vs[i] = s.vel[i]
    if ti.static(pairs()):
        s.xlo[i] = 0.0


@ti.func
def point_stage(p, s: ti.template(), stage: ti.template(), ground: ti.template()):
    """Point p at RK4 stage `stage`: its acceleration from its spring forces (s.frc), drag,
    gravity, the frozen contact forces and, where `ground`, the ground plane's (tested per point);
    its increments added to s.adx, s.adv with the stage's weight, and the next stage's state."""
    vx = s.vs[2 * p]
    vy = s.vs[2 * p + 1]
    fx = s.frc[2 * p] + vx * (-C.VISCOUS_DRAG)
    fy = s.frc[2 * p + 1] + vy * (-C.VISCOUS_DRAG)
    fy += C.POINT_MASS * (-C.GRAVITY)
    fx += s.fcol[2 * p]
    fy += s.fcol[2 * p + 1]
    if ti.static(ground):
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


@ti.func
def stage_end(i, s: ti.template()):
    """Coordinate i after the four stages: the RK4 sum added (in f32 to the low parts)."""
    if ti.static(pairs()):
        s.plo[i] = s.plo[i] + s.adx[i] / 6
        s.vlo[i] = s.vlo[i] + s.adv[i] / 6
        renormalize(s.vel, s.vlo, i, s.one)
    else:
        s.pos[i] = s.pos[i] + s.adx[i] / 6
        s.vel[i] = s.vel[i] + s.adv[i] / 6


@ti.func
def hold_fixed(b, counts: ti.template(), lists: ti.template(), s: ti.template()):
    """Put the fixed points back where they were at the start of the substep (pos_last), at rest:
    the same bits as evogym's discarded update (its RK4 increment and edge corrections of fixed
    points are zeroed). Their forces and intermediate RK4 stages are computed as for any point,
    as in evogym, since the stages feed the springs of their free neighbours."""
    for i in range(counts[b, N_FIXED]):
        hold_point(lists[b, i, 2], s)


@ti.func
def hold_point(p, s: ti.template()):
    """Fixed point p back at pos_last, at rest (`hold_fixed`)."""
    for d in ti.static(range(2)):
        s.pos[2 * p + d] = s.pl[2 * p + d]
        s.vel[2 * p + d] = 0.0
        if ti.static(pairs()):
            s.plo[2 * p + d] = s.pllo[2 * p + d]
            s.vlo[2 * p + d] = 0.0


@ti.func
def snapshot(i, s: ti.template()):
    """Coordinate i's end of a substep (`move`; the lanes kernel's too): its velocity from the
    substep's displacement and pos_last moved on (in f32 the pair renormalised first)."""
    if ti.static(pairs()):
        renormalize(s.pos, s.plo, i, s.one)
        s.vt[i] = ((s.pos[i] - s.pl[i]) + (s.plo[i] - s.pllo[i])) / C.DT
        s.pllo[i] = s.plo[i]
    else:
        s.vt[i] = (s.pos[i] - s.pl[i]) / C.DT
    s.pl[i] = s.pos[i]
