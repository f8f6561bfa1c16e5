"""Narrow phase: evogym's voxel-voxel contact (`resolve_boxel_collisions`) between two quads.

Quads live in local scratch: qf[4q + k] = (x, y, vx_true, vy_true) and qi[4q + k] = (point id,
side k is open) of corner k (q = 0, 1); in f32 (`L.pairs`) qf[4q + k, 4:6] also holds the
position's low part, and every difference of two corners the tests use is taken from the pairs
(`corner_less`). Forces go to fcol[2 id : 2 id + 2] for dynamic points (id >= 0); terrain points
(id < 0) are fixed and their share is dropped, as evogym discards the update of fixed points.
"""

from tsim import constants as C
from tsim.backend.runtime import ti
from tsim.kernels import layout as L
from tsim.kernels import portable
from tsim.kernels.geometry import (
    dist_point_edge,
    intersects,
    intersects_ends,
    normalized,
    point_in_quad,
)

Q_LO = 4  # qf's columns of the low parts (f32)
N_QF = 4  # qf's columns: n_qf() in the process's real type


def n_qf() -> int:
    """qf's columns: 4, and in f32 the positions' low parts."""
    return N_QF + 2 if L.pairs() else N_QF


@ti.func
def qpt(qf: ti.template(), q, k):
    """Position of corner k of scratch quad q (in f32 its pair's high part)."""
    return ti.Vector([qf[4 * q + k, 0], qf[4 * q + k, 1]])


@ti.func
def corner_less(qf: ti.template(), q, k, q2, k2):
    """Corner k of quad q less corner k2 of quad q2. f32: from the pairs, (hi - hi2) + (lo - lo2),
    where hi - hi2 is exact for nearby corners (Sterbenz): evogym places bodies 1e-16 apart (Lifter-v0's
    robot 1.1e-16 from its slot's walls), and which side of a corner a point lies on decides a
    contact in the first substep; float32 numbers alone are 6e-8 apart at 0.6."""
    d = qpt(qf, q, k) - qpt(qf, q2, k2)
    if ti.static(L.pairs()):
        d += ti.Vector([qf[4 * q + k, Q_LO] - qf[4 * q2 + k2, Q_LO],
                        qf[4 * q + k, Q_LO + 1] - qf[4 * q2 + k2, Q_LO + 1]])
    return d


@ti.func
def crosses(qf: ti.template(), q, a1, b1, q2, a2, b2):
    """Whether side (a1, b1) of quad q and side (a2, b2) of quad q2 intersect (evogym's closed
    segment test; f32 from the pairs, its bounds as signs: `geometry.intersects_ends`)."""
    d1 = corner_less(qf, q, b1, q, a1)
    d2 = corner_less(qf, q2, b2, q2, a2)
    a21 = corner_less(qf, q2, a2, q, a1)
    hit = False
    if ti.static(L.pairs()):
        hit = intersects_ends(d1, d2, a21, corner_less(qf, q2, a2, q, b1),
                              corner_less(qf, q2, b2, q, a1))
    else:
        hit = intersects(d1, d2, a21)
    return hit


@ti.func
def qvel(qf: ti.template(), q, k):
    """vel_true of corner k of scratch quad q."""
    return ti.Vector([qf[4 * q + k, 2], qf[4 * q + k, 3]])


@ti.func
def resolve(fcol: ti.template(), qf: ti.template(), qi: ti.template(), m, r, scale):
    """Contacts of quad m's corner points inside quad r, forces scaled by `scale` into fcol
    (see the module docstring for the quads' layout)."""
    margin = ti.static(L.tol().box_margin)
    lo = ti.min(ti.min(qpt(qf, r, 0), qpt(qf, r, 1)), ti.min(qpt(qf, r, 2), qpt(qf, r, 3))) \
        - margin
    hi = ti.max(ti.max(qpt(qf, r, 0), qpt(qf, r, 1)), ti.max(qpt(qf, r, 2), qpt(qf, r, 3))) \
        + margin
    for i in range(4):
        pid = qi[4 * m + i, 0]
        p = qpt(qf, m, i)
        # corners outside r's box cannot be inside r; then corners shared with r
        candidate = lo[0] <= p[0] and p[0] <= hi[0] and lo[1] <= p[1] and p[1] <= hi[1]
        if candidate and pid >= 0:
            for j in range(4):
                if qi[4 * r + j, 0] == pid:
                    candidate = False
        inside = False
        if candidate:  # (Taichi's `and` does not short-circuit)
            inside = point_in_quad(corner_less(qf, r, 0, m, i), corner_less(qf, r, 1, m, i),
                                   corner_less(qf, r, 2, m, i), corner_less(qf, r, 3, m, i))
        if inside:
            s1 = 0 if i < 2 else 2
            s2 = 3 if (i == 0 or i == 3) else 1
            m1a = s1
            m1b = (s1 + 1) % 4
            if s1 >= 2 and qi[4 * m + s1, 1] == 0:
                m1a, m1b = m1b, m1a
            m2a = s2
            m2b = (s2 + 1) % 4
            if s2 >= 2 and qi[4 * m + s2, 1] == 0:
                m2a, m2b = m2b, m2a
            best = -1
            best_d = 0.0
            for s in range(4):
                if qi[4 * r + s, 1] != 0:
                    rs = (s + 1) % 4
                    dr = corner_less(qf, r, rs, r, s)
                    if crosses(qf, m, m1a, m1b, r, s, rs) or crosses(qf, m, m2a, m2b, r, s, rs):
                        d = dist_point_edge(corner_less(qf, m, i, r, s), dr)
                        if best < 0 or d < best_d:
                            best = s
                            best_d = d
            if best >= 0:
                ka = best
                kb = (best + 1) % 4
                slope = corner_less(qf, r, kb, r, ka)
                normal = normalized(ti.Vector([-slope[1], slope[0]]))
                nf = normal * C.CONTACT_K * (C.CONTACT_OFFSET + best_d)
                un = normalized(normal)
                vp = qvel(qf, m, i)
                va = qvel(qf, r, ka)
                vb = qvel(qf, r, kb)
                damp_p = un * (-1.0) * (un[0] * vp[0] + un[1] * vp[1]) * C.CONTACT_VEL_DAMPING
                damp_a = un * (un[0] * va[0] + un[1] * va[1]) * C.CONTACT_VEL_DAMPING
                damp_b = un * (un[0] * vb[0] + un[1] * vb[1]) * C.CONTACT_VEL_DAMPING
                ut = normalized(normal)
                ut = ti.Vector([-ut[1], ut[0]])
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
def load_quad(s: ti.template(), qf: ti.template(), qi: ti.template(), q, i):
    """Copy surface voxel list entry i (corners and open sides in s.sv) into scratch quad q; in
    f32 (`L.pairs`) with its positions' low parts."""
    for k in range(4):
        p = s.sv[8 * i + k]
        qi[4 * q + k, 0] = p
        qi[4 * q + k, 1] = s.sv[8 * i + 4 + k]
        qf[4 * q + k, 0] = s.pos[2 * p]
        qf[4 * q + k, 1] = s.pos[2 * p + 1]
        if ti.static(L.pairs()):
            qf[4 * q + k, Q_LO] = s.plo[2 * p]
            qf[4 * q + k, Q_LO + 1] = s.plo[2 * p + 1]
        qf[4 * q + k, 2] = s.vt[2 * p]
        qf[4 * q + k, 3] = s.vt[2 * p + 1]
