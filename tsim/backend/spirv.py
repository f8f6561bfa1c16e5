"""The step kernel's launch on Taichi's SPIR-V backends (Vulkan, Metal).

Why a loop of compile-time length: for a loop over a runtime length (`range(counts.shape[0])`),
Taichi 1.7's SPIR-V code generator dispatches a fixed 131,072 invocations
(`kMaxNumThreadsGridStrideLoop`) that stride over the range; only a loop with a compile-time
length dispatches as many as it needs. The kernels here loop over a compile-time `n` (the batch
size rounded up, `batch_tier`) and skip the worlds past the batch. One kernel is compiled per
batch tier.

Why the scratch lives in global arrays here (`global_scratch`), not in local ones as on the CPU:
a SPIR-V driver keeps a shader's local arrays in registers or private memory, and Mesa's lavapipe
compiles a dynamically indexed local array slowly: the step kernel with capacity tier 3's arrays
(1,024 reals per point array) took 630 s of CPU to compile, tier 2's 162 s. As per-world slices
of two global ndarrays (one real, one i32) the arrays are plain buffer accesses. And they outlive
a launch, so an env step can be split between launches anywhere between substeps or between a
substep's contacts and the rest of it, with the same arithmetic as one launch.

Why an env step may take several launches (`Launcher`): Mesa's llvmpipe, which runs lavapipe's
shaders, bounds the loops of a shader by one counter (gallivm's `LP_MAX_TGSI_LOOP_ITERATIONS`:
65,535 loop iterations over all the loops of one shader run, shared by the SIMD lanes that run
together, i.e. by up to 4-8 worlds). Once it is spent, every loop leaves after its current
iteration, silently: the physics goes wrong without an error. A 5x5 Walker-v0 robot takes ~2,200
iterations a substep without contacts and more with them; BridgeWalker-v0's bridge (a simulated
object of ~200 surface voxels) more than 65,535 in one substep. So every kernel here ends with a
sentinel loop that such a driver cuts short once the budget is spent, and flags the world; the
launcher then starts the env step again from its state (which only the last launch writes) in
launches of half as many substeps, down to one substep, then one half of a substep (its contacts,
in pieces if need be; the rest) per launch (a GPU's driver has no such bound: one launch of all
substeps per step). Every split gives the bits of one launch (tests/tsim/backend/test_spirv.py, run on
the CPU backend).

Why two more differences from the CPU's code, both SPIR-V only and decided at compile time: f32's
two-sum reads a 1.0 from the global scratch (`Scratch.one`; lavapipe's compiler otherwise turns
(a + b) - a into b, `pairs.renormalize`), and `tanh` is tsim/kernels/portable.py's formula in f32 too
(SPIR-V's f32 `Tanh` on lavapipe is 19 % off at 1e-7).
"""

from typing import NamedTuple

import numpy as np

from tsim import backend
from tsim.backend.runtime import PROFILE_SKIP, ti
from tsim.errors import SgrError
from tsim.kernels.broadphase import LIST_PER_VOXEL
from tsim.kernels.contacts import contacts
from tsim.kernels.layout import (
    GPU_BLOCK,
    I32_1,
    I32_2,
    I32_3,
    N_EDGE_F,
    N_EDGES,
    N_PTS,
    N_SURF,
    N_SURF_ROBOT,
    NONFINITE,
    REAL_1,
    REAL_2,
    RUNNING,
    STATUS,
    UNSTABLE,
    pairs,
    state_columns,
)
from tsim.kernels.scratch import N_PART_F, N_PART_I, Part, Scratch, Terrain
from tsim.kernels.step import load_edges, load_points, move, store_world, terrain_top

# what one launch of `phase_kernel` runs
BEGIN, SUBSTEPS, CONTACTS, MOVE, END = range(5)
# the i32 scratch's two per-world slots after the arrays: the world's status in this env step and
# its substep's contact count
ST_STATUS, ST_COUNT = 0, 1


def batch_tier(n_worlds: int) -> int:
    """The compile-time loop length for a batch: GPU_BLOCK, doubled until it holds n_worlds."""
    n = GPU_BLOCK
    while n < n_worlds:
        n *= 2
    return n


