"""The step kernels: one env step of every world in the batch, evogym's substep repeated n_sub times.

Design: one parallel loop over worlds with serial inner loops over that world's points, springs and
voxels (cache-friendly, no atomics). Each world does all its substeps in one kernel launch, with
its state copied into local arrays (`scratch.Scratch`; see the note in `layout`). A substep is the
pipeline contacts (`contacts`: broad then narrow phase) -> integration (`integrate.rk4`) -> fixed
points -> constraints (`constraints`) -> the new snapshot.
"""

from tsim.backend.runtime import PROFILE_SKIP, ti
from tsim.kernels.broadphase import LIST_PER_VOXEL
from tsim.kernels.constraints import constraints
from tsim.kernels.contacts import contacts
from tsim.kernels.integrate import hold_fixed, rk4, snapshot
from tsim.kernels.layout import (
    E_GOAL,
    E_K,
    E_LEQ,
    E_REST,
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
    S_LO_OF,
    S_POS_LO,
    S_VEL_LO,
    STATUS,
    UNSTABLE,
    V_COL,
    V_OBJ,
    V_OPEN,
    V_PTS,
    V_ROW,
    pairs,
    state_columns,
)
from tsim.kernels.scratch import Scratch, Terrain


@ti.func
def load_edges(b, n_edges, eio, efo, edge_i: ti.template(), edge_f: ti.template(),
               actions: ti.template(), ea: ti.template(), eb: ti.template(), ek: ti.template(),
               egoal: ti.template(), erest: ti.template(), leq: ti.template()):
    """World b's n_edges springs (from eio in edge_i, efo in edge_f) into its scratch at the start
    of an env step: ends, stiffness, rest lengths and goals (from the actions); in f32, leq gets
    the rounding of each spring's initial length (edge_f's E_LEQ column, `springs`)."""
    for e in range(n_edges):
        ea[e] = edge_i[eio + 4 * e]
        eb[e] = edge_i[eio + 4 * e + 1]
        ek[e] = edge_f[efo + N_EDGE_F * e + E_K]
        erest[e] = edge_f[efo + N_EDGE_F * e + E_REST]
        egoal[e] = edge_f[efo + N_EDGE_F * e + E_GOAL]  # the rest length, unless driven:
        d0 = edge_i[eio + 4 * e + 2]
        if d0 >= 0:  # the mean of its actuators' targets times its rest length
            d1 = edge_i[eio + 4 * e + 3]
            total = actions[b, d0]
            cnt = 1.0
            if d1 >= 0:
                total += actions[b, d1]
                cnt = 2.0
            egoal[e] = total * (erest[e] / cnt)
        if ti.static(pairs()):  # f32: the rounding of the edge's initial length (`springs`)
            leq[e] = edge_f[efo + N_EDGE_F * e + E_LEQ]


@ti.func
def load_points(b, n_pts, so, counts: ti.template(), state: ti.template(), vox_i: ti.template(),
                lists: ti.template(), s: ti.template()):
    """World b's surface voxels and n_pts points (from so in state) into its scratch s at the
    start of an env step."""
    ns = ti.static(state_columns())
    for i in range(counts[b, N_SURF]):
        v = lists[b, i, 0]
        for k in ti.static(range(4)):
            s.sv[8 * i + k] = vox_i[b, v, V_PTS + k]
            s.sv[8 * i + 4 + k] = vox_i[b, v, V_OPEN + k]
        s.sm[4 * i] = vox_i[b, v, V_OBJ]
        s.sm[4 * i + 1] = vox_i[b, v, V_ROW]
        s.sm[4 * i + 2] = vox_i[b, v, V_COL]
    for p in range(n_pts):
        for d in ti.static(range(2)):
            s.pos[2 * p + d] = state[so + ns * p + d]
            s.vel[2 * p + d] = state[so + ns * p + 2 + d]
            s.pl[2 * p + d] = state[so + ns * p + 4 + d]
            s.vt[2 * p + d] = state[so + ns * p + 6 + d]
            if ti.static(pairs()):
                # the low parts hold only for the positions they were stored with: a state
                # written from outside (reset, evogym's revert) starts with none
                if state[so + ns * p + S_LO_OF + d] == s.pos[2 * p + d]:
                    s.plo[2 * p + d] = state[so + ns * p + S_POS_LO + d]
                    s.vlo[2 * p + d] = state[so + ns * p + S_VEL_LO + d]
                if s.pl[2 * p + d] == s.pos[2 * p + d]:
                    s.pllo[2 * p + d] = s.plo[2 * p + d]


@ti.func
def terrain_top(ter_f: ti.template()):
    """The highest top of a terrain voxel's box."""
    ter_top = ter_f[0, 11]
    for t in range(1, ter_f.shape[0]):
        ter_top = ti.max(ter_top, ter_f[t, 11])
    return ter_top


