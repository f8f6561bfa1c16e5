"""Taichi kernels for `BatchEnv.step`'s per-point work (issue 48 item 2): the robots' COMs and
the observation rows, computed where the state lives, into preallocated arrays.

What numpy did with temporaries, fancy-index scatters and copies of (B, N, .) arrays, these do in
one pass over each world's points, in the same order and the same types, so the results are
numpy's bits (`BatchEnv(..., fused=False)` keeps the numpy path as the test oracle):
- a COM is the sum of the robot's rows in point order, from +0.0 (numpy's `add.reduce` along a
  non-contiguous axis), over all `N` padded rows: a padding row adds its zeros, or, when free
  objects' points follow the robot's, the row times 0.0 (numpy's `rows * mask`), which matters
  only to the sign of a zero sum (`_coms`); the sum is in the state's type and is divided in
  float64 (numpy's float32 / int64 is float64);
- a relative position is `pos - com` in float64, stored in the observation's type;
- the floor and ceiling sight over the static terrain: the COM in voxel units in the state's type
  (numpy's mean of the quotients), then numpy's comparisons in float64 (max and min are exact);
  over objects, which move, the same from the state's rows (`object_sight`);
- a free object's COM: numpy's pairwise sum of its points (`object_coms`);
- evogym's orientation, of the robot or a free object: tasks/orientation.py's Eigen orders, with
  numpy's arccos between two kernels (`orientation`);
- the convex hull's area of the shape-change tasks (`hull_areas`).
The (B,)-sized rewards and terminations stay in numpy. Float constants that float32 cannot hold
exactly come in as float64 arguments: in an f32 process Taichi makes a literal float32.
"""

from tsim.backend.runtime import ti
from tsim.kernels.layout import state_columns

REAL_1 = ti.types.ndarray(ndim=1)
REAL_2 = ti.types.ndarray(ndim=2)
I32_1 = ti.types.ndarray(dtype=ti.i32, ndim=1)
I32_2 = ti.types.ndarray(dtype=ti.i32, ndim=2)
F64_1 = ti.types.ndarray(dtype=ti.f64, ndim=1)
F64_2 = ti.types.ndarray(dtype=ti.f64, ndim=2)

# Arrays are flat 1-D views with strides known when compiling (the state's columns) or passed as
# ints, as the physics kernels address theirs (`tsim.kernels.layout`): with Taichi's ndarray
# shapes, every store reloads every array's pointer and shape; flat, the observation kernel took
# about half the time.


@ti.func
def _sum_rows(state: ti.template(), so, lo, hi, n, masked: ti.template(), s: ti.template()):
    """s (4 sums: x, y, vx, vy) plus the world's rows lo..hi-1 (the world's rows start at so), each
    times 1.0 or 0.0 (row < n) when `masked`, as numpy's `rows * mask` summed."""
    ns = ti.static(state_columns())
    for p in range(lo, hi):
        for c in ti.static(range(4)):
            if ti.static(masked):
                s[c] += state[so + p * ns + c] * ti.select(p < n, 1.0, 0.0)
            else:
                s[c] += state[so + p * ns + c]


@ti.func
def _coms(state: ti.template(), npts: ti.template(), b, P, N, masked: ti.template(), com: ti.template(),
          vcom: ti.template(), copy: ti.template(), points: ti.template(), real: ti.template()):
    """World b's position and velocity COMs into com, vcom (flat (B, 2)), and with `copy` its N
    rows' positions into points (flat (B, N, 2)); its COM. The padding rows' products are +-0.0
    and change no sum but a zero one's sign, so they are read only when a sum of the robot's rows
    is 0 (see the module docstring)."""
    ns = ti.static(state_columns())
    so = b * P * ns
    n = npts[b]
    z = ti.cast(0.0, real)  # +0.0 in the state's type
    s = ti.Vector([z, z, z, z])
    _sum_rows(state, so, 0, n, n, masked, s)
    if n < N and (s[0] == 0.0 or s[1] == 0.0 or s[2] == 0.0 or s[3] == 0.0):
        s = ti.Vector([z, z, z, z])
        _sum_rows(state, so, 0, N, n, masked, s)
    nf = ti.cast(n, ti.f64)
    c = ti.Vector([ti.cast(s[0], ti.f64) / nf, ti.cast(s[1], ti.f64) / nf])
    com[2 * b] = c[0]
    com[2 * b + 1] = c[1]
    vcom[2 * b] = ti.cast(s[2], ti.f64) / nf
    vcom[2 * b + 1] = ti.cast(s[3], ti.f64) / nf
    if ti.static(copy):
        for p in range(N):
            points[(b * N + p) * 2] = state[so + p * ns]
            points[(b * N + p) * 2 + 1] = state[so + p * ns + 1]
    return c