class Slice:
    """`n` entries of a global 1-D ndarray from `base` on, indexed as a local vector is (`s.pos[i]`
    reads and writes `arr[base + i]`): Taichi evaluates the subscript of a Python object that is no
    Taichi type by calling its `__getitem__` while compiling."""

    def __init__(self, arr, base, n: int):
        self.arr = arr
        self.base = base
        self.n = n

    def __getitem__(self, i):
        return ti.lang.impl.subscript(None, self.arr, self.base + i)


def real_sizes(pc: int, ec: int, sc: int) -> dict[str, int]:
    """The real arrays of a world's scratch and their lengths (capacity pc points, ec edges, sc
    surface voxels), as `step.step_world` makes them."""
    lc = 2 * pc if pairs() else 1
    sizes = {k: 2 * pc for k in ("pos", "vel", "pl", "vt", "xs", "vs", "frc", "fcol", "adx", "adv")}
    sizes.update({k: lc for k in ("plo", "vlo", "pllo", "xlo")})
    sizes["e0"] = 4 * ec if pairs() else 1
    sizes.update({k: ec for k in ("leq", "ek", "egoal", "erest", "ccx", "ccy")})
    sizes.update(box=4 * sc, refbox=4 * sc, one=1, part_f=N_PART_F)
    return sizes


def int_sizes(pc: int, ec: int, sc: int) -> dict[str, int]:
    """The i32 arrays of a world's scratch and their lengths, then the two slots (ST_*)."""
    return {"ea": ec, "eb": ec, "sv": 8 * sc, "sm": 4 * sc, "order": sc, "rank": sc, "cand": sc,
            "nbr": LIST_PER_VOXEL * sc, "nstart": sc + 1, "sweep": 2, "plist": 1, "part_i": N_PART_I,
            "slots": 2}


def scratch_lengths(pc: int, ec: int, sc: int) -> tuple[int, int]:
    """Per world, the lengths of the real and the i32 global scratch."""
    return sum(real_sizes(pc, ec, sc).values()), sum(int_sizes(pc, ec, sc).values())


class WorldScratch(NamedTuple):
    """A world's scratch in the global arrays, its two slots (ST_STATUS, ST_COUNT) and those that
    the pieces of a substep's contacts share (`scratch.Part`)."""

    s: Scratch
    slots: Slice
    part_i: Slice
    part_f: Slice


def global_scratch(gf, gi, b, pc: int, ec: int, sc: int) -> WorldScratch:
    """World b's `Scratch` as slices of the global arrays gf (real) and gi (i32), and its slots."""
    nf, ni = scratch_lengths(pc, ec, sc)
    out = {}
    for arr, sizes, per_world in ((gf, real_sizes(pc, ec, sc), nf), (gi, int_sizes(pc, ec, sc), ni)):
        off = 0
        for name, n in sizes.items():
            out[name] = Slice(arr, b * per_world + off, n)
            off += n
    slots, part_i, part_f = out.pop("slots"), out.pop("part_i"), out.pop("part_f")
    return WorldScratch(Scratch(**out), slots, part_i, part_f)


@ti.func
def laps(m):
    """The sentinel: a loop of m laps, returning how many ran: fewer than m once a driver's loop
    budget is spent. m must be known only at run time: a loop of constant length is unrolled by
    the shader compiler and then runs in full (measured on lavapipe: 31 of 31 laps after the
    budget ran out; tests/tsim/backend/test_vulkan.py)."""
    ran = 0
    for _ in range(m):
        ran += 1
    return ran


@ti.func
def contacts_of(b, counts: ti.template(), s: ti.template(), slots: ti.template(),
                ter_f: ti.template(), ter_i: ti.template(), ter_grid: ti.template(),
                sweep_mode: ti.template(), pair_list: ti.template(), part: ti.template(), last):
    """A running world's contacts of its substep (`step.step_world`'s first half of a substep),
    all of them (part None) or one piece; after the `last` piece, the count into its slot,
    NONFINITE into its status when a coordinate is not finite."""
    count = 0
    if ti.static("contacts" not in PROFILE_SKIP):
        ter_top = terrain_top(ter_f)
        ter = ti.static(Terrain(f=ter_f, i=ter_i, grid=ter_grid, top=ter_top))
        count = contacts(b, counts[b, N_PTS], counts, s, ter, sweep_mode, pair_list, part)
    if last:
        slots[ST_COUNT] = count
        if count < 0:
            slots[ST_STATUS] = NONFINITE