@ti.func
def move(b, n_pts, n_edges, counts: ti.template(), vox_i: ti.template(), lists: ti.template(),
         s: ti.template()):
    """A substep after its contacts: integration, fixed points, constraints, the new snapshot."""
    rk4(n_pts, n_edges, s)
    hold_fixed(b, counts, lists, s)
    if ti.static("constraints" not in PROFILE_SKIP):
        constraints(b, n_edges, counts, vox_i, lists, s)
    for i in range(2 * n_pts):
        snapshot(i, s)


@ti.func
def store_world(b, n_pts, so, counts: ti.template(), state: ti.template(), status,
                s: ti.template()):
    """The end of world b's env step: its scratch back into the state (n_pts points from so) if
    it is still running and finite, else its last snapshot kept and its status set."""
    ns = ti.static(state_columns())
    if status == RUNNING:
        for i in range(2 * n_pts):
            if not (ti.abs(s.pos[i]) < 1e30 and ti.abs(s.vel[i]) < 1e30):
                status = NONFINITE
    if status == RUNNING:
        for p in range(n_pts):
            for d in ti.static(range(2)):
                state[so + ns * p + d] = s.pos[2 * p + d]
                state[so + ns * p + 2 + d] = s.vel[2 * p + d]
                state[so + ns * p + 4 + d] = s.pl[2 * p + d]
                state[so + ns * p + 6 + d] = s.vt[2 * p + d]
                if ti.static(pairs()):
                    state[so + ns * p + S_POS_LO + d] = s.plo[2 * p + d]
                    state[so + ns * p + S_VEL_LO + d] = s.vlo[2 * p + d]
                    state[so + ns * p + S_LO_OF + d] = s.pos[2 * p + d]
    else:
        # evogym keeps the last snapshot: the step never happened for observers
        for p in range(n_pts):
            for d in ti.static(range(2)):
                state[so + ns * p + 4 + d] = state[so + ns * p + d]
                state[so + ns * p + 6 + d] = 0.0
        counts[b, STATUS] = status


@ti.func
def step_world(b, counts: ti.template(), state: ti.template(), edge_i: ti.template(),
               edge_f: ti.template(), vox_i: ti.template(), lists: ti.template(),
               actions: ti.template(), ter_f: ti.template(), ter_i: ti.template(),
               ter_grid: ti.template(), n_sub, P, E, pc: ti.template(), ec: ti.template(),
               sc: ti.template(), sweep_mode: ti.template(), pair_list: ti.template()):
    """One env step of world b (see `step_kernel`), with local arrays of capacity pc, ec, sc."""
    if counts[b, STATUS] == RUNNING:
        n_pts = counts[b, N_PTS]
        n_edges = counts[b, N_EDGES]
        ns = ti.static(state_columns())
        so = b * P * ns
        eio = b * E * 4
        efo = b * E * N_EDGE_F
        # the scratch's arrays are made one by one (each assignment makes a local array), then
        # handed on together. They start from a zero the compiler cannot fold (+0.0: counts are
        # >= 0): Taichi folds constant elements one by one at a cost that grows with the whole
        # kernel, so at tier 3 (~20,000 elements) `ti.Vector.zero` took 24 s of a 45 s compile;
        # now ~13 s. Same values, same results.
        zf = ti.cast(counts[b, N_PTS], float) * 0.0
        zi = counts[b, N_PTS] * 0
        pos = ti.Vector([zf] * (2 * pc))
        vel = ti.Vector([zf] * (2 * pc))
        pl = ti.Vector([zf] * (2 * pc))
        vt = ti.Vector([zf] * (2 * pc))
        xs = ti.Vector([zf] * (2 * pc))
        vs = ti.Vector([zf] * (2 * pc))
        frc = ti.Vector([zf] * (2 * pc))
        fcol = ti.Vector([zf] * (2 * pc))
        adx = ti.Vector([zf] * (2 * pc))
        adv = ti.Vector([zf] * (2 * pc))
        lc = ti.static(2 * pc if pairs() else 1)  # the low parts of f32's pairs (`pairs`)
        plo = ti.Vector([zf] * lc)
        vlo = ti.Vector([zf] * lc)
        pllo = ti.Vector([zf] * lc)
        xlo = ti.Vector([zf] * lc)
        e0 = ti.Vector([zf] * ti.static(4 * ec if pairs() else 1))
        leq = ti.Vector([zf] * ec)
        ea = ti.Vector([zi] * ec, ti.i32)
        eb = ti.Vector([zi] * ec, ti.i32)
        ek = ti.Vector([zf] * ec)
        egoal = ti.Vector([zf] * ec)
        erest = ti.Vector([zf] * ec)
        load_edges(b, n_edges, eio, efo, edge_i, edge_f, actions, ea, eb, ek, egoal, erest, leq)
        ccx = ti.Vector([zf] * ec)
        ccy = ti.Vector([zf] * ec)
        box = ti.Vector([zf] * (4 * sc))
        sv = ti.Vector([zi] * (8 * sc), ti.i32)
        sm = ti.Vector([zi] * (4 * sc), ti.i32)
        order = ti.Vector([zi] * sc, ti.i32)
        rank = ti.Vector([zi] * sc, ti.i32)
        cand = ti.Vector([zi] * sc, ti.i32)
        nbr = ti.Vector([zi] * (LIST_PER_VOXEL * sc), ti.i32)
        nstart = ti.Vector([zi] * (sc + 1), ti.i32)
        refbox = ti.Vector([zf] * (4 * sc))
        plist = ti.Vector([0])
        for i in range(counts[b, N_SURF]):
            order[i] = i
        sweep = ti.Vector([-1, 0])
        s = ti.static(Scratch(pos=pos, vel=vel, pl=pl, vt=vt, xs=xs, vs=vs, frc=frc, fcol=fcol,
                              adx=adx, adv=adv, plo=plo, vlo=vlo, pllo=pllo, xlo=xlo, e0=e0,
                              leq=leq, ea=ea, eb=eb, ek=ek, egoal=egoal, erest=erest, ccx=ccx, ccy=ccy,
                              box=box, sv=sv, sm=sm, order=order, rank=rank, cand=cand,
                              sweep=sweep, nbr=nbr, nstart=nstart, refbox=refbox, plist=plist,
                              one=None))
        load_points(b, n_pts, so, counts, state, vox_i, lists, s)
        ter_top = terrain_top(ter_f)
        ter = ti.static(Terrain(f=ter_f, i=ter_i, grid=ter_grid, top=ter_top))
        status = RUNNING
        for _ in range(n_sub):
            if status == RUNNING:
                count = 0
                if ti.static("contacts" not in PROFILE_SKIP):
                    count = contacts(b, n_pts, counts, s, ter, sweep_mode, pair_list, None)
                if count < 0:
                    status = NONFINITE
                else:
                    move(b, n_pts, n_edges, counts, vox_i, lists, s)
                    if count > counts[b, N_SURF_ROBOT]:
                        status = UNSTABLE
        store_world(b, n_pts, so, counts, state, status, s)