@ti.kernel
def robot_coms(state: REAL_1, npts: I32_1, P: ti.i32, N: ti.i32, masked: ti.template(), com: F64_1,
               vcom: F64_1, copy: ti.template(), points: REAL_1, real: ti.template(), serial: ti.template()):
    """(B, 2) position and velocity COMs (com, vcom: flat) of every world's robot, its first npts[b]
    of the N robot rows of its P state rows (state: flat (B, P, columns)); with `copy`, each
    robot's N rows' positions into points (flat (B, N, 2); `Measure.points`) too."""
    ti.loop_config(serialize=serial)
    for b in range(npts.shape[0]):
        _coms(state, npts, b, P, N, masked, com, vcom, copy, points, real)


@ti.kernel
def observe(state: REAL_1, npts: I32_1, P: ti.i32, N: ti.i32, masked: ti.template(), com: F64_1,
            vcom: F64_1, copy: ti.template(), points: REAL_1, head: ti.i32, W: ti.i32, obs: REAL_1,
            real: ti.template(), serial: ti.template()):
    """`robot_coms`, then each observation row (obs: flat (B, W)) from column `head` on: the
    robot's points relative to its COM (x of every point, then y), zeros to the row's end (`tail`
    writes the blocks after the points), rounded to `real` (obs's type). Columns before `head` are
    the caller's."""
    ns = ti.static(state_columns())
    ti.loop_config(serialize=serial)
    for b in range(npts.shape[0]):
        c = _coms(state, npts, b, P, N, masked, com, vcom, copy, points, real)
        so = b * P * ns
        n = npts[b]
        o = b * W + head
        for p in range(n):
            obs[o + p] = ti.cast(ti.cast(state[so + p * ns], ti.f64) - c[0], real)
            obs[o + n + p] = ti.cast(ti.cast(state[so + p * ns + 1], ti.f64) - c[1], real)
        for k in range(head + 2 * n, W):
            obs[b * W + k] = ti.cast(0.0, real)


@ti.kernel
def tail(npts: I32_1, head: ti.i32, values: REAL_2, W: ti.i32, obs: REAL_1, whole: ti.template(),
         serial: ti.template()):
    """The blocks after the points: values (B, k) into each row of obs (flat (B, W)) from column
    head + 2 npts[b] on. `whole` rewrites the rest of the row with what it holds: a backend that
    uploads only the arrays a kernel reads (Vulkan) would otherwise return the others' columns
    as the device memory held them."""
    ti.loop_config(serialize=serial)
    for b in range(npts.shape[0]):
        c = head + 2 * npts[b]
        o = b * W
        if ti.static(whole):
            for k in range(c):
                obs[o + k] = obs[o + k]
            for k in range(c + values.shape[1], W):
                obs[o + k] = obs[o + k]
        for j in range(values.shape[1]):
            obs[o + c + j] = values[b, j]


@ti.kernel
def clip_actions(a: F64_2, n_act: I32_1, lo: ti.f64, hi: ti.f64, real: ti.template(), out: REAL_2,
                 serial: ti.template()):
    """`BatchSim.set_actions` for a (B, max_actuators) float64 array of finite actions: robot b's
    first n_act[b] clipped to [lo, hi] (max, then min: numpy's `minimum(maximum(a, lo), hi)`) into
    out, rounded to `real`."""
    ti.loop_config(serialize=serial)
    for b in range(n_act.shape[0]):
        for j in range(n_act[b]):
            out[b, j] = ti.cast(ti.min(ti.max(a[b, j], lo), hi), real)


