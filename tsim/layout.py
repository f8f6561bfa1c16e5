"""A batch's layout: the padded per-world arrays the kernels read, built from bodies, objects and
terrain with numpy alone (no Taichi, no backend).

Each world b holds its robot's points, edges and voxels first, then every free object's, padded to
the batch's largest world. `build_layout` places them exactly as evogym does (`Body.place`'s order,
in float64), so the f64 physics starts from evogym's bits; `tsim.sim.BatchSim` then rounds the
placement for f32 and chooses how to launch the kernels on it.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from tsim import constants as C
from tsim import kernels as K
from tsim.bodybatch import BodyBatch
from tsim.world import Terrain, WorldObject


@dataclass
class Layout:
    """The padded arrays of B worlds (P points, E edges, V voxels at most per world).

    Attributes:
        pos0: (B, P, 2) float64, evogym's initial placement of every point.
        rest_f64: (B, E) float64, every edge's rest length.
        edge_i: (B, E, 4) int32, an edge's two points and its two actuators (-1: none).
        edge_f: (B, E, K.N_EDGE_F) in the real type: rest, stiffness, goal and current rest.
        vox_i: (B, V, K.N_VOX_I) int32: a voxel's corners, open sides, material, object and cell.
        lists: (B, max(V, fixed), 3) int32: surface voxels, rigid voxels, fixed points.
        counts: (B, K.N_COUNTS) int32: each world's sizes (points, edges, voxels, lists, actuators).
        ter_f: (T, 12) float64: each terrain voxel's corners, then its box.
        ter_i: (T, 4) int32: each terrain voxel's open sides.
        obj_offsets: per free object, (B,) the index of its first point in each world.
        n_robot_points: (B,) each robot's points.
        n_actuators: (B,) each robot's actuators.
        n_actions: the action columns (robots' actuators, then actuated objects'; at least 1).
    """

    pos0: np.ndarray
    rest_f64: np.ndarray
    edge_i: np.ndarray
    edge_f: np.ndarray
    vox_i: np.ndarray
    lists: np.ndarray
    counts: np.ndarray
    ter_f: np.ndarray
    ter_i: np.ndarray
    obj_offsets: list[np.ndarray]
    n_robot_points: np.ndarray
    n_actuators: np.ndarray
    n_actions: int


def build_layout(bodies: BodyBatch, objs: Sequence[WorldObject], origin: tuple[int, int], terrain: Terrain,
                 real: type) -> Layout:
    """The layout of one robot per world (`bodies`) placed at grid cell `origin`, beside `objs`.

    Args:
        bodies: the robots, one per world (`tsim.bodybatch.build_bodies`).
        objs: the free objects, the same in every world, placed at their own cells.
        origin: the grid cell of every robot's bottom-left cell.
        terrain: the static terrain.
        real: the real type of `edge_f` (numpy.float64 or numpy.float32).

    Returns:
        The `Layout`.
    """
    B = len(bodies)
    obj_p = [o.body.n_points for o in objs]
    obj_e = [o.body.n_edges for o in objs]
    obj_v = [o.body.n_voxels for o in objs]
    n_pts = bodies.n_points + sum(obj_p)
    n_edges = bodies.n_edges + sum(obj_e)
    n_vox = bodies.n_voxels + sum(obj_v)
    n_robot_points = bodies.n_points.copy()
    n_actuators = bodies.n_actuators.copy()
    P, E, V = int(n_pts.max()), int(n_edges.max()), int(n_vox.max())
    # actuated objects (sgr.evogym's further robots) read the action columns after the robot's
    n_obj_act = sum(o.body.n_actuators for o in objs if o.actuated)
    n_actions = max(1, int(n_actuators.max()) + n_obj_act)

    pos0 = np.zeros((B, P, 2))  # evogym's f64 placement, then in the real type (below)
    edge_i = np.zeros((B, E, 4), dtype=np.int32)
    edge_f = np.zeros((B, E, K.N_EDGE_F), dtype=real)
    rest_f64 = np.zeros((B, E))
    vox_i = np.zeros((B, V, K.N_VOX_I), dtype=np.int32)
    # fixed points: corners of material-5 voxels of simulated objects (never the robot's)
    fixed = [np.unique(o.body.voxel_points[o.body.voxel_type == C.FIXED]) for o in objs]
    n_fix = sum(len(f) for f in fixed)
    lists = np.zeros((B, max(V, n_fix), 3), dtype=np.int32)
    counts = np.zeros((B, K.N_COUNTS), dtype=np.int32)

    # the robots, all at once: each packed row goes to (its world, its index in its body)
    a = bodies.arrays
    wp, ip = _rows(bodies.n_points)
    wv, iv = _rows(bodies.n_voxels)
    x, y = origin  # `Body.place`, evaluated in the same order
    start_x = x * C.CELL
    max_y = y * C.CELL + bodies.n_rows * C.CELL
    pos0[wp, ip, 0] = start_x + a["corner_cx"] * C.CELL
    pos0[wp, ip, 1] = max_y[wp] - a["corner_ry"] * C.CELL
    # edges and voxels as whole rows (one scatter of row-sized items each, the fastest numpy has)
    fe = _flat_rows(bodies.n_edges, E)
    rest_e = a["edge_rest"]
    rows_i = np.empty((len(fe), 4), dtype=np.int32)
    rows_i[:, 0] = a["edge_a"]
    rows_i[:, 1] = a["edge_b"]
    rows_i[:, 2:4] = a["edge_drivers"]
    _scatter_rows(edge_i, fe, rows_i)
    rows_f = np.empty((len(fe), K.N_EDGE_F), dtype=real)
    rows_f[:, K.E_REST] = rest_e
    rows_f[:, K.E_K] = a["edge_k"]
    rows_f[:, K.E_GOAL] = rest_e
    rows_f[:, K.E_LEQ] = rest_e
    _scatter_rows(edge_f, fe, rows_f)
    rest_f64.reshape(-1)[fe] = rest_e
    rows_v = np.zeros((len(wv), K.N_VOX_I), dtype=np.int32)
    rows_v[:, K.V_PTS:K.V_PTS + 4] = a["voxel_points"]
    rows_v[:, K.V_OPEN:K.V_OPEN + 4] = a["voxel_open"]
    rows_v[:, K.V_TYPE] = a["voxel_type"]
    rows_v[:, K.V_ROW] = a["voxel_rc"][:, 0]
    rows_v[:, K.V_COL] = a["voxel_rc"][:, 1]
    _scatter_rows(vox_i, wv * V + iv, rows_v)
    n_surf = _list_by_world(lists, 0, a["voxel_open"].any(axis=1), wv, iv, B)
    counts[:, K.N_SURF_ROBOT] = n_surf
    n_rigid = _list_by_world(lists, 1, a["voxel_type"] == C.RIGID, wv, iv, B)

    # then each free object (the same in every world) at its world's offsets
    rows = np.arange(B)[:, None]
    p_off, e_off, v_off = n_robot_points.copy(), bodies.n_edges.copy(), bodies.n_voxels.copy()
    a_off = n_actuators.copy()
    n_fixed = 0
    obj_offsets = []
    for obj_id, obj in enumerate(objs, start=1):
        part = obj.body
        obj_offsets.append(p_off.copy())
        pts = part.place(*obj.cell)
        pcols = p_off[:, None] + np.arange(part.n_points)
        pos0[rows, pcols] = pts.T
        ecols = e_off[:, None] + np.arange(part.n_edges)
        edge_i[rows, ecols, 0] = part.edge_a + p_off[:, None]
        edge_i[rows, ecols, 1] = part.edge_b + p_off[:, None]
        if obj.actuated:
            d = part.edge_drivers
            edge_i[rows, ecols, 2:4] = np.where(d >= 0, d + a_off[:, None, None], -1)
            a_off += part.n_actuators
        else:
            edge_i[rows, ecols, 2:4] = -1
        edge_f[rows, ecols, K.E_REST] = part.edge_rest
        rest_f64[rows, ecols] = part.edge_rest
        edge_f[rows, ecols, K.E_K] = part.edge_k
        edge_f[rows, ecols, K.E_GOAL] = part.edge_rest
        edge_f[rows, ecols, K.E_LEQ] = part.edge_rest
        vcols = v_off[:, None] + np.arange(part.n_voxels)
        vox_i[rows, vcols, K.V_PTS:K.V_PTS + 4] = part.voxel_points + p_off[:, None, None]
        vox_i[rows, vcols, K.V_OPEN:K.V_OPEN + 4] = part.voxel_open
        vox_i[rows, vcols, K.V_TYPE] = part.voxel_type
        vox_i[rows, vcols, K.V_OBJ] = obj_id
        vox_i[rows, vcols, K.V_ROW] = part.voxel_rc[:, 0]
        vox_i[rows, vcols, K.V_COL] = part.voxel_rc[:, 1]
        s_idx = np.nonzero(part.voxel_is_surface)[0]
        lists[rows, n_surf[:, None] + np.arange(len(s_idx)), 0] = s_idx + v_off[:, None]
        n_surf = n_surf + len(s_idx)
        r_idx = np.nonzero(part.voxel_type == C.RIGID)[0]
        lists[rows, n_rigid[:, None] + np.arange(len(r_idx)), 1] = r_idx + v_off[:, None]
        n_rigid = n_rigid + len(r_idx)
        f_idx = fixed[obj_id - 1]
        lists[rows, n_fixed + np.arange(len(f_idx)), 2] = f_idx + p_off[:, None]
        n_fixed += len(f_idx)
        p_off += part.n_points
        e_off += part.n_edges
        v_off += part.n_voxels
    counts[:, K.N_FIXED] = n_fixed
    counts[:, K.N_PTS] = p_off
    counts[:, K.N_EDGES] = e_off
    counts[:, K.N_VOX] = v_off
    counts[:, K.N_SURF] = n_surf
    counts[:, K.N_RIGID] = n_rigid
    counts[:, K.N_ACT] = n_actuators

    t = terrain
    nt = max(1, len(t.corners))
    ter_f = np.zeros((nt, 12))  # f64, then in the real type as the points are (below)
    ter_i = np.zeros((nt, 4), dtype=np.int32)
    if len(t.corners):
        ter_f[:, :8] = t.corners.reshape(-1, 8)
        ter_f[:, 8] = t.corners[:, :, 0].min(axis=1)
        ter_f[:, 9] = t.corners[:, :, 0].max(axis=1)
        ter_f[:, 10] = t.corners[:, :, 1].min(axis=1)
        ter_f[:, 11] = t.corners[:, :, 1].max(axis=1)
        ter_i[:] = t.open
    return Layout(pos0=pos0, rest_f64=rest_f64, edge_i=edge_i, edge_f=edge_f, vox_i=vox_i, lists=lists,
                  counts=counts, ter_f=ter_f, ter_i=ter_i, obj_offsets=obj_offsets,
                  n_robot_points=n_robot_points, n_actuators=n_actuators, n_actions=n_actions)


def _rows(counts: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """For rows packed body after body (`BodyBatch`), each row's body and its index in that body."""
    total = int(counts.sum())
    owner = np.repeat(np.arange(len(counts)), counts)
    starts = np.cumsum(counts) - counts
    return owner, np.arange(total) - starts[owner]


