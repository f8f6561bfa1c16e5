"""`BatchSim`: many worlds of one task (one robot each, bodies may differ) advanced together.

The simulator knows bodies, worlds and actions; it knows nothing of tasks, rewards or evolution.
Positions and velocities it reports are evogym's snapshot values (world units); a world that
became unstable or non-finite is frozen at its last good snapshot and flagged. Its real arrays
(state, actions, ...) have the backend's dtype: float64 (evogym's bits) unless the process runs in
f32 (`tsim.backend`).
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from tsim import backend as backend_mod
from tsim import constants as C
from tsim import kernels as K
from tsim.backend import launch, spirv
from tsim.backend.launch import CachedLaunch
from tsim.backend.mirror import constant, mirror
from tsim.body import Body, as_body_matrix, build_body, check_robot, is_connected, is_connected_batch
from tsim.bodybatch import BodyBatch, build_bodies
from tsim.kernels.reset import reset_worlds
from tsim.layout import build_layout
from tsim.rounding import rest, to_pair
from tsim.world import World

# the terrain's x and y columns (`tsim.layout.Layout.ter_f`: corners TL, TR, BR, BL as x, y, then the box)
TER_X, TER_Y = [0, 2, 4, 6, 8, 9], [1, 3, 5, 7, 10, 11]

# a world's status codes (`BatchSim.status`): only RUNNING worlds advance
RUNNING, UNSTABLE, NONFINITE, INACTIVE = K.RUNNING, K.UNSTABLE, K.NONFINITE, K.INACTIVE

def _as_body(body: Body | object, passive_ok: bool) -> Body:
    matrix = body.matrix if isinstance(body, Body) else body
    if passive_ok:
        m = as_body_matrix(matrix)
        if not is_connected(m):
            raise ValueError("bad body matrix: voxels are not 4-connected (disconnected body)")
    else:
        m = check_robot(matrix)
    return body if isinstance(body, Body) else build_body(m)


def _as_bodies(bodies: Sequence[Body | object], passive_ok: bool) -> BodyBatch:
    """The batch's bodies, checked as `_as_body` checks each, all at once (on a bad body, the
    first one's own error): matrices built together (`build_bodies`), `Body`s kept as they are."""
    if isinstance(bodies, np.ndarray) and bodies.ndim == 3:
        mats = _checked(bodies, passive_ok)
    else:
        has_body = any(isinstance(b, Body) for b in bodies)
        items = [b.matrix if isinstance(b, Body) else b for b in bodies] if has_body else bodies
        mats = _checked_list(items, passive_ok)
        if mats is not None and has_body:
            return BodyBatch.from_bodies([b if isinstance(b, Body) else build_body(m)
                                          for b, m in zip(bodies, mats, strict=True)])
    if mats is None:  # some body is bad (the first one raises its error), or of an unusual type
        return BodyBatch.from_bodies([_as_body(b, passive_ok) for b in bodies])
    return build_bodies(mats)


def _checked_list(items: Sequence[object], passive_ok: bool) -> list[np.ndarray] | np.ndarray | None:
    """The matrices as int64 (an (N, H, W) array when they share a shape) if all pass
    `_as_body`'s checks, else None. Checked per shape, all of a shape at once."""
    groups: dict[tuple, list[int]] = {}
    for i, b in enumerate(items):
        try:
            shape = np.shape(b)
        except ValueError:  # ragged rows
            return None
        groups.setdefault(shape, []).append(i)
    out: list = [None] * len(items)
    for shape, idx in groups.items():
        if len(shape) != 2:
            return None
        try:
            arr = np.asarray([items[i] for i in idx])
            if arr.dtype.kind not in "biuf":  # e.g. numeric strings, which the one-body check reads
                arr = arr.astype(float)
        except (TypeError, ValueError):
            return None
        m = _checked(arr, passive_ok)
        if m is None:
            return None
        if len(groups) == 1:
            return m
        for i, one in zip(idx, m, strict=True):
            out[i] = one
    return out


def _checked(arr: np.ndarray, passive_ok: bool) -> np.ndarray | None:
    """(N, H, W) matrices as int64 if every one passes `_as_body`'s checks, else None."""
    if arr.ndim != 3 or arr.shape[1] * arr.shape[2] == 0 or arr.dtype.kind not in "biuf":
        return None
    if arr.dtype.kind == "f":
        if not (np.isfinite(arr).all() and (arr == np.round(arr)).all()):
            return None
    if len(arr) and (arr.min() < 0 or arr.max() > C.V_ACT):
        return None
    m = arr.astype(np.int64)
    if not passive_ok:
        flat = m.reshape(len(m), -1)
        if not ((flat == C.H_ACT) | (flat == C.V_ACT)).any(axis=1).all():
            return None
    if not is_connected_batch(m).all():
        return None
    return m


