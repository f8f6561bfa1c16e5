"""Taichi kernels for `BatchEnv.step`'s per-point work (issue 48 item 2): the robots' COMs and
the observation rows, computed where the state lives, into preallocated arrays.

What numpy did with temporaries, fancy-index scatters and copies of (B, N, .) arrays, these do in
one pass over each world's points, in the same order and the same types, so the results are
numpy's bits (`BatchEnv(..., fused=False)` keeps the numpy path as the test oracle):
- a COM is the sum of the robot's rows in point order, from +0.0 (numpy's `add.reduce` along a
  non-contiguous axis), over all `N` padded rows: a padding row adds its zeros, or, when free
  objects' points follow the robot's, the row times 0.0 (numpy's `rows * mask`); the sum is in the
  state's type and is divided in float64 (numpy's float32 / int64 is float64);
- a relative position is `pos - com` in float64, stored in the observation's type.
Everything else of a step (the (B,)-sized rewards, termination, the head blocks) stays in numpy.
"""


from tsim.runtime import ti

REAL_1 = ti.types.ndarray(ndim=1)
REAL_2 = ti.types.ndarray(ndim=2)
REAL_3 = ti.types.ndarray(ndim=3)
I32_1 = ti.types.ndarray(dtype=ti.i32, ndim=1)
F64_2 = ti.types.ndarray(dtype=ti.f64, ndim=2)


@ti.func
def _coms(state: ti.template(), npts: ti.template(), b, N, masked: ti.template(), com: ti.template(),
          vcom: ti.template()):
    """World b's position and velocity COMs into com[b], vcom[b] (see the module docstring)."""
    n = npts[b]
    z = state[b, 0, 0] - state[b, 0, 0]  # +0.0 in the state's type (its rows are finite)
    sx, sy, svx, svy = z, z, z, z
    for p in range(N):
        if ti.static(masked):
            m = ti.select(p < n, 1.0, 0.0)
            sx += state[b, p, 0] * m
            sy += state[b, p, 1] * m
            svx += state[b, p, 2] * m
            svy += state[b, p, 3] * m
        else:
            sx += state[b, p, 0]
            sy += state[b, p, 1]
            svx += state[b, p, 2]
            svy += state[b, p, 3]
    nf = ti.cast(n, ti.f64)
    com[b, 0] = ti.cast(sx, ti.f64) / nf
    com[b, 1] = ti.cast(sy, ti.f64) / nf
    vcom[b, 0] = ti.cast(svx, ti.f64) / nf
    vcom[b, 1] = ti.cast(svy, ti.f64) / nf


@ti.kernel
def robot_coms(state: REAL_3, npts: I32_1, N: ti.i32, masked: ti.template(), com: F64_2, vcom: F64_2,
               copy: ti.template(), points: REAL_3):
    """(B, 2) position and velocity COMs of every world's robot (its first npts[b] of N rows);
    with `copy`, each robot's N rows' positions into points (B, N, 2) too (`Measure.points`)."""
    for b in range(npts.shape[0]):
        _coms(state, npts, b, N, masked, com, vcom)
        if ti.static(copy):
            for p in range(N):
                points[b, p, 0] = state[b, p, 0]
                points[b, p, 1] = state[b, p, 1]


@ti.kernel
def observe(state: REAL_3, npts: I32_1, N: ti.i32, masked: ti.template(), com: F64_2, vcom: F64_2,
            copy: ti.template(), points: REAL_3, head: ti.i32, obs: REAL_2):
    """`robot_coms`, then each observation row from column `head` on: the robot's points relative
    to its COM (x of every point, then y), zeros to the row's end (`tail` writes the blocks after
    the points). Columns before `head` are the caller's."""
    for b in range(npts.shape[0]):
        _coms(state, npts, b, N, masked, com, vcom)
        if ti.static(copy):
            for p in range(N):
                points[b, p, 0] = state[b, p, 0]
                points[b, p, 1] = state[b, p, 1]
        n = npts[b]
        cx = com[b, 0]
        cy = com[b, 1]
        for p in range(n):
            obs[b, head + p] = ti.cast(state[b, p, 0], ti.f64) - cx
            obs[b, head + n + p] = ti.cast(state[b, p, 1], ti.f64) - cy
        for k in range(head + 2 * n, obs.shape[1]):
            obs[b, k] = 0.0


@ti.kernel
def tail(npts: I32_1, head: ti.i32, values: REAL_2, obs: REAL_2):
    """The blocks after the points: values (B, k) into each row from column head + 2 npts[b] on."""
    for b in range(npts.shape[0]):
        c = head + 2 * npts[b]
        for j in range(values.shape[1]):
            obs[b, c + j] = values[b, j]