@ti.func
def move_of(b, counts: ti.template(), vox_i: ti.template(), lists: ti.template(),
            s: ti.template(), slots: ti.template()):
    """A running world's substep after its contacts (`step.step_world`'s second half)."""
    move(b, counts[b, N_PTS], counts[b, N_EDGES], counts, vox_i, lists, s)
    if slots[ST_COUNT] > counts[b, N_SURF_ROBOT]:
        slots[ST_STATUS] = UNSTABLE


@ti.kernel
def phase_kernel(phase: ti.template(), counts: I32_2, state: REAL_1, edge_i: I32_1, edge_f: REAL_1,
                 vox_i: I32_3, lists: I32_3, actions: REAL_2, ter_f: REAL_2, ter_i: I32_2,
                 ter_grid: I32_2, n_sub: ti.i32, P: ti.i32, E: ti.i32, pc: ti.template(),
                 ec: ti.template(), sc: ti.template(), sweep_mode: ti.template(),
                 pair_list: ti.template(), block: ti.template(), n: ti.template(), gf: REAL_1,
                 gi: I32_1, piece: ti.i32, pieces: ti.i32, overrun: I32_1):
    """One part of an env step of every world (`kernels.step.step_kernel`'s arguments, then
    the batch tier n, the global scratch gf and gi, see `global_scratch`): BEGIN loads a running
    world into its scratch; SUBSTEPS runs n_sub substeps; CONTACTS (piece `piece` of `pieces` of
    them, `contacts.contacts`) and MOVE the two halves of one;
    END writes the state back (as `step.step_world` does at its end). overrun[b] = 1 where the
    driver's loop budget ran out (see the module docstring)."""
    ti.loop_config(block_dim=block)
    for b in range(n):
        if b < counts.shape[0]:
            w = ti.static(global_scratch(gf, gi, b, pc, ec, sc))
            s = ti.static(w.s)
            if ti.static(phase == BEGIN):
                w.slots[ST_STATUS] = counts[b, STATUS]
                if counts[b, STATUS] == RUNNING:
                    ns = ti.static(state_columns())
                    s.sweep[0] = -1
                    s.sweep[1] = 0
                    s.plist[0] = 0
                    s.one[0] = 1.0
                    for i in range(counts[b, N_SURF]):
                        s.order[i] = i
                    if ti.static(pairs()):  # the local arrays start at zero (step_world)
                        for i in range(2 * counts[b, N_PTS]):
                            s.plo[i] = 0.0
                            s.vlo[i] = 0.0
                            s.pllo[i] = 0.0
                    load_edges(b, counts[b, N_EDGES], b * E * 4, b * E * N_EDGE_F, edge_i, edge_f,
                               actions, s.ea, s.eb, s.ek, s.egoal, s.erest, s.leq)
                    load_points(b, counts[b, N_PTS], b * P * ns, counts, state, vox_i, lists, s)
            if ti.static(phase == SUBSTEPS):
                for _ in range(n_sub):
                    if w.slots[ST_STATUS] == RUNNING:
                        contacts_of(b, counts, s, w.slots, ter_f, ter_i, ter_grid, sweep_mode,
                                    pair_list, None, True)
                        if w.slots[ST_STATUS] == RUNNING:
                            move_of(b, counts, vox_i, lists, s, w.slots)
            if ti.static(phase == CONTACTS):
                if w.slots[ST_STATUS] == RUNNING:
                    part = ti.static(Part(piece=piece, pieces=pieces, i=w.part_i, f=w.part_f))
                    contacts_of(b, counts, s, w.slots, ter_f, ter_i, ter_grid, sweep_mode,
                                pair_list, part, piece == pieces - 1)
            if ti.static(phase == MOVE):
                if w.slots[ST_STATUS] == RUNNING:
                    move_of(b, counts, vox_i, lists, s, w.slots)
            if ti.static(phase == END):
                if counts[b, STATUS] == RUNNING:
                    store_world(b, counts[b, N_PTS], b * P * ti.static(state_columns()), counts, state,
                                w.slots[ST_STATUS], s)
            # written whatever it finds: on lavapipe, entries that a launch left unwritten came
            # back as an earlier launch wrote them (Taichi seems not to copy an array that a
            # kernel only writes to the device)
            overrun[b] = ti.select(laps(n_sub + 1) == n_sub + 1, 0, 1)


