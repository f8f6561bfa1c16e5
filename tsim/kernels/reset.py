"""A partial reset where the state lives on a device (`BatchSim.reset(mask)`, tsim/backend/mirror.py): the
chosen worlds' rows back to their placement at rest in place, instead of bringing the whole state
to the host, writing it there and sending it back."""

from tsim.backend.runtime import ti
from tsim.kernels.layout import I32_1, REAL_1, S_LO_OF, S_POS_LO, pairs, state_columns


@ti.kernel
def reset_worlds(state: REAL_1, pos0: REAL_1, lo: REAL_1, lo_of: REAL_1, worlds: I32_1, P: ti.i32):
    """Worlds `worlds` (their indices) of state (flat (B, P, columns)) at rest at pos0 (flat (B, P,
    2)): every column 0, positions and last positions pos0's, and in f32 the placement's low parts
    (lo, lo_of; unread in f64). What `BatchSim.reset` writes on the host, the same values."""
    ns = ti.static(state_columns())
    for k, p in ti.ndrange(worlds.shape[0], P):
        at = (worlds[k] * P + p) * ns
        src = (worlds[k] * P + p) * 2
        for c in ti.static(range(ns)):
            state[at + c] = 0.0
        for c in ti.static(range(2)):
            state[at + c] = pos0[src + c]
            state[at + 4 + c] = pos0[src + c]
            if ti.static(pairs()):
                state[at + S_POS_LO + c] = lo[src + c]
                state[at + S_LO_OF + c] = lo_of[src + c]
