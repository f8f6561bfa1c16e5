"""Constraints after each substep's integration: evogym's edge-length bands (every edge into
+-25 %, rigid voxels' sides into +-3 %), projected on the positions."""

from tsim import constants as C
from tsim.backend.runtime import ti
from tsim.kernels.integrate import hold_fixed
from tsim.kernels.layout import N_RIGID, V_PTS, pairs
from tsim.kernels.springs import add_to_ends

_HI = 1.0 + C.EDGE_BAND
_LO = 1.0 - C.EDGE_BAND
_HI_R = 1.0 + C.EDGE_BAND_RIGID
_LO_R = 1.0 - C.EDGE_BAND_RIGID


@ti.func
def constraints(b, n_edges, counts: ti.template(), vox_i: ti.template(), lists: ti.template(),
                s: ti.template()):
    """Pass 1: Jacobi projection of every edge into +-25 % (fixed points stay: their position
    this substep is still pos_last), applied in evogym's order (`add_to_ends`); pass 2: rigid
    voxels into +-3 % (evogym's rigid pass ignores the fixed flag). In f32 the positions are the
    pairs s.pos + s.plo and the corrections go to the low parts (`pairs`)."""
    for e in range(n_edges):
        edge_correction(e, s)
    if ti.static(pairs()):
        add_to_ends(n_edges, s.plo, s.ea, s.eb, s.ccx, s.ccy, True)
    else:
        add_to_ends(n_edges, s.pos, s.ea, s.eb, s.ccx, s.ccy, True)
    hold_fixed(b, counts, lists, s)
    rigid_voxels(b, counts, vox_i, lists, s)


@ti.func
def edge_correction(e, s: ti.template()):
    """Edge e's correction into +-25 %, into s.ccx[e], s.ccy[e] (pass 1 of `constraints`; the lanes
    kernel calls it for each lane's edges)."""
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


@ti.func
def rigid_voxels(b, counts: ti.template(), vox_i: ti.template(), lists: ti.template(), s: ti.template()):
    """Pass 2 of `constraints`: each rigid voxel's 4 sides into +-3 %, voxel by voxel (they share
    corners: the lanes kernel runs it on one lane). Entries are updated as x[i] = x[i] - v, not
    x[i] -= v (the same value; tsim/kernels/integrate.py says why)."""
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
