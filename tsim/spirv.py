"""The step kernel's launch on Taichi's SPIR-V backends (Vulkan, Metal).

Why a loop of compile-time length: for a loop over a runtime length (`range(counts.shape[0])`),
Taichi 1.7's SPIR-V code generator dispatches a fixed 131,072 invocations
(`kMaxNumThreadsGridStrideLoop`) that stride over the range; only a loop with a compile-time
length dispatches as many as it needs. Each idle invocation still pays for the step's local
arrays, and on Mesa's lavapipe (Vulkan on the CPU) a launch of `step_kernel` took 0.9 s whether 1
or 16 worlds ran, or none. `step_kernel_sized` loops over a compile-time `n` (the batch size
rounded up, `batch_tier`) and skips the worlds past the batch: a 4-robot Walker-v0 step took 10 ms
instead. One kernel is compiled per batch tier.

Why an env step may take several launches (`Launcher`): Mesa's llvmpipe, which runs lavapipe's
shaders, bounds the loops of a shader by one counter (gallivm's `LP_MAX_TGSI_LOOP_ITERATIONS`:
65,535 loop iterations over all the loops of one shader run, shared by the SIMD lanes that run
together, i.e. by up to 4-8 worlds). Once it is spent, every loop leaves after its current
iteration, silently: the physics goes wrong without an error. A 5x5 Walker-v0 robot takes ~2,200
iterations a substep without contacts and more with them, so its 30 substeps in one launch ran
out (at substep ~30 without contacts, ~26 with; sooner for worlds that share SIMD lanes: the two
"known bugs" of docs/VALIDATION.md). So `step_kernel_sized` ends with a sentinel loop that such a
driver cuts short once the budget is spent, and flags the world; the launcher then puts the batch
back to the env step's start and runs the step again in launches of half as many substeps (a
GPU's driver has no such bound: one launch per step). Nothing outside the state array is carried
between substeps except what cannot change results (the broad phase's sweep decision and pair
list are rebuilt; the current rest lengths are recomputed at every substep's first RK4 stage), so
any split gives the same numbers as one launch (tests/tsim/test_spirv.py).
"""

import numpy as np

from tsim.errors import SgrError
from tsim.kernels.layout import GPU_BLOCK, I32_1, I32_2, I32_3, REAL_1, REAL_2, RUNNING, STATUS
from tsim.kernels.step import step_world
from tsim.runtime import ti

N_SUB_ARG = 10  # the place of n_sub among the step kernels' arguments


def batch_tier(n_worlds: int) -> int:
    """The compile-time loop length for a batch: GPU_BLOCK, doubled until it holds n_worlds."""
    n = GPU_BLOCK
    while n < n_worlds:
        n *= 2
    return n


@ti.func
def laps(m):
    """The sentinel: a loop of m laps, returning how many ran: fewer than m once a driver's loop
    budget is spent. m must be known only at run time: a loop of constant length is unrolled by
    the shader compiler and then runs in full (measured on lavapipe: 31 of 31 laps after the
    budget ran out; tests/tsim/test_vulkan.py)."""
    ran = 0
    for _ in range(m):
        ran += 1
    return ran


@ti.kernel
def step_kernel_sized(counts: I32_2, state: REAL_1, edge_i: I32_1, edge_f: REAL_1,
                      vox_i: I32_3, lists: I32_3, actions: REAL_2, ter_f: REAL_2,
                      ter_i: I32_2, ter_grid: I32_2, n_sub: ti.i32, P: ti.i32, E: ti.i32,
                      pc: ti.template(), ec: ti.template(), sc: ti.template(),
                      sweep_mode: ti.template(), pair_list: ti.template(), block: ti.template(),
                      n: ti.template(), overrun: I32_1):
    """`kernels.step.step_kernel` over a loop of compile-time length n >= the batch size;
    overrun[b] = 1 where the driver's loop budget ran out (see the module docstring)."""
    ti.loop_config(block_dim=block)
    for b in range(n):
        if b < counts.shape[0]:
            step_world(b, counts, state, edge_i, edge_f, vox_i, lists, actions, ter_f, ter_i,
                       ter_grid, n_sub, P, E, pc, ec, sc, sweep_mode, pair_list)
            # written whatever it finds: on lavapipe, entries that a launch left unwritten came
            # back as an earlier launch wrote them (Taichi seems not to copy an array that a
            # kernel only writes to the device)
            overrun[b] = ti.select(laps(n_sub + 1) == n_sub + 1, 0, 1)


class Launcher:
    """Env steps of one batch through `step_kernel_sized`, in launches of `chunk` substeps: all of
    them until the driver's loop budget runs out, then half as many (and so on, remembered)."""

    def __init__(self, n_worlds: int):
        self.chunk: int | None = None  # substeps per launch; None: all of a step's
        self.overrun = np.zeros(n_worlds, dtype=np.int32)

    def step(self, args: tuple, counts: np.ndarray, state: np.ndarray) -> None:
        """One env step of `step_kernel_sized(*args, overrun)` (args[N_SUB_ARG] substeps).
        `counts` and `state` ((B, P, state columns)) are the arrays that args[0] and args[1] (its
        flat view) are; they are written in place.

        A world whose status leaves RUNNING in some substep is left by its launch at that launch's
        start; it is put back to the env step's start here, every column (in f32 the pairs' low
        parts too), then pos_last = pos and vel_true = 0, which is what one launch of all substeps
        leaves."""
        n_sub = args[N_SUB_ARG]
        chunk = min(self.chunk or n_sub, n_sub)
        start_state = state.copy()
        start_counts = counts.copy()
        while not self._run(args, n_sub, chunk):
            if chunk == 1:
                raise SgrError("a world of this batch needs more loop iterations in one substep than "
                               "this Vulkan driver runs in one shader (Mesa's lavapipe stops every "
                               "loop after 65,535); use SGR_ARCH=cpu, or a GPU's driver")
            chunk = (chunk + 1) // 2
            state[...] = start_state
            counts[...] = start_counts
        self.chunk = chunk
        running = start_counts[:, STATUS] == RUNNING
        stopped = running & (counts[:, STATUS] != RUNNING)
        if stopped.any():
            state[stopped] = start_state[stopped]
            state[stopped, :, 4:6] = start_state[stopped, :, 0:2]
            state[stopped, :, 6:8] = 0.0

    def _run(self, args: tuple, n_sub: int, chunk: int) -> bool:
        """The step's substeps in launches of `chunk`; False at the first launch that overran."""
        done = 0
        while done < n_sub:
            k = min(chunk, n_sub - done)
            step_kernel_sized(*args[:N_SUB_ARG], k, *args[N_SUB_ARG + 1:], self.overrun)
            if self.overrun.any():
                return False
            done += k
        return True
