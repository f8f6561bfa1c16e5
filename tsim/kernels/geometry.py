"""Geometric predicates on 2-vectors: evogym's point-in-voxel, segment and distance tests."""

from tsim import constants as C
from tsim.kernels import layout as L
from tsim.runtime import ti


@ti.func
def cross(a, b):
    """The 2-D cross product a x b (z component)."""
    return a[0] * b[1] - a[1] * b[0]


@ti.func
def point_in_quad(p, tl, tr, br, bl):
    """evogym's point-in-voxel test: triangles (TL,TR,BR) and (TL,BR,BL), boundary inside."""
    a_tl = tl - p
    a_tr = tr - p
    a_br = br - p
    a_bl = bl - p
    ca = cross(a_tl, a_tr)
    cb = cross(a_tr, a_br)
    cc = cross(a_br, a_tl)
    inside = (cc * ca >= 0.0) and (cc * cb >= 0.0)
    if not inside:
        cd = cross(a_tl, a_bl)
        ce = cross(a_bl, a_br)
        inside = (cc * cd >= 0.0) and (cc * ce >= 0.0)
    return inside


@ti.func
def intersects(a1, b1, a2, b2):
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
def dist_point_edge(p, a, b):
    """Distance from p to the line through a and b (evogym's); 1000 for a degenerate edge."""
    base = b - a
    length = ti.sqrt(base[0] * base[0] + base[1] * base[1])
    d = 1000.0
    if length >= C.DEGENERATE_EDGE:
        slant = p - a
        d = ti.abs(base[0] * slant[1] - slant[0] * base[1]) / length
    return d


@ti.func
def normalized(v):
    """v / |v|, unguarded as in evogym."""
    return v / ti.sqrt(v[0] * v[0] + v[1] * v[1])


@ti.func
def in_box(x, y, x0, x1, y0, y1):
    """In the box widened by the box margin: the same test as `narrowphase.resolve`'s candidate
    corners."""
    m = ti.static(L.tol().box_margin)
    return x0 - m <= x and x <= x1 + m and y0 - m <= y and y <= y1 + m
