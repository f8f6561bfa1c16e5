"""Taichi kernels: one env step of every world in the batch, evogym's substep repeated 30 times.

One physics stage per module, in the order a substep runs them (as brax lays out its pipeline):
- `layout`: the arrays' columns, status codes, capacity tiers, the real type's tolerances;
- `scratch`: one world's local arrays, passed to every stage as one `Scratch`;
- `geometry`: point-in-voxel, segment and distance tests;
- `broadphase`: which voxel pairs may touch (plain loop, sweep and prune, pair lists);
- `narrowphase`: evogym's voxel-voxel contact force between two quads;
- `contacts`: a substep's boxes, pairs and contact forces (broad then narrow phase);
- `springs`: spring forces and their scatter in evogym's order;
- `pairs`: f32's positions and velocities as float32 pairs hi + lo;
- `integrate`: RK4 and the fixed points;
- `constraints`: the edge-length bands;
- `step`: the kernels that run the substeps of every world.

The source is one for both real types: arrays and locals take the process's real type (f64 by
default, f32 on request: `tsim.backend.runtime.init`), fixed before the first kernel compiles.
"""

from tsim.kernels.broadphase import (
                                     LIST_ALWAYS,
                                     LIST_AUTO,
                                     LIST_MIN,
                                     LIST_OFF,
                                     LIST_PER_VOXEL,
                                     SKIN,
                                     SWEEP_ALWAYS,
                                     SWEEP_AUTO,
                                     SWEEP_MIN,
                                     SWEEP_OFF,
                                     SWEEP_RATIO,
)
from tsim.kernels.layout import (
                                     E_GOAL,
                                     E_K,
                                     E_LEQ,
                                     E_REST,
                                     EC,
                                     GPU_BLOCK,
                                     INACTIVE,
                                     N_ACT,
                                     N_COUNTS,
                                     N_EDGE_F,
                                     N_EDGES,
                                     N_FIXED,
                                     N_PTS,
                                     N_RIGID,
                                     N_SURF,
                                     N_SURF_ROBOT,
                                     N_TER_F_PAIRS,
                                     N_VOX,
                                     N_VOX_I,
                                     NONFINITE,
                                     NS,
                                     PC,
                                     RUNNING,
                                     S_LO_OF,
                                     S_POS_LO,
                                     S_VEL_LO,
                                     SC,
                                     STATUS,
                                     TER_LO,
                                     TOLERANCES,
                                     UNSTABLE,
                                     V_COL,
                                     V_OBJ,
                                     V_OPEN,
                                     V_PTS,
                                     V_ROW,
                                     V_TYPE,
                                     Tolerances,
                                     capacity,
                                     pairs,
                                     state_columns,
                                     tol,
)
from tsim.kernels.step import step_kernel, step_kernel_serial

__all__ = ["E_GOAL", "E_K", "E_LEQ", "E_REST", "EC", "GPU_BLOCK", "INACTIVE", "LIST_ALWAYS", "LIST_AUTO",
           "LIST_MIN", "LIST_OFF", "LIST_PER_VOXEL", "N_ACT", "N_COUNTS", "N_EDGE_F", "N_EDGES", "N_FIXED",
           "N_PTS", "N_RIGID", "N_SURF", "N_SURF_ROBOT", "N_TER_F_PAIRS", "N_VOX", "N_VOX_I", "NONFINITE",
           "NS", "PC", "RUNNING", "S_LO_OF", "S_POS_LO", "S_VEL_LO", "SC", "SKIN", "STATUS", "SWEEP_ALWAYS",
           "SWEEP_AUTO", "SWEEP_MIN", "SWEEP_OFF", "SWEEP_RATIO", "TER_LO", "TOLERANCES", "UNSTABLE",
           "V_COL", "V_OBJ", "V_OPEN", "V_PTS", "V_ROW", "V_TYPE", "Tolerances", "capacity", "pairs",
           "state_columns", "step_kernel", "step_kernel_serial", "tol"]