@ti.func
def _see(x, y, cx, cy, d: ti.template(), below: ti.template(), e: ti.template(), seen: ti.template()):
    """One point (x, y, voxel units, float64) seen from the COM (cx, cy): the highest point below
    (`below`) or the lowest above in each of the 2 d + 1 windows around cx it falls in."""
    if x > cx - (d + 0.5) and x < cx + (d + 0.5) and ((y < cy) if ti.static(below) else (y > cy)):
        for k in ti.static(range(2 * d + 1)):
            if x > cx + ti.static(k - d - 0.5) and x < cx + ti.static(k - d + 0.5):
                e[k] = ti.max(e[k], y) if ti.static(below) else ti.min(e[k], y)
                seen[k] = 1


@ti.func
def _sight_row(b, cy, d: ti.template(), below: ti.template(), rng, cell, e: ti.template(),
               seen: ti.template(), out: ti.template()):
    """World b's 2 d + 1 distances from what `_see` kept: to the point seen, else `rng` voxels;
    clipped to [0, rng], in world units."""
    for k in ti.static(range(2 * d + 1)):
        v = ti.cast(0.0, ti.f64)
        if ti.static(below):
            v = cy - (e[k] if seen[k] else cy - rng)
        else:
            v = (e[k] if seen[k] else cy + rng) - cy
        # np.clip keeps a NaN (a non-finite COM), where max and min would drop it
        out[b, k] = (v if ti.math.isnan(v) else ti.min(ti.max(v, 0.0), rng)) * cell


@ti.kernel
def terrain_sight(cv: F64_2, tx: REAL_1, ty: REAL_1, d: ti.template(), below: ti.template(), rng: ti.f64,
                  cell: ti.f64, out: F64_2, serial: ti.template()):
    """`tasks.observations.terrain_sight` over a static terrain (tx, ty: its points in voxel units,
    as numpy divided them): for each world's COM cv[b] (voxel units), the floor (`below`) or
    ceiling distance in 2 d + 1 windows, world units, into out (B, 2 d + 1). The same comparisons
    in float64 as numpy's; max and min are exact, so the same bits."""
    inf = ti.cast(ti.math.inf, ti.f64)
    ti.loop_config(serialize=serial)
    for b in range(cv.shape[0]):
        cx = cv[b, 0]
        cy = cv[b, 1]
        e = ti.Vector([-inf if ti.static(below) else inf] * (2 * d + 1), dt=ti.f64)
        seen = ti.Vector([0] * (2 * d + 1), dt=ti.i32)
        for m in range(tx.shape[0]):
            _see(ti.cast(tx[m], ti.f64), ti.cast(ty[m], ti.f64), cx, cy, d, below, e, seen)
        _sight_row(b, cy, d, below, rng, cell, e, seen, out)


@ti.kernel
def object_sight(state: REAL_1, rows: I32_2, P: ti.i32, tx: REAL_1, ty: REAL_1, n_static: ti.i32, cv: F64_2,
                 d: ti.template(), below: ti.template(), rng: ti.f64, cell: ti.f64, real: ti.template(),
                 out: F64_2, serial: ti.template()):
    """`terrain_sight` over objects that may move: world b's points are its state rows rows[b, :]
    (P rows a world), each position divided by the cell in type `real` (numpy's type for the
    concatenated points: the state's, or float64 where a fixed object's float64 points join them,
    `tasks.observations._sight_points`), and the first n_static of tx, ty (fixed objects' points,
    divided by numpy in that type); then compared in float64."""
    ns = ti.static(state_columns())
    inf = ti.cast(ti.math.inf, ti.f64)
    ti.loop_config(serialize=serial)
    for b in range(cv.shape[0]):
        cx = cv[b, 0]
        cy = cv[b, 1]
        c = ti.cast(cell, real)
        e = ti.Vector([-inf if ti.static(below) else inf] * (2 * d + 1), dt=ti.f64)
        seen = ti.Vector([0] * (2 * d + 1), dt=ti.i32)
        for m in range(rows.shape[1]):
            at = (b * P + rows[b, m]) * ns
            x = ti.cast(ti.cast(state[at], real) / c, ti.f64)
            _see(x, ti.cast(ti.cast(state[at + 1], real) / c, ti.f64), cx, cy, d, below, e, seen)
        for m in range(n_static):
            _see(ti.cast(tx[m], ti.f64), ti.cast(ty[m], ti.f64), cx, cy, d, below, e, seen)
        _sight_row(b, cy, d, below, rng, cell, e, seen, out)


