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
- a relative position is `pos - com` in float64, stored in the observation's type.
Everything else of a step (the (B,)-sized rewards, termination, the head blocks) stays in numpy.
"""

from tsim.kernels.layout import state_columns
from tsim.runtime import ti

REAL_1 = ti.types.ndarray(ndim=1)
REAL_2 = ti.types.ndarray(ndim=2)
I32_1 = ti.types.ndarray(dtype=ti.i32, ndim=1)
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
          vcom: ti.template(), copy: ti.template(), points: ti.template()):
    """World b's position and velocity COMs into com, vcom (flat (B, 2)), and with `copy` its N
    rows' positions into points (flat (B, N, 2)); its COM. The padding rows' products are +-0.0
    and change no sum but a zero one's sign, so they are read only when a sum of the robot's rows
    is 0 (see the module docstring)."""
    ns = ti.static(state_columns())
    so = b * P * ns
    n = npts[b]
    z = state[so] - state[so]  # +0.0 in the state's type (its rows are finite)
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
               vcom: F64_1, copy: ti.template(), points: REAL_1, serial: ti.template()):
    """(B, 2) position and velocity COMs (com, vcom: flat) of every world's robot, its first npts[b]
    of the N robot rows of its P state rows (state: flat (B, P, columns)); with `copy`, each
    robot's N rows' positions into points (flat (B, N, 2); `Measure.points`) too."""
    ti.loop_config(serialize=serial)
    for b in range(npts.shape[0]):
        _coms(state, npts, b, P, N, masked, com, vcom, copy, points)


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
        c = _coms(state, npts, b, P, N, masked, com, vcom, copy, points)
        so = b * P * ns
        n = npts[b]
        o = b * W + head
        for p in range(n):
            obs[o + p] = ti.cast(ti.cast(state[so + p * ns], ti.f64) - c[0], real)
            obs[o + n + p] = ti.cast(ti.cast(state[so + p * ns + 1], ti.f64) - c[1], real)
        for k in range(head + 2 * n, W):
            obs[b * W + k] = ti.cast(0.0, real)


@ti.kernel
def tail(npts: I32_1, head: ti.i32, values: REAL_2, W: ti.i32, obs: REAL_1, serial: ti.template()):
    """The blocks after the points: values (B, k) into each row of obs (flat (B, W)) from column
    head + 2 npts[b] on."""
    ti.loop_config(serialize=serial)
    for b in range(npts.shape[0]):
        o = b * W + head + 2 * npts[b]
        for j in range(values.shape[1]):
            obs[o + j] = values[b, j]


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