def _flat_rows(counts: np.ndarray, width: int) -> np.ndarray:
    """For rows packed body after body, each row's place `world * width + index` in a padded
    (B, width) layout."""
    starts = np.cumsum(counts) - counts
    shift = np.arange(len(counts)) * width - starts
    return np.arange(int(counts.sum())) + np.repeat(shift, counts)


def _scatter_rows(dst: np.ndarray, at: np.ndarray, rows: np.ndarray) -> None:
    """dst (B, n, k) seen as B * n rows of k items: rows (m, k) into rows `at` (m,), each row as
    one opaque item (numpy's 1-D scatter; several times faster than a 2-D fancy assignment)."""
    k = dst.shape[-1] * dst.itemsize
    item = np.dtype((np.void, k))
    dst.reshape(-1, dst.shape[-1]).view(item).reshape(-1)[at] = \
        np.ascontiguousarray(rows, dtype=dst.dtype).view(item).reshape(-1)


def _list_by_world(lists: np.ndarray, col: int, keep: np.ndarray, world: np.ndarray, index: np.ndarray,
                   B: int) -> np.ndarray:
    """Write each world's kept packed rows' `index` into `lists[world, :, col]` in order; the
    counts per world."""
    w, i = world[keep], index[keep]
    n = np.bincount(w, minlength=B)
    _, slot = _rows(n)
    lists[w, slot, col] = i
    return n