@ti.kernel
def step_kernel(counts: I32_2, state: REAL_1, edge_i: I32_1, edge_f: REAL_1, vox_i: I32_3,
                lists: I32_3, actions: REAL_2, ter_f: REAL_2, ter_i: I32_2, ter_grid: I32_2,
                n_sub: ti.i32, P: ti.i32, E: ti.i32, pc: ti.template(), ec: ti.template(),
                sc: ti.template(), sweep_mode: ti.template(), pair_list: ti.template(),
                block: ti.template()):
    """One env step (n_sub substeps) of every running world, worlds in parallel (`block` worlds
    per thread block: 1 on a CPU, where Taichi deals blocks to its threads, a warp's multiple on
    a GPU). state, edge_i and edge_f are flat views of the (B, P, 8), (B, E, 4) and (B, E, 4)
    arrays; every world fits the capacity (pc points, ec edges, sc surface voxels). Real arrays
    are of the process's real type."""
    ti.loop_config(block_dim=block)
    for b in range(counts.shape[0]):
        step_world(b, counts, state, edge_i, edge_f, vox_i, lists, actions, ter_f, ter_i,
                   ter_grid, n_sub, P, E, pc, ec, sc, sweep_mode, pair_list)


@ti.kernel
def step_kernel_serial(counts: I32_2, state: REAL_1, edge_i: I32_1, edge_f: REAL_1, vox_i: I32_3,
                       lists: I32_3, actions: REAL_2, ter_f: REAL_2, ter_i: I32_2,
                       ter_grid: I32_2, n_sub: ti.i32, P: ti.i32, E: ti.i32, pc: ti.template(),
                       ec: ti.template(), sc: ti.template(), sweep_mode: ti.template(),
                       pair_list: ti.template()):
    """`step_kernel` on the calling thread: for single-threaded processes, where handing the loop
    to Taichi's thread pool costs ~0.15 ms per launch (measured on the 2-vCPU VM)."""
    ti.loop_config(serialize=True)
    for b in range(counts.shape[0]):
        step_world(b, counts, state, edge_i, edge_f, vox_i, lists, actions, ter_f, ter_i,
                   ter_grid, n_sub, P, E, pc, ec, sc, sweep_mode, pair_list)
