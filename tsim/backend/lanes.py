"""The lanes kernel: each world's env step on L lanes (threads) of one thread block, GPU and Vulkan
only (issue #48 item 1; `BatchSim.choose_kernel(lanes=L)`).

Today's step kernel gives each world one thread, everything serial in it. Here world b is thread
block b of L threads (L a power of two, compile time): a substep's contacts run on lane 0 as the
CPU runs them (`contacts.contacts`, the same function: its pair order decides the contact forces'
sums), then its integration, constraints and snapshot are spread over the lanes, points and
edges dealt to them (tsim/kernels/lanes.py: each point gathers its springs' forces in the
scatter's order, so the sums are the same sums; the rigid voxels' pass stays on lane 0). Phases
end at `ti.simt.block.sync()`. Taichi's CPU backend has no block barrier, so the CPU never
compiles this: its kernels and its f64 bits are what they were.

The world's arrays live in the SPIR-V launch's global scratch (`spirv.global_scratch`, one
world's slice of two global ndarrays; a third holds each world's incidence lists, built once on
the host), because they must outlive a launch: on Mesa's lavapipe an env step is split into
launches (`spirv.Launcher`: the driver's loop budget), and the lanes kernel takes the same phases
(BEGIN, SUBSTEPS, CONTACTS, MOVE, END) and the same launcher. On a GPU's driver a step is BEGIN,
one launch of every substep, END. A launch of substeps copies the arrays its lanes share
(`SHARED_REAL`, `SHARED_INT`) into `ti.simt.block.SharedArray`s where they fit (`fits_shared`:
capacity tier 0), works there, and copies them back; larger worlds work in the global scratch,
where lanes read consecutive points and edges of their world. Not checked: whether a GPU's Vulkan
driver makes global-memory writes visible to the other lanes at Taichi's SPIR-V barrier (it may
order workgroup memory only; lavapipe runs a block's lanes in turn, and CUDA's `__syncthreads`
orders both).
"""

from typing import NamedTuple

import numpy as np