class Launcher:
    """Env steps of one batch through `phase_kernel`: BEGIN, then the substeps in launches of
    `chunk` (all of them until the driver's loop budget runs out, then half as many, and so on,
    remembered), then END. `chunk` 0: each substep in launches of its contacts, in `pieces`
    pieces (doubled while a piece runs out), then MOVE."""

    def __init__(self, n_worlds: int):
        self.chunk: int | None = None  # substeps per launch; None: all of a step's; 0: halves
        self.pieces = 1  # launches of a substep's contacts when chunk is 0
        self.overrun = np.zeros(n_worlds, dtype=np.int32)
        self._scratch: tuple | None = None  # the global scratch (gf, gi), made at the first step

    def step(self, args: tuple) -> None:
        """One env step: args are `kernels.step.step_kernel`'s arguments, then the batch tier
        (args[N_SUB_ARG] substeps; counts, a numpy array, and state, a numpy array or a device's
        Taichi ndarray (`tsim.backend.mirror`), are written in place)."""
        n_sub = args[N_SUB_ARG]
        gf, gi = self._scratch_for(args)
        chunk = n_sub if self.chunk is None else min(self.chunk, n_sub)
        while (overran := self._run(args, gf, gi, chunk)) is not None:
            if chunk > 0:
                chunk //= 2
            elif overran == CONTACTS and self.pieces < MAX_PIECES:
                self.pieces *= 2
            else:
                raise SgrError("a world of this batch needs more loop iterations in one part of a "
                               "substep than this Vulkan driver runs in one shader (Mesa's lavapipe "
                               "stops every loop after 65,535); use SGR_ARCH=cpu, or a GPU's driver")
        self.chunk = chunk
        self._launch(END, args, gf, gi, 1)

    def _scratch_for(self, args: tuple) -> tuple:
        pc, ec, sc = args[PC_ARG:PC_ARG + 3]
        n = args[-1]
        if self._scratch is None or self._scratch[2] != (pc, ec, sc, n):
            nf, ni = scratch_lengths(pc, ec, sc)
            real = getattr(ti, backend.real().taichi)
            self._scratch = (ti.ndarray(real, n * nf), ti.ndarray(ti.i32, n * ni), (pc, ec, sc, n))
        return self._scratch[:2]

    def _launch(self, phase: int, args: tuple, gf, gi, n_sub: int, piece: int = 0,
                pieces: int = 1) -> bool:
        """One launch of `phase`; False if the driver's loop budget ran out in it."""
        phase_kernel(phase, *args[:N_SUB_ARG], n_sub, *args[N_SUB_ARG + 1:], gf, gi, piece, pieces,
                     self.overrun)
        return not self.overrun.any()

    def _run(self, args: tuple, gf, gi, chunk: int) -> int | None:
        """BEGIN, then the env step's substeps in launches of `chunk` (0: each in launches of
        its contacts' pieces, then the rest); the phase of the first launch that overran, or
        None."""
        if not self._launch(BEGIN, args, gf, gi, 1):
            raise SgrError("a world of this batch is too large to load in one shader of this Vulkan "
                           "driver (Mesa's lavapipe stops every loop after 65,535 iterations); "
                           "use SGR_ARCH=cpu, or a GPU's driver")
        done = 0
        n_sub = args[N_SUB_ARG]
        while done < n_sub:
            if chunk == 0:
                for piece in range(self.pieces):
                    if not self._launch(CONTACTS, args, gf, gi, 1, piece, self.pieces):
                        return CONTACTS
                if not self._launch(MOVE, args, gf, gi, 1):
                    return MOVE
                done += 1
            else:
                k = min(chunk, n_sub - done)
                if not self._launch(SUBSTEPS, args, gf, gi, k):
                    return SUBSTEPS
                done += k
        return None


N_SUB_ARG = 10  # the place of n_sub among the step kernels' arguments
PC_ARG = 13  # the place of pc (then ec, sc)
MAX_PIECES = 64  # most launches a substep's contacts are split into
