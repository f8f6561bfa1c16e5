"""Geometric predicates on 2-vectors: evogym's point-in-voxel, segment and distance tests."""

from tsim import constants as C
from tsim.backend.runtime import ti
from tsim.kernels import layout as L


@ti.func
def cross(a, b):
    """The 2-D cross product a x b (z component)."""
    return a[0] * b[1] - a[1] * b[0]


@ti.func
def point_in_quad(a_tl, a_tr, a_br, a_bl):
    """evogym's point-in-voxel test of a point p, given the voxel's corners less p (tl - p, ...):
    triangles (TL,TR,BR) and (TL,BR,BL), boundary inside. (Differences, so that f32 can give them
    from its pairs: `narrowphase.corner_less`.)"""
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
def intersects(d1, d2, a21):
    """Closed intersection of segments a1 + t d1 and a2 + s d2 (a21 = a2 - a1); near-parallel
    pairs (|det| < 1e-4) never intersect."""
    det = -d1[0] * d2[1] + d2[0] * d1[1]
    hit = False
    if ti.abs(det) >= C.PARALLEL_EPS:
        xd = a21[0]
        yd = a21[1]
        t = (-d2[1] * xd + d2[0] * yd) / det
        s = (-d1[1] * xd + d1[0] * yd) / det
        hit = 0.0 <= t and t <= 1.0 and 0.0 <= s and s <= 1.0
    return hit


@ti.func
def intersects_ends(d1, d2, a21, a2b1, b2a1):
    """`intersects`, with its bounds t <= 1 and s <= 1 tested as the signs of cross products of
    the segments' ends (a2b1 = a2 - b1, b2a1 = b2 - a1) instead of quotients (f32): a quotient
    rounds at 6e-8 relative, so a crossing 7.7e-12 beyond a segment's end (0.1 long) reads as on
    it, where float64's quotient (1 + 7.7e-11) does not (Lifter-v0). The same test in exact
    arithmetic: t det = d2 x a21, (t - 1) det = d2 x (a2 - b1), s det = d1 x a21, (s - 1) det =
    d1 x (b2 - a1)."""
    det = -d1[0] * d2[1] + d2[0] * d1[1]
    hit = False
    if ti.abs(det) >= C.PARALLEL_EPS:
        sg = 1.0 if det > 0 else -1.0
        hit = (cross(d2, a21) * sg >= 0.0 and cross(d2, a2b1) * sg <= 0.0
               and cross(d1, a21) * sg >= 0.0 and cross(d1, b2a1) * sg <= 0.0)
    return hit


@ti.func
def dist_point_edge(slant, base):
    """Distance from p to the line through a and b (evogym's), given slant = p - a and base =
    b - a; 1000 for a degenerate edge."""
    length = ti.sqrt(base[0] * base[0] + base[1] * base[1])
    d = 1000.0
    if length >= C.DEGENERATE_EDGE:
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
