"""The kernels' array layout, status codes, capacity tiers and the tolerances of the real type.

All arrays are Taichi ndarrays or numpy arrays, so the kernels compile once per process for any
batch; `counts`, `state` and `actions` change between launches, the others are static. "real" is
the process's floating-point type (f64 by default, f32 on request; `tsim.backend.real`):
- `counts[b, :]`   int: see the COUNT_* column names below.
- `state[b, p, :]` real: pos(0:2) vel(2:4) pos_last(4:6) vel_true(6:8) of dynamic point p
  (robot points first, then free objects such as Thrower's package); in f32 also the low parts
  of pos (8:10) and vel (10:12) and the pos (12:14) they belong to (`pairs`, `state_columns`).
- `edge_i[b, e, :]` int: a, b, driver0, driver1 (actuator indices or -1).
- `edge_f[b, e, :]` real: rest length, k, goal at rest, and (E_LEQ) in f64 the current rest length
  at rest, unused (the kernel derives each step's goals from the actions and keeps the current
  rest lengths in local arrays), in f32 how far the spring's float32 initial length lies from
  evogym's float64 one, less the rest length's rounding (`BatchSim._length_rounding`,
  `springs.spring_forces`).
- `vox_i[b, v, :]` int: corner points (TL, TR, BR, BL), open sides (top, right, bottom, left),
  material, object id, row, col; `lists[b, i, 0]` surface voxels (robot first),
  `lists[b, i, 1]` rigid voxels, `lists[b, i, 2]` fixed points (corners of a simulated object's
  material-5 voxels: evogym discards their RK4 increment and their edge-constraint moves).
- terrain (shared by the batch, static): `ter_f[t, :]` corners TL, TR, BR, BL as x, y pairs then
  the AABB, in f32 then the corners' low parts (`pairs`); `ter_i[t, :]` open sides;
  `ter_grid[gx, gy]` the surface voxel in that cell or -1.
"""

from __future__ import annotations

from tsim import backend
from tsim.backend.runtime import ti
from tsim.backend.tables import PRECISIONS, Tolerances

# counts columns
N_PTS, N_EDGES, N_VOX, N_SURF, N_SURF_ROBOT, N_RIGID, N_ACT, STATUS, N_FIXED = range(9)
N_COUNTS = 9
# STATUS values: a world is simulated only while its status is RUNNING
RUNNING, UNSTABLE, NONFINITE, INACTIVE = 0, 1, 2, 3

# vox_i columns
V_PTS, V_OPEN, V_TYPE, V_OBJ, V_ROW, V_COL = 0, 4, 8, 9, 10, 11
N_VOX_I = 12

# edge_f columns
E_REST, E_K, E_GOAL, E_LEQ = range(4)
N_EDGE_F = 4
NS = 8  # state columns of every real type (pos, vel, pos_last, vel_true)
# f32 only (`pairs`): each position and velocity is a pair hi + lo of float32 numbers, hi the
# state's own column; the low parts follow the 8 columns, with the positions they belong to
S_POS_LO, S_VEL_LO, S_LO_OF = 8, 10, 12
NS_PAIRS = 14
# ter_f: corners (0:8), box (8:12), and in f32 the corners' low parts (TER_LO:TER_LO + 8)
TER_LO = 12
N_TER_F_PAIRS = 20

# Real arrays take the process's real type (their dtype is left to the argument: one kernel
# source for f64 and f32); integer arrays are i32
REAL_1 = ti.types.ndarray(ndim=1)
REAL_2 = ti.types.ndarray(ndim=2)
I32_1 = ti.types.ndarray(dtype=ti.i32, ndim=1)
I32_2 = ti.types.ndarray(dtype=ti.i32, ndim=2)
I32_3 = ti.types.ndarray(dtype=ti.i32, ndim=3)

GPU_BLOCK = 64  # worlds per thread block on a GPU (each world is one thread)

# ------------------------------------------------------------------------------------------------
# The per-point state of a world lives in local arrays (LLVM allocas) for the whole env step
# (`scratch.Scratch`). Stores to ndarrays force LLVM to reload every ndarray's data pointer and
# shape after each store (they might alias), which made the spring loop ~3x slower than with local
# accumulators. Hot loops store only to locals; ndarrays are addressed through flat 1-D views with
# compile-time strides. The local arrays have a static capacity (points, edges, surface voxels):
# a batch uses the smallest tier `capacity(k)` that holds its largest world; each tier is its own
# compiled kernel, and results do not depend on the tier (tests/tsim/test_kernels.py).
# ------------------------------------------------------------------------------------------------
PC, EC, SC = 64, 160, 32  # tier 0: points, edges, surface voxels (a 5x5 robot and Thrower's box)


def capacity(k: int) -> tuple[int, int, int]:
    """Local-array capacity (points, edges, surface voxels) of tier k: tier 0 doubled k times."""
    return PC << k, EC << k, SC << k


# the kernels' margins per real type: tsim/backend/__init__.py's `PRECISIONS` rows own them
TOLERANCES: dict[str, Tolerances] = {name: p.tolerances for name, p in PRECISIONS.items()}


def pairs() -> bool:
    """Whether the kernels keep positions and velocities as float32 pairs hi + lo (f32 only;
    f64 compiles without them, so its bits are what they were). Read at compile time."""
    return backend.real().pairs


def state_columns() -> int:
    """Columns of `state` in the process's real type: NS, and in f32 the pairs' low parts."""
    return NS_PAIRS if pairs() else NS


def tol() -> Tolerances:
    """The tolerances of the process's real type (called inside kernels under `ti.static`)."""
    return backend.real().tolerances
