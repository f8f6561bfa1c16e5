"""One world's scratch: the local arrays an env step works in, passed to every stage as one value.

A `Scratch` is made inside the step kernel (`step.step_world`) from local Taichi vectors and handed
to the stages' functions as a compile-time argument (`ti.template()`); Taichi inlines them, so the
code is the same as with the arrays passed one by one. Points are interleaved x, y (index 2p + d).
"""

from __future__ import annotations

from typing import NamedTuple


class Scratch(NamedTuple):
    """Local arrays of one world (capacity pc points, ec edges, sc surface voxels)."""

    # points (2 pc): the substep's state, RK4 stages and forces
    pos: object  # position
    vel: object  # velocity
    pl: object  # pos_last: position at the start of the substep
    vt: object  # vel_true: (pos - pos_last) / dt of the last substep, contacts' damping reads it
    xs: object  # an RK4 stage's position
    vs: object  # an RK4 stage's velocity
    frc: object  # an RK4 stage's spring forces
    fcol: object  # contact forces, frozen across the RK4 stages
    adx: object  # the weighted sum of the stages' position increments
    adv: object  # the same for velocity
    # f32 only (`pairs`; capacity 1 and unused in f64): the low parts of pos, vel and pl, an
    # RK4 stage's offset from the substep's position, and per edge its stage-0 vector, length and
    # stretch (4 ec; `springs.spring_forces`)
    plo: object
    vlo: object
    pllo: object
    xlo: object
    e0: object
    # springs (ec), contiguous: their ends, stiffness, goal and rest lengths; per-edge outputs
    leq: object  # current rest length (set at RK4 stage 0); f32: edge_f's E_LEQ column (`layout`)
    ea: object
    eb: object
    ek: object
    egoal: object
    erest: object
    ccx: object  # per-edge vectors (spring forces, constraint corrections) before their scatter
    ccy: object
    # surface voxels (sc): boxes (x0, x1, y0, y1), corners and open sides, object, row, col
    box: object
    sv: object
    sm: object
    # sweep and prune (`broadphase`): order along the axis, rank in it, candidates, the decision
    order: object
    rank: object
    cand: object
    sweep: object  # [-1 undecided / 0 plain loop / 1 sweep, axis]
    # the pair list (`broadphase.SKIN`): partners, their starts, the boxes when listed, valid
    nbr: object
    nstart: object
    refbox: object
    plist: object
    # None in local scratch (the CPU); in the SPIR-V global scratch one real holding 1.0, read at
    # run time by f32's two-sum (`pairs.renormalize` says why)
    one: object


class Terrain(NamedTuple):
    """The batch's terrain ndarrays (see `layout`) and the highest top of a terrain voxel."""

    f: object
    i: object
    grid: object
    top: object


# a `Part`'s slots: i32 (what one piece of a substep's contacts hands the next, `contacts`)
P_COUNT, P_N_LIST, P_FITS, P_FINITE = range(4)
N_PART_I = 4
P_WX, P_WY = range(2)  # real
N_PART_F = 2


class Part(NamedTuple):
    """Piece `piece` of `pieces` of a substep's contacts (`contacts.contacts`, SPIR-V only), with
    the slots `i` (i32, P_COUNT ...) and `f` (real, P_WX, P_WY) that the pieces share."""

    piece: object
    pieces: object
    i: object
    f: object


def pieced(part: Part | None) -> bool:
    """Whether `contacts` runs one piece (`part`) of a substep's contacts, not all (None)."""
    return part is not None
