"""The step kernel's launch on Taichi's SPIR-V backends (Vulkan, Metal).

Why: for a loop over a runtime length (`range(counts.shape[0])`), Taichi 1.7's SPIR-V code
generator dispatches a fixed 131,072 invocations (`kMaxNumThreadsGridStrideLoop`) that stride over
the range; only a loop with a compile-time length dispatches as many as it needs. Each idle
invocation still pays for the step's local arrays, and on Mesa's lavapipe (Vulkan on the CPU) a
launch of `step_kernel` took 0.9 s whether 1 or 16 worlds ran, or none. `step_kernel_sized` loops
over a compile-time `n` (the batch size rounded up, `batch_tier`) and skips the worlds past the
batch: a 4-robot Walker-v0 step took 10 ms instead. One kernel is compiled per batch tier.
"""

from tsim.kernels.layout import GPU_BLOCK, I32_1, I32_2, I32_3, REAL_1, REAL_2
from tsim.kernels.step import step_world
from tsim.runtime import ti


def batch_tier(n_worlds: int) -> int:
    """The compile-time loop length for a batch: GPU_BLOCK, doubled until it holds n_worlds."""
    n = GPU_BLOCK
    while n < n_worlds:
        n *= 2
    return n


@ti.kernel
def step_kernel_sized(counts: I32_2, state: REAL_1, edge_i: I32_1, edge_f: REAL_1,
                      vox_i: I32_3, lists: I32_3, actions: REAL_2, ter_f: REAL_2,
                      ter_i: I32_2, ter_grid: I32_2, n_sub: ti.i32, P: ti.i32, E: ti.i32,
                      pc: ti.template(), ec: ti.template(), sc: ti.template(),
                      sweep_mode: ti.template(), pair_list: ti.template(), block: ti.template(),
                      n: ti.template()):
    """`kernels.step.step_kernel` over a loop of compile-time length n >= the batch size."""
    ti.loop_config(block_dim=block)
    for b in range(n):
        if b < counts.shape[0]:
            step_world(b, counts, state, edge_i, edge_f, vox_i, lists, actions, ter_f, ter_i,
                          ter_grid, n_sub, P, E, pc, ec, sc, sweep_mode, pair_list)