@ti.kernel
def com_voxel_units(state: REAL_1, npts: I32_1, P: ti.i32, cell: ti.f64, real: ti.template(), out: F64_2,
                    serial: ti.template()):
    """`tasks.observations.com_voxel_units`: each robot's mean point position over `cell`, in the
    state's type `real` as numpy computes it (the quotients summed in point order from +0.0, that
    mean's order, then divided by the point count), stored in float64."""
    ns = ti.static(state_columns())
    ti.loop_config(serialize=serial)
    for b in range(npts.shape[0]):
        so = b * P * ns
        n = npts[b]
        c = ti.cast(cell, real)
        sx = ti.cast(0.0, real)  # +0.0 of the state's type
        sy = sx
        for p in range(n):
            sx += state[so + p * ns] / c
            sy += state[so + p * ns + 1] / c
        out[b, 0] = ti.cast(sx / ti.cast(n, real), ti.f64)
        out[b, 1] = ti.cast(sy / ti.cast(n, real), ti.f64)


@ti.func
def _pairwise(state: ti.template(), at, ns, n):
    """numpy's pairwise sum (`add.reduce` along a contiguous axis of n <= 128 values, numpy's
    PW_BLOCKSIZE): under 8 values one after another; else 8 accumulators over the whole blocks of
    8, combined ((r0 + r1) + (r2 + r3)) + ((r4 + r5) + (r6 + r7)), then the rest one after another.
    The values are state[at + i ns]. numpy starts the short sum from -0.0, which changes no sum of
    at least one value, so this starts from the first."""
    res = state[at]
    if n < 8:
        for i in range(1, n):
            res += state[at + i * ns]
    else:
        r = ti.Vector([state[at + j * ns] for j in ti.static(range(8))])
        whole = n - n % 8
        for k in range(1, whole // 8):
            for j in ti.static(range(8)):
                r[j] += state[at + (8 * k + j) * ns]
        res = ((r[0] + r[1]) + (r[2] + r[3])) + ((r[4] + r[5]) + (r[6] + r[7]))
        for i in range(whole, n):
            res += state[at + i * ns]
    return res


@ti.kernel
def object_coms(state: REAL_1, rows: I32_1, n: ti.i32, com: F64_2, vcom: F64_2, real: ti.template(),
                serial: ti.template()):
    """(B, 2) position and velocity COMs of a free object of n <= 128 points, in world b the flat
    state's rows rows[b] .. rows[b] + n - 1, as `tasks.observations.com` computes them from
    `BatchEnv._object_points`' arrays: each coordinate's n values summed along a contiguous axis
    (numpy's pairwise sum, `_pairwise`) after +0.0 (add.reduce's initial value), in the state's
    type, then divided by n in float64 (numpy's real / int64)."""
    ns = ti.static(state_columns())
    ti.loop_config(serialize=serial)
    for b in range(rows.shape[0]):
        at = rows[b] * ns
        z = ti.cast(0.0, real)  # +0.0 in the state's type
        nf = ti.cast(n, ti.f64)
        for c in ti.static(range(2)):
            com[b, c] = ti.cast(z + _pairwise(state, at + c, ns, n), ti.f64) / nf
            vcom[b, c] = ti.cast(z + _pairwise(state, at + 2 + c, ns, n), ti.f64) / nf


# ---------------------------------------------------------------------- orientation
# `tasks.orientation.orientation` in two kernels around numpy's arccos (whose bits depend on the
# machine's numpy build, so it stays numpy's): `orientation_terms` writes each point's clamped
# cosine, its reference magnitude and its cross product, `orientation_sums` adds them up. Points
# are rows of a flat real array: world b's point i at (base[b] + i) * stride, its reference's at
# (ref_base[b] + i) * ref_stride; count[b] points. Everything after the positions is float64, as
# numpy computes it (its COMs are float64 even from float32 positions).


@ti.func
def _eigen_com(src: ti.template(), base, stride, n, c: ti.template()):
    """Coordinate c's mean of n points as `tasks.orientation._eigen_com` adds them: the first,
    then groups of four ((p1 + p2) + (p3 + p4)) while a whole group fits below the last multiple
    of four of n - 1, then the rest one by one; divided by n."""
    s = ti.cast(src[base * stride + c], ti.f64)
    groups = ((n - 1) & ~3) // 4
    for k in range(groups):
        at = (base + 1 + 4 * k) * stride + c
        p1 = ti.cast(src[at], ti.f64)
        p2 = ti.cast(src[at + stride], ti.f64)
        p3 = ti.cast(src[at + 2 * stride], ti.f64)
        p4 = ti.cast(src[at + 3 * stride], ti.f64)
        s += (p1 + p2) + (p3 + p4)
    for j in range(3):
        i = 1 + 4 * groups + j
        if i < n:
            s += ti.cast(src[(base + i) * stride + c], ti.f64)
    return s / ti.cast(n, ti.f64)


@ti.kernel
def orientation_terms(src: REAL_1, base: I32_1, stride: ti.i32, ref: REAL_1, ref_base: I32_1,
                      ref_stride: ti.i32, count: I32_1, clamp: ti.f64, tiny: ti.f64, cos: F64_2,
                      mag_old: F64_2, cross: F64_2, serial: ti.template()):
    """Per point of each world (its first count[b]): the clamped cosine between its centred
    direction now and at reset, its centred distance at reset and the cross product of the two
    unit directions, into cos, mag_old, cross (B, W); `tasks.orientation.orientation`'s steps.
    Its constants 0.99999 and 1e-7 come as float64 arguments (clamp, tiny): in an f32 process a
    literal here would be float32's."""
    ti.loop_config(serialize=serial)
    for b in range(count.shape[0]):
        n = count[b]
        cx = _eigen_com(src, base[b], stride, n, 0)
        cy = _eigen_com(src, base[b], stride, n, 1)
        ox = _eigen_com(ref, ref_base[b], ref_stride, n, 0)
        oy = _eigen_com(ref, ref_base[b], ref_stride, n, 1)
        for i in range(n):
            x = ti.cast(src[(base[b] + i) * stride], ti.f64) - cx
            y = ti.cast(src[(base[b] + i) * stride + 1], ti.f64) - cy
            x0 = ti.cast(ref[(ref_base[b] + i) * ref_stride], ti.f64) - ox
            y0 = ti.cast(ref[(ref_base[b] + i) * ref_stride + 1], ti.f64) - oy
            mn = ti.sqrt(x * x + y * y)
            mo = ti.sqrt(x0 * x0 + y0 * y0)
            ux, uy, vx, vy = x, y, x0, y0
            if mn > 0:
                ux = x / mn
                uy = y / mn
            if mo > 0:
                vx = x0 / mo
                vy = y0 / mo
            cs = ux * vx + uy * vy
            if mn * mo < tiny:
                cs = clamp
            if cs > 1.0:
                cs = clamp
            if cs < -1.0:
                cs = -clamp
            cos[b, i] = cs
            mag_old[b, i] = mo
            cross[b, i] = ux * vy - uy * vx


@ti.func
def _eigen_sum(a: ti.template(), b, n):
    """Row b's first n >= 4 values of a (B, W) added in the order of Eigen's SSE2 reduction, as
    `tasks.orientation._eigen_sum` (n >= 4: a body's or object's points)."""
    z = ti.cast(0.0, ti.f64)
    p0x, p0y = a[b, 0], a[b, 1]
    p1x = a[b, 2] if n > 2 else z
    p1y = a[b, 3] if n > 3 else z
    end4 = (n // 4) * 4
    for k in range(1, end4 // 4):
        i = 4 * k
        p0x += a[b, i]
        p0y += a[b, i + 1]
        p1x += a[b, i + 2]
        p1y += a[b, i + 3]
    p0x = p0x + p1x
    p0y = p0y + p1y
    if n - end4 >= 2:
        p0x += a[b, end4]
        p0y += a[b, end4 + 1]
    res = p0x + p0y
    if n % 2 == 1:
        res += a[b, n - 1]
    return res


@ti.kernel
def orientation_sums(angle: F64_2, mag_old: F64_2, cross: F64_2, count: I32_1, two_pi: ti.f64,
                     out: F64_1, serial: ti.template()):
    """Each world's orientation from `orientation_terms`' arrays, angle holding arccos of its
    cosines: the reference-weighted mean angle, 2 pi minus it where the summed cross products are
    positive (`tasks.orientation.orientation`'s last lines; angle is overwritten)."""
    ti.loop_config(serialize=serial)
    for b in range(count.shape[0]):
        n = count[b]
        for i in range(n):
            angle[b, i] = angle[b, i] * mag_old[b, i]
        avg = _eigen_sum(angle, b, n) / _eigen_sum(mag_old, b, n)
        out[b] = two_pi - avg if _eigen_sum(cross, b, n) > 0 else avg


def orientation(src, base, stride: int, ref, ref_base, ref_stride: int, count, width: int,
                serial: bool):
    """(B,) `tasks.orientation.orientation` of the points described above (the robot's or a free
    object's), the same bits: two kernels and numpy's arccos of a (B, width) array between them
    (width: the largest count)."""
    import numpy as np

    from tasks.orientation import PI_EVOGYM

    n = count.shape[0]
    cos, mag_old, cross = (np.zeros((n, width)) for _ in range(3))
    orientation_terms(src, base, stride, ref, ref_base, ref_stride, count, 0.99999, 1e-7, cos, mag_old, cross,
                      serial)
    angle = np.arccos(cos, out=cos)
    out = np.empty(n)
    orientation_sums(angle, mag_old, cross, count, 2 * PI_EVOGYM, out, serial)
    return out


# ---------------------------------------------------------------------- convex hull area
@ti.func
def _before(pts: ti.template(), at, i, j):
    """Whether point i comes before point j in (x, y) order (numpy's lexsort of (y, x))."""
    xi, xj = pts[(at + i) * 2], pts[(at + j) * 2]
    return xi < xj or (xi == xj and pts[(at + i) * 2 + 1] < pts[(at + j) * 2 + 1])


@ti.func
def _half_hull(pts: ti.template(), at, b, n, N, order: ti.template(), H: ti.template(),
               c: ti.template(), reverse: ti.template()):
    """`tasks.suite.shape._chain` for world b: the monotone chain over its x-sorted points (from
    the right with `reverse`), popping while the turn is not left; then 0.0 plus the pairwise sum
    (numpy's order) of the L - 1 cross products of the chain's consecutive vertices."""
    L = 0
    for k in range(n):
        p = order[b, n - 1 - k] if ti.static(reverse) else order[b, k]
        qx = ti.cast(pts[(at + p) * 2], ti.f64)
        qy = ti.cast(pts[(at + p) * 2 + 1], ti.f64)
        while L >= 2:
            ax, ay = H[b, 2 * (L - 2)], H[b, 2 * (L - 2) + 1]
            bx, by = H[b, 2 * (L - 1)], H[b, 2 * (L - 1) + 1]
            if (bx - ax) * (qy - ay) - (by - ay) * (qx - ax) <= 0:
                L -= 1
            else:
                break
        H[b, 2 * L] = qx
        H[b, 2 * L + 1] = qy
        L += 1
    for k in range(L - 1):
        c[b * (N - 1) + k] = H[b, 2 * k] * H[b, 2 * k + 3] - H[b, 2 * k + 2] * H[b, 2 * k + 1]
    total = ti.cast(0.0, ti.f64)
    if L >= 2:
        total += _pairwise(c, b * (N - 1), 1, L - 1)
    return total


@ti.kernel
def hull_areas(pts: REAL_1, N: ti.i32, count: I32_1, order: I32_2, H: F64_2, c: F64_1, out: F64_1,
               serial: ti.template()):
    """`tasks.suite.shape.hull_area` of each world's first count[b] points (pts: flat (B, N, 2)),
    the same bits for 2 <= N <= 129 (the pairwise sum's one block): the points' order by (x, y)
    (an insertion sort, stable as lexsort), the lower and upper chains, 0.5 times their sums.
    order (B, N), H (B, 2 N + 2) and c (B (N - 1)) are scratch."""
    ti.loop_config(serialize=serial)
    for b in range(count.shape[0]):
        n = count[b]
        at = b * N
        for i in range(n):
            order[b, i] = i
        for i in range(1, n):
            key = order[b, i]
            j = i
            while j > 0 and _before(pts, at, key, order[b, j - 1]):
                order[b, j] = order[b, j - 1]
                j -= 1
            order[b, j] = key
        lower = _half_hull(pts, at, b, n, N, order, H, c, False)
        upper = _half_hull(pts, at, b, n, N, order, H, c, True)
        out[b] = 0.5 * (lower + upper)
