"""Physical constants and material codes of evogym 2.0.0 (spec appendix A).

Every number here is evogym's; changing one changes the physics and breaks parity with the
recorded reference trajectories.
"""

from __future__ import annotations

import math

# --- material codes (evogym VOXEL_TYPES) ---------------------------------------------------------
EMPTY = 0
RIGID = 1
SOFT = 2
H_ACT = 3
V_ACT = 4
FIXED = 5
MATERIAL_NAMES = {EMPTY: "empty", RIGID: "rigid", SOFT: "soft", H_ACT: "h_act", V_ACT: "v_act",
                  FIXED: "fixed"}

# --- geometry -------------------------------------------------------------------------------------
CELL = 0.1  # voxel edge length in world units
MAIN_REST = abs(CELL)
DIAG_REST = math.sqrt(CELL * CELL + CELL * CELL)  # = 0.14142135623730951
POINT_MASS = 1.0

# --- spring constants (nominal; static stiffness is 0.006 x these) ------------------------------
K_RIGID_MAIN = 3e8 / 3.5
K_RIGID_DIAG = 3e8 / 7.0
K_SOFT_MAIN = 3e8 / 6.0
K_SOFT_DIAG = K_SOFT_MAIN / 4.0
K_ACT_MAIN = 3e8 / 5.0
K_ACT_DIAG = K_ACT_MAIN / 2.0

# --- dynamics -------------------------------------------------------------------------------------
DT = 1e-4
SUBSTEPS = 30
GRAVITY = 110.0
VISCOUS_DRAG = 0.1
GROUND_K = 2000000.0 * 7  # y < 0 plane stiffness
FRICTION_DYN = 0.2  # dynamic_friction_const
CONTACT_K = 300000.0 * 7
CONTACT_OFFSET = 0.005
CONTACT_VEL_DAMPING = 140.0
CONTACT_FRICTION = 150.0 * 8
PARALLEL_EPS = 1e-4
DEGENERATE_EDGE = 1e-6
# ours, not evogym's: a corner farther than this outside a voxel's bounding box skips the exact
# point-in-voxel test. That test fails there (rounding errors are ~1e-15 at these coordinates)
# except for a corner exactly on the line through the voxel's TL-BR diagonal, which evogym's test
# calls inside however far away; see docs/VALIDATION.md
BOX_MARGIN = 1e-9
REST_CONVERGENCE = 0.006
EDGE_BAND = 0.25
EDGE_BAND_RIGID = 0.03

ACTION_MIN = 0.6
ACTION_MAX = 1.6