from tsim import backend
from tsim.backend import spirv
from tsim.backend.runtime import PROFILE_SKIP, ti
from tsim.backend.spirv import (
    BEGIN,
    CONTACTS,
    END,
    MOVE,
    ST_COUNT,
    ST_STATUS,
    SUBSTEPS,
    Slice,
    global_scratch,
    laps,
)
from tsim.kernels.contacts import contacts
from tsim.kernels.lanes import incidence_sizes, move_lanes, own, sync
from tsim.kernels.layout import (
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
from tsim.kernels.scratch import Part, Scratch, Terrain
from tsim.kernels.step import load_edges, load_points, store_world, terrain_top

MAX_LANES = 1024  # a thread block's most threads (CUDA, and Vulkan's guaranteed minimum is 128)


def check_lanes(lanes: object) -> int:
    """`lanes` as the lanes per world, or ValueError: a power of two from 1 to MAX_LANES."""
    if not (isinstance(lanes, int) and not isinstance(lanes, bool) and 1 <= lanes <= MAX_LANES
            and lanes & (lanes - 1) == 0):
        raise ValueError(f"lanes must be a power of two from 1 to {MAX_LANES}, got {lanes!r}")
    return lanes


# the scratch arrays the lanes read and write in every phase of a substep: in shared memory for a
# launch of substeps where they fit (`fits_shared`), copied in at its start and out at its end
# (not fcol: the contacts add into it with `+=`, an atomic on these arrays, see tsim/kernels/lanes.py)
SHARED_REAL = ("pos", "vel", "pl", "vt", "xs", "vs", "frc", "adx", "adv", "plo", "vlo", "pllo",
               "xlo", "e0", "leq", "ek", "egoal", "erest", "ccx", "ccy")
SHARED_INT = ("ea", "eb")
SHARED_BYTES = 32 * 1024  # lavapipe's shared memory per workgroup; a CUDA block may have 48 KB


def shared_lengths(pc: int, ec: int, sc: int) -> tuple[int, int]:
    """Per world, the lengths of the real and the i32 shared arrays (`SHARED_REAL`, `SHARED_INT`)."""
    real, ints = spirv.real_sizes(pc, ec, sc), spirv.int_sizes(pc, ec, sc)
    return sum(real[k] for k in SHARED_REAL), sum(ints[k] for k in SHARED_INT)


def fits_shared(pc: int, ec: int, sc: int) -> bool:
    """Whether a world's `SHARED_REAL` and `SHARED_INT` arrays fit SHARED_BYTES (tier 0 does: ~19 KB
    in f64; tier 1 does not)."""
    nf, ni = shared_lengths(pc, ec, sc)
    return nf * np.dtype(backend.real().dtype).itemsize + 4 * ni <= SHARED_BYTES


def shared_layout(pc: int, ec: int, sc: int) -> tuple:
    """The shared arrays' lengths (`shared_lengths`) and Taichi's real type of the process."""
    return (*shared_lengths(pc, ec, sc), getattr(ti, backend.real().taichi))


def shared_scratch(s: Scratch, shf, shi, pc: int, ec: int, sc: int) -> tuple[Scratch, tuple]:
    """The scratch s with its `SHARED_REAL` and `SHARED_INT` arrays as slices of the shared arrays
    shf and shi, and the copies between them: ((shared, global, length), ...)."""
    real, ints = spirv.real_sizes(pc, ec, sc), spirv.int_sizes(pc, ec, sc)
    fields = {}
    plan = []
    for arr, names, sizes in ((shf, SHARED_REAL, real), (shi, SHARED_INT, ints)):
        off = 0
        for name in names:
            fields[name] = Slice(arr, off, sizes[name])
            plan.append((fields[name], getattr(s, name), sizes[name]))
            off += sizes[name]
    return s._replace(**fields), tuple(plan)


class Incidence(NamedTuple):
    """A world's incidence lists (`kernels.lanes.incidence_sizes`)."""

    ist: Slice
    imid: Slice
    inc: Slice


def incidence(arr, b, pc: int, ec: int) -> Incidence:
    """World b's incidence lists as slices of the global i32 array arr."""
    sizes = incidence_sizes(pc, ec)
    per_world = sum(sizes.values())
    out = {}
    off = 0
    for name, n in sizes.items():
        out[name] = Slice(arr, b * per_world + off, n)
        off += n
    return Incidence(**out)


def incidence_lists(edge_i: np.ndarray, n_edges: np.ndarray, pc: int, ec: int, n: int) -> np.ndarray:
    """Every world's incidence lists, flat, world after world (`incidence`; n worlds' room, the
    batch tier): per point p its first ends' edges then its second ends' edges, each ascending,
    from edge_i (B, E, 4) of which world b's first n_edges[b] rows are its edges."""
    B, E = edge_i.shape[:2]
    valid = np.arange(E)[None, :] < np.asarray(n_edges)[:, None]
    w = np.broadcast_to(np.arange(B)[:, None], (B, E))[valid]
    e = np.broadcast_to(np.arange(E)[None, :], (B, E))[valid]
    ends = [edge_i[:, :, k][valid].astype(np.int64) for k in (0, 1)]
    per = [np.bincount(w * pc + x, minlength=B * pc).reshape(B, pc) for x in ends]
    ist = np.zeros((B, pc + 1), dtype=np.int64)
    ist[:, 1:] = np.cumsum(per[0] + per[1], axis=1)
    imid = ist[:, :pc] + per[0]
    inc = np.zeros((B, 2 * ec), dtype=np.int64)
    for x, base in zip(ends, (ist[:, :pc], imid), strict=True):
        key = w * pc + x
        order = np.argsort(key, kind="stable")  # (world, edge) order within a point: ascending
        k = key[order]
        rank = np.arange(len(k)) - np.searchsorted(k, k, "left")
        inc[w[order], base.reshape(-1)[k] + rank] = e[order]
    out = np.zeros((n, sum(incidence_sizes(pc, ec).values())), dtype=np.int32)
    out[:B] = np.concatenate([ist, imid, inc], axis=1)
    return out.reshape(-1)


@ti.func
def contacts_lane0(b, counts: ti.template(), s: ti.template(), slots: ti.template(),
                   ter_f: ti.template(), ter_i: ti.template(), ter_grid: ti.template(),
                   sweep_mode: ti.template(), pair_list: ti.template(), part: ti.template(), last):
    """`spirv.contacts_of` (a substep's contacts, serial: lane 0 calls it)."""
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
def move_all(b, lane, lanes: ti.template(), counts: ti.template(), vox_i: ti.template(),
             lists: ti.template(), s: ti.template(), inc: ti.template(), slots: ti.template()):
    """A running world's substep after its contacts, on every lane (`spirv.move_of`); every lane
    reads the status before lane 0 may write it. Starts after and ends at a barrier."""
    running = slots[ST_STATUS] == RUNNING
    sync()
    if running:
        move_lanes(b, counts[b, N_PTS], counts[b, N_EDGES], lane, lanes, counts, vox_i, lists, s, inc)
        if lane == 0:
            if slots[ST_COUNT] > counts[b, N_SURF_ROBOT]:
                slots[ST_STATUS] = UNSTABLE
    sync()


@ti.func
def copy_over(plan: ti.template(), lane, lanes: ti.template(), into_shared: ti.template()):
    """Each (shared, global, length) of `plan` copied whole, into the shared array or out of it,
    the entries dealt to the lanes."""
    for i in ti.static(range(len(plan))):
        for k in range(own(plan[i][2], lane, lanes)):
            j = lane + k * lanes
            if ti.static(into_shared):
                plan[i][0][j] = plan[i][1][j]
            else:
                plan[i][1][j] = plan[i][0][j]


@ti.func
def substeps(b, lane, lanes: ti.template(), n_sub, counts: ti.template(), vox_i: ti.template(),
             lists: ti.template(), ter_f: ti.template(), ter_i: ti.template(), ter_grid: ti.template(),
             sweep_mode: ti.template(), pair_list: ti.template(), s: ti.template(), inc: ti.template(),
             slots: ti.template()):
    """n_sub substeps of a world: each its contacts on lane 0, then the rest on every lane."""
    for _ in range(n_sub):
        running = slots[ST_STATUS] == RUNNING
        sync()  # every lane has read the status before lane 0 may change it
        if running:
            if lane == 0:
                contacts_lane0(b, counts, s, slots, ter_f, ter_i, ter_grid, sweep_mode, pair_list, None,
                               True)
            sync()
            move_all(b, lane, lanes, counts, vox_i, lists, s, inc, slots)


@ti.kernel
def lanes_kernel(phase: ti.template(), counts: I32_2, state: REAL_1, edge_i: I32_1, edge_f: REAL_1,
                 vox_i: I32_3, lists: I32_3, actions: REAL_2, ter_f: REAL_2, ter_i: I32_2,
                 ter_grid: I32_2, n_sub: ti.i32, P: ti.i32, E: ti.i32, pc: ti.template(),
                 ec: ti.template(), sc: ti.template(), sweep_mode: ti.template(),
                 pair_list: ti.template(), block: ti.template(), n: ti.template(), gf: REAL_1,
                 gi: I32_1, piece: ti.i32, pieces: ti.i32, overrun: I32_1, lanes: ti.template(),
                 gl: I32_1, shared: ti.template()):
    """`spirv.phase_kernel` with `lanes` threads per world (one thread block each; `block` is
    unused): thread t runs lane t % lanes of world t // lanes. BEGIN and END (once per env step),
    and a substep's contacts, run on lane 0; the rest of a substep on every lane. gl holds the
    worlds' incidence lists (`incidence`); overrun[t] = 1 where the driver's loop budget ran out
    in thread t."""
    ti.loop_config(block_dim=lanes)
    for t in range(n * lanes):
        b = t // lanes
        lane = t % lanes
        if b < counts.shape[0]:
            w = ti.static(global_scratch(gf, gi, b, pc, ec, sc))
            s = ti.static(w.s)
            inc = ti.static(incidence(gl, b, pc, ec))
            if ti.static(phase == BEGIN):
                if lane == 0:
                    w.slots[ST_STATUS] = counts[b, STATUS]
                    if counts[b, STATUS] == RUNNING:
                        ns = ti.static(state_columns())
                        s.sweep[0] = -1
                        s.sweep[1] = 0
                        s.plist[0] = 0
                        s.one[0] = 1.0
                        for i in range(counts[b, N_SURF]):
                            s.order[i] = i
                        if ti.static(pairs()):
                            for i in range(2 * counts[b, N_PTS]):
                                s.plo[i] = 0.0
                                s.vlo[i] = 0.0
                                s.pllo[i] = 0.0
                        load_edges(b, counts[b, N_EDGES], b * E * 4, b * E * N_EDGE_F, edge_i, edge_f,
                                   actions, s.ea, s.eb, s.ek, s.egoal, s.erest, s.leq)
                        load_points(b, counts[b, N_PTS], b * P * ns, counts, state, vox_i, lists, s)
            if ti.static(phase == SUBSTEPS):
                if ti.static(shared):  # the substeps' arrays in shared memory, copied in and out
                    nsh = ti.static(shared_layout(pc, ec, sc))
                    shf = ti.simt.block.SharedArray((nsh[0],), nsh[2])
                    shi = ti.simt.block.SharedArray((nsh[1],), ti.i32)
                    sh = ti.static(shared_scratch(s, shf, shi, pc, ec, sc))
                    copy_over(sh[1], lane, lanes, True)
                    sync()
                    substeps(b, lane, lanes, n_sub, counts, vox_i, lists, ter_f, ter_i, ter_grid,
                             sweep_mode, pair_list, sh[0], inc, w.slots)
                    copy_over(sh[1], lane, lanes, False)
                else:
                    substeps(b, lane, lanes, n_sub, counts, vox_i, lists, ter_f, ter_i, ter_grid,
                             sweep_mode, pair_list, s, inc, w.slots)
            if ti.static(phase == CONTACTS):
                if lane == 0:
                    if w.slots[ST_STATUS] == RUNNING:
                        part = ti.static(Part(piece=piece, pieces=pieces, i=w.part_i, f=w.part_f))
                        contacts_lane0(b, counts, s, w.slots, ter_f, ter_i, ter_grid, sweep_mode,
                                       pair_list, part, piece == pieces - 1)
            if ti.static(phase == MOVE):
                move_all(b, lane, lanes, counts, vox_i, lists, s, inc, w.slots)
            if ti.static(phase == END):
                if lane == 0:
                    if counts[b, STATUS] == RUNNING:
                        store_world(b, counts[b, N_PTS], b * P * ti.static(state_columns()), counts,
                                    state, w.slots[ST_STATUS], s)
            # every thread's own entry, written whatever it finds (`spirv.phase_kernel`)
            overrun[t] = ti.select(laps(n_sub + 1) == n_sub + 1, 0, 1)


class LanesLauncher(spirv.Launcher):
    """`spirv.Launcher` (BEGIN, substeps in launches that fit the driver's loop budget, END)
    launching `lanes_kernel` with `lanes` lanes per world."""

    def __init__(self, n_worlds: int, lanes: int, shared: bool = True):
        super().__init__(n_worlds)
        self.lanes = check_lanes(lanes)
        self.shared = shared  # a launch of substeps in shared memory where the arrays fit
        self.launched_shared = False  # whether one did (tests read it)
        self.overrun = np.zeros(n_worlds * lanes, dtype=np.int32)
        self._incidence: tuple | None = None

    def _incidence_for(self, args: tuple):
        """The worlds' incidence lists (`incidence_lists`), made at the first launch (edges do not
        change) and kept on the device."""
        pc, ec = args[spirv.PC_ARG:spirv.PC_ARG + 2]
        n = args[-1]
        if self._incidence is None or self._incidence[1] != (pc, ec, n):
            counts, edge_i = args[0], args[2]
            flat = edge_i if isinstance(edge_i, np.ndarray) else edge_i.to_numpy()
            lists = incidence_lists(flat.reshape(counts.shape[0], -1, 4), counts[:, N_EDGES], pc, ec, n)
            arr = ti.ndarray(ti.i32, lists.shape[0])
            arr.from_numpy(lists)
            self._incidence = (arr, (pc, ec, n))
        return self._incidence[0]

    def _launch(self, phase: int, args: tuple, gf, gi, n_sub: int, piece: int = 0,
                pieces: int = 1) -> bool:
        """One launch of `phase`; False if the driver's loop budget ran out in it."""
        shared = phase == SUBSTEPS and self.shared and fits_shared(*args[spirv.PC_ARG:spirv.PC_ARG + 3])
        self.launched_shared |= shared
        lanes_kernel(phase, *args[:spirv.N_SUB_ARG], n_sub, *args[spirv.N_SUB_ARG + 1:], gf, gi, piece,
                     pieces, self.overrun, self.lanes, self._incidence_for(args), shared)
        return not self.overrun.any()