class BatchSim:
    """B worlds of one `World`, one robot each (bodies may differ), stepped together.

    Robot b is built from `bodies[b]` and placed with its matrix's bottom-left cell at grid cell
    `origin`. Body matrices are checked and built all at once (`tsim.bodybatch`).

    Args:
        world: The world that every member of the batch simulates.
        bodies: One body per world: `Body`s or body matrices, or one (B, H, W) array.
        origin: The grid cell (x, y) of the bottom-left cell of each robot's body matrix.
        arch: The process's backend (`tsim.backend.get`); None means $SGR_ARCH, else cpu.
        precision: The process's real type (`tsim.backend.get`); None means $SGR_PRECISION,
            else f64.
        passive_ok: Admit bodies without actuators (evogym loads those as plain objects; the
            reference traces contain a few).

    Raises:
        ValueError: When `bodies` is empty or a body is bad.
    """

    def __init__(self, world: World, bodies: Sequence[Body | object], origin: tuple[int, int],
                 *, arch: str | None = None, precision: str | None = None, passive_ok: bool = False):
        if len(bodies) == 0:
            raise ValueError("BatchSim needs at least one body")
        self.backend = backend_mod.get(arch, precision)
        self.dtype = self.backend.dtype
        self.world = world
        self.origin = (int(origin[0]), int(origin[1]))
        self.bodies = _as_bodies(bodies, passive_ok)  # a sequence of `Body`s (made when read)
        # grows whenever the state may have changed: each `step` and `reset`, each read of
        # `state` (which every outside writer goes through) and each assignment to it
        self.state_version = 0
        self.free_objects = world.free_objects
        self._gpu_block = K.GPU_BLOCK  # worlds per thread block on a GPU (`choose_kernel`)
        self._lanes = 1  # threads per world: 1, today's kernels; more, the lanes kernel (`choose_kernel`)
        self._build()
        self.reset()

    # ------------------------------------------------------------------ layout
    def _build(self) -> None:
        """The batch's arrays (`tsim.layout`), rounded for f32, then how its steps launch."""
        lay = build_layout(self.bodies, self.free_objects, self.origin, self.world.terrain, self.dtype)
        B, P = lay.pos0.shape[:2]
        self.n_robot_points, self.n_actuators = lay.n_robot_points, lay.n_actuators
        self.max_actuators = int(self.n_actuators.max())
        self.max_robot_points = int(self.n_robot_points.max())
        self._obj_offsets, self._rest_f64 = lay.obj_offsets, lay.rest_f64
        real, pos0, counts = self.dtype, lay.pos0, lay.counts
        # f32: the terrain as float32 pairs hi + lo, rounded once (`tsim.rounding.to_pair`), each
        # world's bodies against it (`_round_world`); f64: evogym's placement itself
        ter_f = self._round_terrain(lay.ter_f)
        self._pos0_f64 = pos0
        self._pos0 = pos0 if real == np.float64 else np.zeros(pos0.shape, dtype=real)
        # f32: the placement's low parts (its rest below float32, `_round_world`), and the
        # positions they belong to (a `reset` after `initial_positions` was written drops them)
        self._pos0_lo = self._pos0_lo_of = None
        # (version, arrays) of `kernel_initial_positions`; the version moves on with every change
        self._pos0_version, self._pos0_kernel = 0, None
        if real != np.float64:
            self._pos0_lo = np.zeros(pos0.shape, dtype=real)
            self._pos0_lo_of = np.zeros(pos0.shape, dtype=real)
        self._counts0 = counts
        self.counts = counts.copy()  # the running counts; `reset` restores them in place
        self.edge_f, self.edge_i, self.vox_i, self.lists = lay.edge_f, lay.edge_i, lay.vox_i, lay.lists
        self.ter_f = ter_f
        if real != np.float64:
            self._round_placement(range(B))
        self.ter_i = lay.ter_i
        self.ter_grid = np.ascontiguousarray(self.world.terrain.grid.astype(np.int32))
        # the state: on a device kept there between steps, copied to the host when it reads
        # (`tsim.backend.mirror`); on the CPU the numpy array the kernels write in place
        self._state_m = mirror(np.zeros((B, P, K.state_columns()), dtype=real), self.backend.on_host)
        self.actions = np.ones((B, lay.n_actions), dtype=real)
        # (B, max_actuators): which action columns are a robot's actuators (the rest is padding)
        self._actuator_mask = np.arange(self.max_actuators)[None, :] < self.n_actuators[:, None]
        self._choose_launch()
        # the arrays no step changes. On a GPU they are copied once into Taichi's own ndarrays, so
        # that they stay on the device instead of crossing the bus at every launch. On the CPU the
        # numpy arrays themselves are passed (flattened once, so every step passes the same
        # objects): a cached launch (tsim/backend/launch.py) sets a numpy array's address once, where a
        # Taichi ndarray must be set again at every launch (~1 us each). So the numpy edge_i,
        # edge_f, vox_i, lists and ter_* are read-only after construction
        static = (self.edge_i.reshape(-1), self.edge_f.reshape(-1), self.vox_i, self.lists,
                  self.ter_f, self.ter_i, self.ter_grid)
        self._static = tuple(constant(a, self.backend.cached_launch) for a in static)
        self._edge_f_stale = False  # the copy above is current (`_round_placement`)

    def _round_terrain(self, ter_f: np.ndarray) -> np.ndarray:
        """The terrain's (T, 12) float64 columns in the kernels' real type: f64 as they are; f32 as
        float32 pairs hi + lo (the corners' low parts in the K.TER_LO columns, the boxes keep their
        hi alone), keeping each axis's rests for `_round_world`."""
        self._ter_fixed = []  # per axis (f32): the terrain's rests x - hi and their float32 lo
        real = self.dtype
        if real == np.float64:
            return ter_f
        ter_r = np.zeros((len(ter_f), K.N_TER_F_PAIRS), dtype=real)
        for cols in (TER_X, TER_Y):
            hi, lo = to_pair(ter_f[:, cols], real)
            ter_r[:, cols] = hi
            ter_r[:, [K.TER_LO + c for c in cols[:4]]] = lo[:, :4]
            self._ter_fixed.append((rest(ter_f[:, cols], hi).reshape(-1), lo.reshape(-1)))
        return ter_r

    def _choose_launch(self) -> None:
        """How this batch's steps launch: the kernels' capacity tier, the serial CPU path, the
        contact sweep and pair list, and the launcher (`choose_kernel` overrides each)."""
        counts, lists, vox_i, pos0 = self._counts0, self.lists, self.vox_i, self._pos0_f64
        # the smallest local-array capacity tier that holds every world (a compiled kernel each)
        n_surf = int(counts[:, K.N_SURF].max())
        sizes = (pos0.shape[1], self.edge_i.shape[1], n_surf)
        self.capacity_tier = 0
        while any(n > c for n, c in zip(sizes, K.capacity(self.capacity_tier), strict=True)):
            self.capacity_tier += 1
        # one CPU thread: run on the calling thread, skipping the thread pool's hand-off
        self._serial = self.backend.on_host and (self.backend.threads == 1 or self.n_worlds == 1)
        # how contact pairs are found (the same pairs either way): with the kernel that can sweep
        # and prune only when some world is long enough to gain from it (tests force either)
        self.sweep_mode = K.SWEEP_AUTO if any(
            _sweep_pays(pos0[w], vox_i[w, lists[w, :counts[w, K.N_SURF], 0], K.V_PTS:K.V_PTS + 4])
            for w in np.flatnonzero(counts[:, K.N_SURF] >= K.SWEEP_MIN)) else K.SWEEP_OFF
        # and whether a substep may test only the pairs listed at an earlier one (the same pairs
        # act): in the kernel that lists pairs only when some world is large enough to gain
        self.pair_list = K.LIST_AUTO if n_surf >= K.LIST_MIN else K.LIST_OFF
        self._spirv = self.backend.launch_path == "spirv"  # see tsim/backend/spirv.py
        self._spirv_launcher = spirv.Launcher(self.n_worlds)
        self._launcher = self._make_launcher()  # how `step` launches the kernels (tsim/backend/launch.py)

    def _round_world(self, w: int) -> tuple[np.ndarray, np.ndarray]:
        """World w's float64 placement as float32 pairs hi + lo (f32 only, `tsim.rounding.to_pair`):
        hi each coordinate's float32 rounding, lo its rest rounded keeping the order of the rests
        among themselves and against the terrain's, so that hi + lo holds evogym's placement to
        ~1e-15 and in its order: Lifter-v0's robot stands 1.1e-16 from its slot's walls, which
        decides its first contacts, where float32 numbers alone are 6e-8 apart."""
        p = self._pos0_f64[w]
        hi = np.empty(p.shape, dtype=self.dtype)
        lo = np.empty(p.shape, dtype=self.dtype)
        for d in range(2):
            hi[:, d], lo[:, d] = to_pair(p[:, d], self.dtype, self._ter_fixed[d])
        return hi, lo

    def _round_placement(self, worlds) -> None:
        """f32: these worlds' float64 placement as float32 pairs (`_round_world`), and their
        springs' initial-length rounding (`_length_rounding`)."""
        for w in worlds:
            self._pos0[w], self._pos0_lo[w] = self._round_world(w)
            self._pos0_lo_of[w] = self._pos0[w]
            self._length_rounding(w)
        self._edge_f_stale = True  # a GPU's copy: sent again before the next step (`step`)

    def _length_rounding(self, w: int) -> None:
        """f32: per spring of world w, how far its initial length as the kernel computes it in
        float32 from the placement's pairs lies from evogym's float64 length, less the float32
        rounding of its rest length (edge_f's E_LEQ column; `springs.spring_forces` subtracts it
        from the stretch, so that a spring starts as stretched as in evogym: else the rounding of
        its length (~4e-9 at 0.1) strains a spring by ~0.2 force units, and points evogym holds
        still to the last bit drift off the terrain corners they touch, PlatformJumper-v0)."""
        edge_f, edge_i = self.edge_f, self.edge_i
        a, b = edge_i[w, :, 0], edge_i[w, :, 1]  # padding: point 0 to itself, 0
        hi, lo, p64 = self._pos0[w], self._pos0_lo[w], self._pos0_f64[w]
        d32 = (hi[a] - hi[b]) + (lo[a] - lo[b])  # float32, as `spring_forces` at stage 0
        l32 = np.sqrt(d32[:, 0] * d32[:, 0] + d32[:, 1] * d32[:, 1])
        d64 = p64[a] - p64[b]
        l64 = np.sqrt(d64[:, 0] * d64[:, 0] + d64[:, 1] * d64[:, 1])
        rest32 = edge_f[w, :, K.E_REST].astype(np.float64)
        edge_f[w, :, K.E_LEQ] = ((l32.astype(np.float64) - l64) - (rest32 - self._rest_f64[w]))

    # ------------------------------------------------------------------ control
    @property
    def n_worlds(self) -> int:
        """B, the batch size: one world per body."""
        return len(self.bodies)

    def reset_mask(self, mask: object) -> np.ndarray:
        """Check a reset mask: one bool per world.

        Integers are refused, not cast: numpy reads an int array as indices, so [1, 0] would mean
        world 1 and world 0 to one reader and world 0 to another.

        Args:
            mask: The worlds to reset, one bool per world.

        Returns:
            `mask` as a (B,) bool array.

        Raises:
            ValueError: When `mask` is not of shape (B,) or not bools.
        """
        sel = np.asarray(mask)
        if sel.shape != (self.n_worlds,):
            raise ValueError(f"reset mask must have shape ({self.n_worlds},), got {sel.shape}")
        if sel.dtype != bool:
            raise ValueError(f"reset mask must be {self.n_worlds} booleans (one per world), got "
                             f"dtype {sel.dtype}; for world indices idx: mask = np.zeros(B, bool); "
                             "mask[idx] = True")
        return sel

    def reset(self, mask: np.ndarray | None = None) -> None:
        """Put worlds back to their initial placement at rest, running again (evogym's `reset`).

        Args:
            mask: (B,) bools: reset only the worlds where it is True. None resets every world.
        """
        # every world: plain slices, several times faster than a full mask
        sel = slice(None) if mask is None else self.reset_mask(mask)
        if mask is None:
            self.time = np.zeros(self.n_worlds, dtype=np.int64)
        self.state_version += 1
        if mask is not None and self._state_m.on_device:
            self._reset_on_device(sel)
        else:
            # every world's rows are rewritten by a full reset: a device's values need not come back
            state = self._state_m.host(write=True, keep=mask is not None)
            state[sel] = 0.0
            state[sel, :, 0:2] = self._pos0[sel]
            state[sel, :, 4:6] = self._pos0[sel]
            if self._pos0_lo is not None:  # f32: the placement's low parts (`_round_world`)
                state[sel, :, K.S_POS_LO:K.S_POS_LO + 2] = self._pos0_lo[sel]
                state[sel, :, K.S_LO_OF:K.S_LO_OF + 2] = self._pos0_lo_of[sel]
        self.counts[sel] = self._counts0[sel]  # in place: a cached launch holds its address
        self.actions[sel] = 1.0
        self.time[sel] = 0

    def _reset_on_device(self, sel: np.ndarray) -> None:
        """`reset`'s state writes for the worlds in `sel` where the state lives on a device: by
        `tsim.kernels.reset.reset_worlds` there, so the state does not come to the host and back."""
        worlds = np.flatnonzero(sel).astype(np.int32)
        if len(worlds) == 0:
            return
        reset_worlds(self._state_m.device(), *self.kernel_initial_positions(), worlds, self._state_m.shape[1])

    def kernel_initial_positions(self) -> tuple:
        """`initial_positions` as kernels take them: flat, with f32's low parts.

        On a device they are copied there once per placement (it changes only by `place_object`,
        `shift_robots` or a write through `initial_positions`), so a partial reset or an object's
        orientation does not send (B, P, 2) arrays across the bus each time.

        Returns:
            The flat `initial_positions`, then in f32 the placement's low parts (`_round_world`),
            else a one-element stand-in for each.
        """
        cached = self._pos0_kernel
        if cached is None or cached[0] != self._pos0_version:
            f32 = self._pos0_lo is not None
            parts = (self._pos0, self._pos0_lo, self._pos0_lo_of) if f32 else (
                self._pos0, np.zeros(1, self.dtype), np.zeros(1, self.dtype))
            cached = self._pos0_kernel = (self._pos0_version, tuple(
                constant(np.ascontiguousarray(a).reshape(-1), self.backend.on_host) for a in parts))
        return cached[1]

    def place_object(self, w: int, name: str, cell: tuple[int, int]) -> None:
        """Start a free object of world w at a grid cell from the next `reset` of that world on.

        For objects placed anew each episode, e.g. Catcher-v0's package and pegs. Fixed points stay
        fixed wherever they are put.

        Args:
            w: The world.
            name: The free object's name.
            cell: The grid cell (x, y) of the bottom-left of the object's bounding box.

        Raises:
            KeyError: When the world has no free object of that name.
        """
        k, obj = self._free_object(name)
        self._pos0_version += 1
        off = self._obj_offsets[k][w]
        self._pos0_f64[w, off:off + obj.body.n_points] = obj.body.place(int(cell[0]), int(cell[1])).T
        if self._pos0 is not self._pos0_f64:  # f32: the world rounded anew (`tsim.rounding`)
            self._round_placement([w])

    def shift_robots(self, dx: np.ndarray) -> None:
        """Start each world's robot further right from the next `reset` of that world on.

        A perturbed start for robustness tests. Objects and terrain stay where they are.

        Args:
            dx: (B,) shifts, world w's robot by `dx[w]`: evogym's length units (a voxel is 0.1),
                to the left when negative.

        Raises:
            ValueError: When `dx` is not B finite numbers.
        """
        dx = np.asarray(dx, dtype=np.float64)
        if dx.shape != (self.n_worlds,) or not np.all(np.isfinite(dx)):
            raise ValueError(f"shift_robots needs {self.n_worlds} finite shifts, got shape {dx.shape}")
        robot = np.arange(self._pos0.shape[1])[None, :] < self.n_robot_points[:, None]
        self._pos0_version += 1
        self._pos0_f64[:, :, 0] += np.where(robot, dx[:, None], 0.0)
        if self._pos0 is not self._pos0_f64:  # f32: shifted in float64, then rounded anew
            self._round_placement(range(self.n_worlds))

    def set_actions(self, actions: np.ndarray | Sequence[np.ndarray]) -> None:
        """Actuator targets, one row per world in evogym's actuator order, clipped to [0.6, 1.6].

        Accepts a (B, max_actuators) array (entries past a robot's actuator count are ignored) or
        a list of B 1-D arrays of each robot's exact actuator count.
        """
        B = self.n_worlds
        if isinstance(actions, np.ndarray) and actions.dtype != object:
            if actions.dtype.kind not in "fiu":  # complex would lose its imaginary part, bool mean 0.6/1.0
                raise ValueError(f"actions must be real numbers, got dtype {actions.dtype}")
            a = np.asarray(actions, dtype=np.float64)
            if a.shape != (B, self.max_actuators):
                raise ValueError(f"wrong action shape: expected ({B}, {self.max_actuators}), "
                                 f"got {a.shape}")
            # vectorised: one finiteness test and one clip for the whole batch
            M = self.max_actuators
            mask = self._actuator_mask
            if not np.isfinite(a).all():  # padding past a robot's actuators may hold anything
                ok = np.isfinite(a) | ~mask
                if not ok.all():
                    w = int(np.nonzero(~ok.all(axis=1))[0][0])
                    r = a[w, :self.n_actuators[w]]
                    raise ValueError(f"non-finite actions for robot {w}: {r[~np.isfinite(r)][:3]}")
            # max then min is np.clip's value for finite actions, without np.clip's ~5 us of
            # Python-level dispatch per call
            clipped = np.minimum(np.maximum(a, C.ACTION_MIN), C.ACTION_MAX)
            np.copyto(self.actions[:, :M], clipped, where=mask)
            return
        else:
            if not hasattr(actions, "__len__") or isinstance(actions, str | bytes):
                raise ValueError(f"actions must be a ({B}, {self.max_actuators}) array or {B} rows, "
                                 f"one per robot, got {type(actions).__name__}")
            if len(actions) != B:
                raise ValueError(f"wrong action shape: expected {B} rows, got {len(actions)}")
            rows = []
            for w, r in enumerate(actions):
                r = np.asarray(r)
                if r.dtype.kind not in "fiu":
                    raise ValueError(f"actions for robot {w} must be real numbers, got dtype {r.dtype}")
                r = r.astype(np.float64).reshape(-1)
                if r.shape != (self.n_actuators[w],):
                    raise ValueError(f"wrong action shape for robot {w}: expected "
                                     f"({self.n_actuators[w]},), got {r.shape}")
                rows.append(r)
        for w, r in enumerate(rows):
            if not np.all(np.isfinite(r)):
                raise ValueError(f"non-finite actions for robot {w}: {r[~np.isfinite(r)][:3]}")
            self.actions[w, :len(r)] = np.clip(r, C.ACTION_MIN, C.ACTION_MAX)

    def step(self, n: int = 1) -> None:
        """Advance every running world by n env steps (30 substeps each)."""
        if self._edge_f_stale:  # f32: edge_f changed since the kernels' own copy was made
            if not isinstance(self._static[1], np.ndarray):
                self._static[1].from_numpy(np.ascontiguousarray(self.edge_f.reshape(-1)))
            self._edge_f_stale = False
        self.state_version += 1
        for _ in range(n):
            running = self.counts[:, K.STATUS] == K.RUNNING
            edge_i, edge_f, vox_i, lists, ter_f, ter_i, ter_grid = self._static
            args = (self.counts, self._state_m.device(), edge_i, edge_f, vox_i, lists,
                    self.actions, ter_f, ter_i, ter_grid, C.SUBSTEPS, self._state_m.shape[1],
                    self.edge_i.shape[1], *K.capacity(self.capacity_tier), self.sweep_mode,
                    self.pair_list)
            self._launcher(args)
            self.time += running & (self.counts[:, K.STATUS] == K.RUNNING)

    def _make_launcher(self):
        """The backend's launcher of a step for this batch and its `choose_kernel` choices."""
        path = "lanes" if self._lanes > 1 else "spirv" if self._spirv else self.backend.kernel_path
        return launch.launcher(path, serial=self._serial, block=self._gpu_block, split=self._spirv_launcher,
                               n_worlds=self.n_worlds, lanes=self._lanes)

    @property
    def _launch(self) -> CachedLaunch | None:
        """The launcher's cached launch context, if any (tests read it, or set None to make the next
        step call the kernel through Taichi)."""
        return self._launcher.cached

    @_launch.setter
    def _launch(self, value: CachedLaunch | None) -> None:
        self._launcher.cached = value

    def deactivate(self, mask: np.ndarray) -> None:
        """Freeze worlds (e.g. terminated episodes) so they cost nothing and stop moving."""
        mask = np.asarray(mask, dtype=bool)
        sel = mask & (self.counts[:, K.STATUS] == K.RUNNING)
        self.counts[sel, K.STATUS] = K.INACTIVE

    def choose_kernel(self, *, serial: bool | None = None, extra_capacity_tiers: int = 0,
                      spirv_launch: bool | None = None, substeps_per_launch: int | None = None,
                      gpu_block: int | None = None, lanes: int | None = None) -> None:
        """Force a kernel variant instead of the one chosen for this batch.

        Tests and benchmarks compare the variants; every variant gives the same bits. An argument
        left None keeps its current choice.

        Args:
            serial: Run on the calling thread (True, CPU only) or on the thread pool (False).
            extra_capacity_tiers: Compile for local arrays that many tiers bigger than needed.
            spirv_launch: Take (True) or leave (False) the SPIR-V backends' launch
                (tsim/backend/spirv.py), on any backend.
            substeps_per_launch: Split the SPIR-V launch's env steps into launches of that many
                substeps.
            gpu_block: The worlds per thread block on a GPU (default `GPU_BLOCK`, 64): a multiple
                of 32 up to 1,024, each block size its own compiled kernel (bench/gpu_probe.py
                compares them). The CPU keeps its 1.
            lanes: More than 1 runs each world on that many threads of one thread block
                (tsim/backend/lanes.py): a power of two up to 1,024, on a GPU or Vulkan only
                (Taichi's CPU backend has no block barrier). 1 runs the backend's own kernel again.

        Raises:
            ValueError: When `gpu_block` or `lanes` is out of range, or `lanes` > 1 on the CPU.
        """
        if lanes is not None:
            from tsim.backend.lanes import check_lanes

            check_lanes(lanes)
            if lanes > 1 and self.backend.on_host:
                raise ValueError("the lanes kernel runs on a GPU or Vulkan only (Taichi's CPU backend "
                                 "has no block barrier)")
            self._lanes = lanes
        if gpu_block is not None:
            if not (isinstance(gpu_block, int) and 32 <= gpu_block <= 1024 and gpu_block % 32 == 0):
                raise ValueError(f"gpu_block must be a multiple of 32 from 32 to 1024, got {gpu_block!r}")
            self._gpu_block = gpu_block
        if serial is not None:
            self._serial = bool(serial)
        if spirv_launch is not None:
            self._spirv = bool(spirv_launch)
        if substeps_per_launch is not None:
            self._spirv_launcher.chunk = int(substeps_per_launch)
        self.capacity_tier += int(extra_capacity_tiers)
        self._launcher = self._make_launcher()

    def ignore_robot_self_collisions(self) -> None:
        """Turn evogym's instability rule off for these worlds, across resets.

        evogym's rule counts only robots' self-collisions, and a world led by an object that is no
        robot (sgr.evogym's EvoSim without robots) has none.
        """
        self._counts0[:, K.N_SURF_ROBOT] = 0
        self.counts[:, K.N_SURF_ROBOT] = 0

    def set_world_status(self, w: int, status: int) -> None:
        """Set world w's status code (RUNNING, UNSTABLE, ...).

        RUNNING lets a frozen world advance again after its state was restored (evogym's revert);
        UNSTABLE freezes it.

        Args:
            w: The world.
            status: The new code, one of `tsim.sim`'s RUNNING, UNSTABLE, NONFINITE and INACTIVE.
        """
        self.counts[w, K.STATUS] = status

    # ------------------------------------------------------------------ read-out
    @property
    def state(self) -> np.ndarray:
        """(B, P, columns) every world's points in the real type, to read and write.

        The columns are position 0:2, velocity 2:4, last position 4:6, true velocity 6:8 (and f32's
        low parts, `tsim.kernels.layout`), written in place by `step` and `reset`.

        Each read moves `state_version` on, as the reader may write it: `BatchEnv` then measures
        the state anew rather than reuse its last measurement. So write through `state` each time,
        not through a reference kept across any launch (a `step`, a partial `reset(mask)`, or
        `BatchEnv`'s measuring and observing kernels): on a device a launch copies in what was
        written through the last read and no later write, and a reference kept from before a step
        does not see that step (`tsim.backend.mirror`). To read only, use `read_state`.
        """
        self.state_version += 1
        return self._state_m.host(write=True)

    @state.setter
    def state(self, value: np.ndarray) -> None:
        """Copy `value` ((B, P, columns)) into the state: the next step starts from it."""
        value = np.asarray(value)
        if value.shape != self._state_m.shape:
            raise ValueError(f"a state must have shape {self._state_m.shape}, got {value.shape}")
        self.state_version += 1
        self._state_m.assign(value)

    @property
    def state_shape(self) -> tuple[int, int, int]:
        """`state`'s shape (B, P, columns), without reading it."""
        return self._state_m.shape

    def read_state(self) -> np.ndarray:
        """`state` for reading only, as a read-only view.

        On a device the next step need not copy it in again, and `state_version` stays (the state
        is as the last measurement saw it).
        """
        view = self._state_m.host().view()
        view.flags.writeable = False
        return view

    def kernel_state(self):
        """The flat state as kernels take it, for kernels that only read it (`tasks.kernels`).

        On a device it is the device's own array, which then need not come to the host.
        """
        return self._state_m.device(write=False)

    @property
    def status(self) -> np.ndarray:
        """(B,) copy of each world's status code; only RUNNING worlds advance.

        The codes are `tsim.sim`'s RUNNING, UNSTABLE, NONFINITE and INACTIVE.
        """
        return self.counts[:, K.STATUS].copy()

    def world_status(self, w: int) -> int:
        """World w's status code, as `status` (a scalar read, cheap enough for every step)."""
        return int(self.counts[w, K.STATUS])

    @property
    def n_points(self) -> np.ndarray:
        """(B,) the number of simulated points of each world.

        They are its robot's, then its free objects' (`state`'s rows, in that order; padding after
        them).
        """
        return self.counts[:, K.N_PTS].copy()

    def object_offsets(self, k: int) -> np.ndarray:
        """(B,) the row in `state` where free object k starts in each world.

        Its points follow in its body's order.

        Args:
            k: The object's index in `free_objects`.
        """
        return np.array(self._obj_offsets[k])

    @property
    def initial_positions(self) -> np.ndarray:
        """(B, P, 2) every point's position at reset, as `state`'s rows.

        It is the reference of an object's orientation. Writing it moves where the next reset
        starts, as `place_object` and `shift_robots` do (in f32 until one of them, which round
        evogym's float64 placement anew, `tsim.rounding`).
        """
        self._pos0_version += 1  # the caller may write it (`kernel_initial_positions`)
        return self._pos0

    @property
    def unstable(self) -> np.ndarray:
        """Worlds frozen by evogym's self-collision instability rule or a non-finite state."""
        s = self.counts[:, K.STATUS]
        return (s == K.UNSTABLE) | (s == K.NONFINITE)

    def robot_pos(self, w: int) -> np.ndarray:
        """(2, n) robot point positions of world w, evogym point order, world units."""
        return self.read_state()[w, :self.n_robot_points[w], 0:2].T.copy()

    def robot_vel(self, w: int) -> np.ndarray:
        """(2, n) robot point velocities of world w, in evogym's point order.

        In world units per unit of simulated time (dt = 1e-4 per substep).

        Args:
            w: The world.
        """
        return self.read_state()[w, :self.n_robot_points[w], 2:4].T.copy()

    def object_pos(self, w: int, name: str) -> np.ndarray:
        """(2, n) point positions of free object `name` in world w, in world units.

        Args:
            w: The world.
            name: The free object's name.

        Raises:
            KeyError: When the world has no free object of that name (fixed objects are terrain,
                not simulated).
        """
        k, obj = self._free_object(name)
        off = self._obj_offsets[k][w]
        return self.read_state()[w, off:off + obj.body.n_points, 0:2].T.copy()

    def objects_pos(self, w: int) -> dict[str, np.ndarray]:
        """`object_pos` of every free object of world w, by name (what a picture of it draws)."""
        return {o.name: self.object_pos(w, o.name) for o in self.free_objects}

    def object_vel(self, w: int, name: str) -> np.ndarray:
        """(2, n) point velocities of free object `name` in world w, in `robot_vel`'s units.

        Args:
            w: The world.
            name: The free object's name.

        Raises:
            KeyError: When the world has no free object of that name, as `object_pos`.
        """
        k, obj = self._free_object(name)
        off = self._obj_offsets[k][w]
        return self.read_state()[w, off:off + obj.body.n_points, 2:4].T.copy()

    def _free_object(self, name: str):
        for k, o in enumerate(self.free_objects):
            if o.name == name:
                return k, o
        raise KeyError(f"no free object {name!r} in world {self.world.name}")

    def robot_com(self) -> np.ndarray:
        """(B, 2) unweighted mean of each robot's points (evogym's centre of mass).

        In f32 it is the mean of the positions' pairs hi + lo (`tsim.kernels.pairs`), summed in
        float64, then rounded to float32: a float32 sum of ~30 coordinates near 1 rounds at ~1e-7,
        which can put the COM further from evogym's than evogym's own chaos floor (Jumper-v0).
        """
        mask = np.arange(self._state_m.shape[1])[None, :] < self.n_robot_points[:, None]
        if self.dtype == np.float64:
            s = (self.read_state()[:, :, 0:2] * mask[:, :, None]).sum(axis=1)
            return s / self.n_robot_points[:, None]
        s = (self.states64()[:, :, 0:2] * mask[:, :, None]).sum(axis=1)
        return (s / self.n_robot_points[:, None]).astype(self.dtype)

    def states64(self) -> np.ndarray:
        """(B, P, 4) every point's position (0:2) and velocity (2:4) in float64.

        For comparing f32 with f64 or evogym. In f64 these are the state's own columns; in f32 each
        is its pair hi + lo (`tsim.kernels.pairs`), which holds it to ~1e-15, where float32 alone
        rounds at ~1e-8. A low part counts only while its position is the one it was written for
        (a position changed from Python, e.g. by `place_object`, has none until the next step).
        """
        st = self.read_state()
        out = st[:, :, 0:4].astype(np.float64)
        if st.shape[2] > K.NS:
            own = st[:, :, K.S_LO_OF:K.S_LO_OF + 2] == st[:, :, 0:2]
            out[:, :, 0:2] += np.where(own, st[:, :, K.S_POS_LO:K.S_POS_LO + 2], 0.0)
            out[:, :, 2:4] += np.where(own, st[:, :, K.S_VEL_LO:K.S_VEL_LO + 2], 0.0)
        return out


def _sweep_pays(pos: np.ndarray, corners: np.ndarray) -> bool:
    """The kernel's `_choose_sweep` on a world's initial placement: pos (P, 2), corners (n, 4)
    point ids of its surface voxels."""
    n = len(corners)
    if n < K.SWEEP_MIN:
        return False
    best = n * n
    for axis in (0, 1):
        c = pos[corners, axis]
        low = np.sort(c.min(axis=1))
        w = float((c.max(axis=1) - c.min(axis=1)).max())
        near = np.searchsorted(low, low + w, "right") - np.searchsorted(low, low - w, "left")
        best = min(best, int(near.sum()))
    return best * K.SWEEP_RATIO <= n * n
