"""`BatchEnv`: one task, many robots (bodies may differ), stepped together.

Layout: observations are a (B, max_obs_dim) array of the simulator's real type (float64, or
float32 in an f32 process: `tsim.backend`; rewards follow it too), row b holding robot b's evogym
observation in its first `obs_dims[b]` entries and zeros after; actions are (B, max_actuators) with
robot b using its first `n_actuators[b]` entries (or a list of per-robot arrays). Rewards,
`terminated` and `truncated` are (B,) arrays. A robot that terminated stops moving and earns 0 from
then on while the others go on.
"""

from __future__ import annotations

import numbers
import random
from collections.abc import Sequence

import numpy as np

from tasks import kernels as EK
from tasks import observations as O
from tasks.spec import Measure
from tasks.specs import task_spec, task_world
from tsim import constants as C
from tsim.backend.mirror import constant
from tsim.body import Body
from tsim.sim import BatchSim

UNSTABLE_PENALTY = -3.0
FUSED_MIN = 64  # robots from which `BatchEnv` takes the kernel path by default (see `fused`)


def obs_dim(task: str, n_points: int) -> int:
    """evogym's observation length for a robot of n points on `task`."""
    return task_spec(task).obs_dim(n_points)


class BatchEnv:
    """One evogym task for many robots (bodies may differ), stepped together.

    Everything task-specific comes from the task's spec (`tasks/spec.py`). The layout of
    observations, actions and rewards is in `tasks.env`'s module docstring.

    Args:
        task: The task's id, such as "Walker-v0".
        bodies: One body per robot: `Body`s, body matrices or one (B, H, W) array (as `BatchSim`).
        episode_steps: The episode length: None for the SGR paper's length for the task, "evogym"
            for evogym's registered limit, or a positive int.
        arch: The process's backend, as `BatchSim`'s.
        precision: The simulator's real type, as `BatchSim`'s.
        passive_ok: Admit bodies without actuators, as `BatchSim`.
        seeds: Seeds of the worlds' random streams, as `seed` takes them.
        robot_shift: (B,) starts each robot that much right of its task's placement
            (`BatchSim.shift_robots`; a perturbed start for robustness tests).
        fused: Compute the COMs and observation rows by Taichi kernels (`tasks.kernels`, True) or
            by numpy (False, the kernels' test oracle); the same bits either way. None takes the
            kernels from `FUSED_MIN` robots on, where their launches cost less than numpy's
            temporaries.

    Raises:
        ValueError: When `episode_steps` is not a positive int, "evogym" or None, or a body is
            bad.
    """

    def __repr__(self) -> str:
        return (f"BatchEnv({self.task!r}, {self.n_worlds} robot{'s' if self.n_worlds != 1 else ''}, "
                f"episode_steps={self.episode_steps}, {np.dtype(self.dtype).name})")

    def __init__(self, task: str, bodies: Sequence[Body | object],
                 episode_steps: int | str | None = None, *, arch: str | None = None,
                 precision: str | None = None, passive_ok: bool = False,
                 seeds: Sequence[int] | int | None = None, robot_shift: Sequence[float] | None = None,
                 fused: bool | None = None):
        """Build the worlds and start their first episodes (the arguments: see the class)."""
        self.spec = task_spec(task)
        self.task = task
        episode_steps = self.spec.episode_length(episode_steps)
        if (not isinstance(episode_steps, numbers.Integral) or isinstance(episode_steps, bool | np.bool_)
                or episode_steps < 1):
            raise ValueError(f"episode_steps must be a positive int, 'evogym' or None, got {episode_steps!r}")
        self.episode_steps = int(episode_steps)  # numpy's integers too (a config's, a sweep's)
        self.sim = BatchSim(task_world(task), bodies, self.spec.origin, arch=arch,
                            precision=precision, passive_ok=passive_ok)
        self.dtype = self.sim.dtype
        if robot_shift is not None:
            self.sim.shift_robots(np.asarray(robot_shift))
        self.n_worlds = self.sim.n_worlds
        self.n_actuators = self.sim.n_actuators.copy()
        self.n_points = self.sim.n_robot_points.copy()
        # one spec call per distinct point count (a batch has few)
        sizes, inverse = np.unique(self.n_points, return_inverse=True)
        self.obs_dims = np.array([self.spec.obs_dim(int(n)) for n in sizes])[inverse.reshape(-1)]
        self.max_obs_dim = int(self.obs_dims.max())
        N = self.sim.max_robot_points
        self._mask = np.arange(N)[None, :] < self.n_points[:, None]
        world = self.sim.world
        self._terrain = (np.concatenate([o.pos0 for o in world.fixed_objects], axis=1)
                         if world.fixed_objects else np.zeros((2, 0))).astype(self.dtype, copy=False)
        self._head = self.spec.head_width()
        self._rel_cols = self._relative_columns()
        self._obj_index = {o.name: self._object_index(k) for k, o in enumerate(self.sim.free_objects)}
        # free objects' points of the state now, by name: read once per state within `step` (the
        # reward's measure and several observation blocks ask for them); emptied whenever the
        # state may have changed (a step, a reset, a caller writing `sim.state` between steps)
        # (and what kernels measured of this state, under (what, name): "coms", "orientation",
        # "com_vox"; `_per_state`)
        self._points_now: dict[str | tuple[str, str], tuple[np.ndarray, ...] | np.ndarray] = {}
        self.task_state: dict[str, np.ndarray] = {}
        self._rngs: dict[int, random.Random] = {}
        self.fused = self.n_worlds >= FUSED_MIN if fused is None else bool(fused)
        self._init_fused()
        self.seed(seeds)
        self.reset()

    def _init_fused(self) -> None:
        """What the kernel path keeps: the observation's own buffer, the robots' points when the
        spec's rewards read them, the observation's blocks around the points, the last
        measurement."""
        B, N = self._mask.shape
        # the robots' point counts, which every kernel here reads: on a device, kept there
        self._npts = constant(self.n_points.astype(np.int32), self.sim.backend.on_host)
        # on a CPU on the calling thread: the kernels are one memory-bound pass over the state, and
        # on the 2-vCPU VM a second thread added CPU time (0.31-0.37 against 0.22-0.29 us per
        # robot-step at B = 8,192) without saving wall time. Elsewhere numpy arguments travel to a
        # device and back (Vulkan: only those a kernel reads)
        self._cpu = self._serial = self.sim.backend.on_host
        self._ti_real = EK.ti.f32 if self.dtype == np.float32 else EK.ti.f64
        # for `tasks.kernels.object_coms` and `orientation`: each free object's first row in the
        # flat state in every world, its point count, and that count per world (objects of at most
        # 128 points, the pairwise sum's one block; larger ones keep numpy)
        P = self.sim.state_shape[1]
        first = {name: np.arange(B) * P + pts[:, 0] for name, (_, pts) in self._obj_index.items()}
        self._obj_rows = {
            o.name: (constant(first[o.name].astype(np.int32), self._cpu), o.body.n_points,
                     constant(np.full(B, o.body.n_points, dtype=np.int32), self._cpu))
            for o in self.sim.free_objects if o.body.n_points <= 128}
        # for `tasks.kernels.orientation`: each world's first row of the robots' (B, N, 2) arrays
        # and of the flat state
        self._dense_rows = constant((np.arange(B) * N).astype(np.int32), self._cpu)
        self._state_rows = constant((np.arange(B) * P).astype(np.int32), self._cpu)
        self._sight_plans: dict[tuple[str, ...], tuple] = {}  # `_object_sight`'s, by objects seen
        self._n_act = self.n_actuators.astype(np.int32)
        self._masked = bool(self.sim.free_objects)
        # the robots' points before and after a step (two, used in turn), if rewards read them
        shape = (B, N, 2) if self.spec.reads_points else (1, 1, 2)
        self._points_buf = (np.empty(shape, dtype=self.dtype), np.empty(shape, dtype=self.dtype))
        self._points_flip = 0
        # (BatchSim.state_version, com, vcom, points, Measure or None) of the last measurement
        self._last: tuple | None = None
        blocks = self.spec.observation
        k = next(i for i, b in enumerate(blocks) if b.width < 0)
        self._head_blocks, self._tail_blocks = blocks[:k], blocks[k + 1:]
        self._tail_width = sum(b.width for b in self._tail_blocks)
        # the static terrain in voxel units as `O.terrain_sight` divides it (x row, y row)
        self._terrain_vox = np.ascontiguousarray(self._terrain / C.CELL)
        self._obs_buf = np.zeros((B, self.max_obs_dim), dtype=self.dtype) if self.fused else None

    # ------------------------------------------------------------------ layout helpers
    def _relative_columns(self) -> np.ndarray:
        """Column of each robot point's relative x and y in the observation row (dump column for
        padding)."""
        B, N = self._mask.shape
        p = np.arange(N)[None, :]
        head = self._head
        cx = np.where(self._mask, head + p, self.max_obs_dim)
        cy = np.where(self._mask, head + self.n_points[:, None] + p, self.max_obs_dim)
        return np.stack([cx, cy], axis=2)

    def _robot(self) -> tuple[np.ndarray, np.ndarray]:
        N = self.sim.max_robot_points
        state = self.sim.read_state()
        return state[:, :N, 0:2], state[:, :N, 2:4]

    def _object_index(self, k: int) -> tuple[np.ndarray, np.ndarray]:
        """Row and point indices (B, n) of free object k's points in `sim.state`."""
        n = self.sim.free_objects[k].body.n_points
        off = self.sim.object_offsets(k)
        return np.arange(self.n_worlds)[:, None], off[:, None] + np.arange(n)[None, :]

    def _object_points(self, name: str) -> tuple[np.ndarray, np.ndarray]:
        """(B, n, 2) positions and velocities of free object `name` in every world."""
        if name not in self._obj_index:
            raise KeyError(f"no free object {name!r} in world {self.sim.world.name}")

        def gather():
            rows, pts = self._obj_index[name]
            s = self.sim.read_state()[rows, pts].transpose(0, 2, 1)
            # (B, 2, n) contiguous, seen as (B, n, 2): numpy's sums over the points depend on the
            # layout, and this one gives the COMs evogym's rewards were validated with, bit for bit
            return (np.ascontiguousarray(s[:, 0:2]).transpose(0, 2, 1),
                    np.ascontiguousarray(s[:, 2:4]).transpose(0, 2, 1))
        return self._per_state(name, gather)

    def _per_state(self, key, compute):
        """`compute()`, once per state: kept in `_points_now`, which is emptied whenever the state
        may have changed."""
        hit = self._points_now.get(key)
        if hit is None:
            hit = self._points_now[key] = compute()
        return hit

    def _object_coms(self, name: str) -> tuple[np.ndarray, np.ndarray]:
        """(B, 2) position and velocity COMs of free object `name` (`O.com` of `_object_points`):
        on the kernel path by `tasks.kernels.object_coms`, the same bits without gathering the
        object's points (on a device the state stays there)."""
        def compute():
            if self.fused and name in self._obj_rows:
                rows, n, _ = self._obj_rows[name]
                out = (np.empty((self.n_worlds, 2)), np.empty((self.n_worlds, 2)))
                EK.object_coms(self.sim.kernel_state(), rows, n, out[0], out[1], self._ti_real, self._serial)
                return out
            pos, vel = self._object_points(name)
            ones = np.ones(pos.shape[:2], dtype=bool)
            return O.com(pos, ones), O.com(vel, ones)
        return self._per_state(("coms", name), compute)

    def _robot_orientation(self, points: np.ndarray, pos0: np.ndarray, mask: np.ndarray) -> np.ndarray:
        """`O.orientation(points, pos0, mask)` of the robots' (B, N, 2) points by
        `tasks.kernels.orientation` (the same bits; mask is the env's own)."""
        rows = self._dense_rows
        return EK.orientation(np.ascontiguousarray(points).reshape(-1), rows, 2,
                              np.ascontiguousarray(pos0).reshape(-1), rows, 2, self._npts, mask.shape[1],
                              self._serial)

    def _robot_orientation_now(self) -> np.ndarray:
        """(B,) the robots' orientation now (`O.orientation` of `_robot()`'s points), by
        `tasks.kernels.orientation` over the state's rows."""
        sim = self.sim
        if self._pos0_k is None:  # on a device, copied there once per full reset
            self._pos0_k = constant(self._pos0.reshape(-1), self._cpu)
        return EK.orientation(sim.kernel_state(), self._state_rows, sim.state_shape[2], self._pos0_k,
                              self._dense_rows, 2, self._npts, self._mask.shape[1], self._serial)

    def _object_orientation(self, name: str) -> np.ndarray:
        """(B,) orientation of free object `name` against its points at reset (`O.orientation`):
        by `tasks.kernels.orientation` over the state's rows where the object fits its sums."""
        if name not in self._obj_rows:
            pos = self._object_points(name)[0]
            return O.orientation(pos, self._object_pos0(name), np.ones(pos.shape[:2], dtype=bool))
        sim = self.sim
        rows, n, count = self._obj_rows[name]
        return self._per_state(("orientation", name), lambda: EK.orientation(
            sim.kernel_state(), rows, sim.state_shape[2], sim.kernel_initial_positions()[0], rows, 2, count,
            n, self._serial))

    def _object_now(self, name: str) -> np.ndarray:
        """(B, 2, n) current points of world object `name`: a simulated one's state, a static
        one's (all-fixed terrain) initial points in every world."""
        if name in self._obj_index:
            rows, pts = self._obj_index[name]
            return self.sim.read_state()[rows, pts, 0:2].transpose(0, 2, 1)
        p0 = self.sim.world.object(name).pos0
        return np.broadcast_to(p0, (self.n_worlds, *p0.shape))

    def _object_pos0(self, name: str) -> np.ndarray:
        """(B, n, 2) positions of free object `name` at reset (its orientation's reference)."""
        rows, pts = self._obj_index[name]
        return self.sim.initial_positions[rows, pts]

    def _measure(self, com: np.ndarray, points: np.ndarray | None = None) -> Measure:
        """The measure of the state now: `points` from the kernel path (None when the spec's
        rewards do not read them), else a copy of the state's."""
        objects = {name: self._object_coms(name)[0] for name in self.spec.tracked}
        if not self.fused:
            points = self._robot()[0].copy()
        return Measure(com, objects, points=points, mask=self._mask, pos0=self._pos0,
                       state=self.task_state,
                       orientation_of=self._robot_orientation if self.fused else O.orientation,
                       kernels=self.fused)

    def _set_actions(self, actions) -> None:
        """`BatchSim.set_actions`; on the kernel path on a CPU a (B, max_actuators) array of finite
        actions by `tasks.kernels.clip_actions` (the same values; it writes only the robots'
        columns, which a device backend would return with the others as its memory held them).
        Anything else goes to `set_actions` itself (which raises its errors)."""
        sim = self.sim
        if (self.fused and self._cpu and isinstance(actions, np.ndarray) and actions.dtype.kind in "fiu"
                and actions.shape == (self.n_worlds, sim.max_actuators)):
            a = np.ascontiguousarray(actions, dtype=np.float64)
            if np.isfinite(a).all():
                EK.clip_actions(a, self._n_act, C.ACTION_MIN, C.ACTION_MAX, self._ti_real, sim.actions,
                                self._serial)
                return
        sim.set_actions(actions)

    def _points_out(self) -> np.ndarray:
        """The next of the two points buffers (`_init_fused`)."""
        self._points_flip ^= 1
        return self._points_buf[self._points_flip]

    def _fused_coms(self) -> tuple[np.ndarray, np.ndarray, np.ndarray | None]:
        """(com, vcom, points or None) of the robots now, by `tasks.kernels.robot_coms`."""
        B = self.n_worlds
        com, vcom = np.empty((B, 2)), np.empty((B, 2))
        pts = self._points_out()
        sim = self.sim
        EK.robot_coms(sim.kernel_state(), self._npts, sim.state_shape[1], sim.max_robot_points,
                      self._masked, com.reshape(-1), vcom.reshape(-1), self.spec.reads_points,
                      pts.reshape(-1), self._ti_real, self._serial)
        return com, vcom, pts if self.spec.reads_points else None

    def _fused_observe(self) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray | None]:
        """(obs, com, vcom, points or None) now, by `tasks.kernels.observe`: the observation's
        points and padding written, its other blocks left to `_fused_blocks`."""
        B = self.n_worlds
        com, vcom = np.empty((B, 2)), np.empty((B, 2))
        obs = self._obs_buf  # the env's own (the caller gets copies): its memory stays mapped
        pts = self._points_out()
        sim = self.sim
        EK.observe(sim.kernel_state(), self._npts, sim.state_shape[1], sim.max_robot_points,
                   self._masked, com.reshape(-1), vcom.reshape(-1), self.spec.reads_points,
                   pts.reshape(-1), self._head, self.max_obs_dim, obs.reshape(-1), self._ti_real,
                   self._serial)
        return obs, com, vcom, pts if self.spec.reads_points else None

    def _fused_blocks(self, obs: np.ndarray, com: np.ndarray, vcom: np.ndarray,
                      measure: Measure | None = None) -> None:
        """The observation's blocks other than the points, into `obs` (`_fused_observe`);
        `measure`, of the same state, lends them what it computed (the orientation)."""
        if not self._head_blocks and not self._tail_blocks:
            return
        scene = self._scene(com, vcom, measure)
        col = 0
        for block in self._head_blocks:
            obs[:, col:col + block.width] = block.fn(scene)
            col += block.width
        if self._tail_blocks:
            values = np.empty((self.n_worlds, self._tail_width), dtype=self.dtype)
            col = 0
            for block in self._tail_blocks:
                values[:, col:col + block.width] = block.fn(scene)
                col += block.width
            EK.tail(self._npts, self._head, values, self.max_obs_dim, obs.reshape(-1), not self._cpu,
                    self._serial)

    def _scene(self, com: np.ndarray, vcom: np.ndarray, measure: Measure | None = None) -> O.Scene:
        return O.Scene(robot=self._robot, mask=self._mask, n_points=self.n_points, com=com, vcom=vcom,
                       pos0=self._pos0, terrain=self._terrain, object_points=self._object_points,
                       object_pos0=self._object_pos0, object_coms=self._object_coms,
                       object_orientation=self._object_orientation if self.fused else None,
                       robot_orientation=self._robot_orientation_now if self.fused else None,
                       state=self.task_state,
                       object_now=self._object_now, measure=measure,
                       static_sight=self._static_sight if self.fused else None,
                       object_sight=self._object_sight if self.fused else None)

    def _static_sight(self, dist: int, below: bool) -> np.ndarray:
        """`O.terrain_sight` of `O.com_voxel_units` over the static terrain, by
        `tasks.kernels.com_voxel_units` and `tasks.kernels.terrain_sight`."""
        com_vox = self._com_vox()
        if self._terrain_vox.shape[1] == 0:
            return O.terrain_sight(com_vox, self._terrain, dist, below=below)
        out = np.empty((self.n_worlds, 2 * dist + 1))
        EK.terrain_sight(com_vox, self._terrain_vox[0], self._terrain_vox[1], dist, below, 5.0, C.CELL,
                         out, self._serial)
        return out

    def _com_vox(self) -> np.ndarray:
        """(B, 2) `O.com_voxel_units` of the robots now, by `tasks.kernels.com_voxel_units`
        (once per state)."""
        def compute():
            sim = self.sim
            com_vox = np.empty((self.n_worlds, 2))
            EK.com_voxel_units(sim.kernel_state(), self._npts, sim.state_shape[1], C.CELL, self._ti_real,
                               com_vox, self._serial)
            return com_vox
        return self._per_state(("com_vox", ""), compute)

    def _object_sight(self, dist: int, below: bool, objects: tuple[str, ...]) -> np.ndarray | None:
        """`O.terrain_sight` over the named objects' current points (`O._sight_points`), by
        `tasks.kernels.object_sight`: the simulated ones' from the state, the fixed ones' (the same
        in every world) divided by the cell once, in the type numpy's concatenation has. None
        (numpy's way, then) when none of them is simulated."""
        if not any(name in self._obj_index for name in objects):
            return None
        plan = self._sight_plans.get(objects)
        if plan is None:
            plan = self._sight_plans[objects] = self._sight_plan(objects)
        rows, tx, ty, n_static, real = plan
        sim = self.sim
        out = np.empty((self.n_worlds, 2 * dist + 1))
        EK.object_sight(sim.kernel_state(), rows, sim.state_shape[1], tx, ty, n_static, self._com_vox(), dist,
                        below, 5.0, C.CELL, real, out, self._serial)
        return out

    def _sight_plan(self, objects: tuple[str, ...]) -> tuple:
        """What `_object_sight` passes for `objects`: the simulated ones' state rows (B, M), the
        fixed ones' points in voxel units (x row, y row; one padding point when there are none),
        their count, and the Taichi type the points are divided in."""
        moving = [n for n in objects if n in self._obj_index]
        fixed = [self.sim.world.object(n).pos0 for n in objects if n not in self._obj_index]
        real = np.result_type(self.dtype, *(p.dtype for p in fixed))
        rows = np.concatenate([self._obj_index[n][1] for n in moving], axis=1)
        pts = (np.concatenate(fixed, axis=1).astype(real) / C.CELL if fixed else np.zeros((2, 1), real))
        return (constant(rows.astype(np.int32), self._cpu), constant(pts[0], self._cpu),
                constant(pts[1], self._cpu), len(pts[0]) if fixed else 0,
                EK.ti.f32 if real == np.float32 else EK.ti.f64)

    # ------------------------------------------------------------------ task state
    def seed(self, seeds: Sequence[int] | int | None = None) -> None:
        """Restart the worlds' random streams, from which a task with per-episode randomness draws.

        Such a task (`TaskSpec.state`) draws from world w's stream (a `random.Random`) at every
        reset of world w.

        Args:
            seeds: One seed per world, world w's stream seeded with `seeds[w]`; an int s seeds it
                with s + w, and None with w.

        Raises:
            ValueError: When a sequence of seeds does not hold one per world.
        """
        if seeds is None or np.ndim(seeds) == 0:  # None, an int, a numpy integer or a 0-d array
            base = 0 if seeds is None else int(seeds)
            self._seeds = (base, None)
        else:
            if len(seeds) != self.n_worlds:
                raise ValueError(f"{len(seeds)} seeds for {self.n_worlds} worlds")
            self._seeds = (0, [int(s) for s in seeds])
        # made when a world first draws (a task without per-episode randomness never does)
        self._rngs = {}

    def _rng(self, w: int) -> random.Random:
        """World w's random stream, seeded by `seed` (made on first use)."""
        rng = self._rngs.get(w)
        if rng is None:
            base, seeds = self._seeds
            rng = self._rngs[w] = random.Random(base + w if seeds is None else seeds[w])
        return rng

    def _init_state(self, mask: np.ndarray | None) -> None:
        if self.spec.state is None:
            return
        worlds = range(self.n_worlds) if mask is None else np.nonzero(mask)[0]
        for w in worlds:
            for key, value in self.spec.state(self._rng(int(w))).items():
                value = np.asarray(value)
                if key not in self.task_state:
                    self.task_state[key] = np.zeros((self.n_worlds, *value.shape), value.dtype)
                self.task_state[key][w] = value

    def _place_objects(self, mask: np.ndarray | None) -> None:
        """Objects placed per episode (`TaskSpec.placement`) go where this episode's task state
        puts them, in the worlds being reset (before the simulator's reset, which starts from
        there)."""
        if self.spec.placement is None:
            return
        worlds = range(self.n_worlds) if mask is None else np.nonzero(mask)[0]
        for w in worlds:
            one = {k: v[w] for k, v in self.task_state.items()}
            cells = self.spec.placement(one)
            self.spec.check_placement(cells)
            for name, cell in cells.items():
                self.sim.place_object(w, name, cell)

    # ------------------------------------------------------------------ API
    def reset(self, mask: np.ndarray | None = None) -> np.ndarray:
        """Start new episodes: all worlds, or only those where `mask` (B,) is True."""
        if mask is not None:
            mask = self.sim.reset_mask(mask)
        self._init_state(mask)
        self._place_objects(mask)
        self.sim.reset(mask)
        self._points_now.clear()
        if mask is None:
            self.elapsed = np.zeros(self.n_worlds, dtype=np.int64)
            self.terminated = np.zeros(self.n_worlds, dtype=bool)
            self._pos0 = self._robot()[0].copy()
            self._pos0_k = None  # `_robot_orientation_now`'s copy of it
        else:
            self.elapsed[mask] = 0
            self.terminated[mask] = False
        return self.observe()

    @property
    def t(self) -> int:
        """Steps taken by the longest-running world since its reset."""
        return int(self.elapsed.max())

    def step(self, actions) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, dict]:
        """Advance every world by one env step.

        An unstable world gets -3 and terminates; a terminated one earns 0 from then on.

        Args:
            actions (ArrayLike): (B, max_actuators), robot b using its first `n_actuators[b]`
                entries, or a list of per-robot arrays (`BatchSim.set_actions`).

        Returns:
            obs: (B, max_obs_dim) observations.
            reward: (B,) rewards.
            terminated: (B,) bools.
            truncated: (B,) bools.
            info: `unstable` (B,) bools, and `t`, each world's steps since its reset.

        Raises:
            RuntimeError: Once any world reached `episode_steps`, until `reset`.
        """
        if (self.elapsed >= self.episode_steps).any():
            raise RuntimeError("episode is over (truncated); call reset()")
        self._set_actions(actions)
        self._points_now.clear()  # the caller may have written the state since the last step
        if self.fused:
            # the last measurement (after the last step, a reset or `observe`) while the state
            # is the one it measured (`BatchSim.state_version`), else a new one
            last = self._last
            if last is None or last[0] != self.sim.state_version:
                last = (None, *self._fused_coms(), None)
            # the last step's `after`, its lazily computed parts included, or a measure of these COMs
            before = last[4] if last[4] is not None else self._measure(last[1], last[3])
        else:
            before = self._measure(self._robot_coms()[0])
        active = ~self.terminated
        self.sim.step()
        self._points_now.clear()
        self.elapsed += 1
        unstable = self.sim.unstable & active
        if self.fused:  # the observation's points now, its other blocks after the reward
            obs, com_after, vcom_after, pts = self._fused_observe()
            after = self._measure(com_after, pts)
        else:
            com_after, vcom_after = self._robot_coms()
            after = self._measure(com_after)
        reward = self.spec.reward(before, after)
        reward = np.where(unstable, reward + UNSTABLE_PENALTY, reward)
        done = unstable.copy()
        if self.spec.goal is not None:
            gx, bonus = self.spec.goal[:2]
            left = tuple(self.spec.goal[2:]) == ("left",)
            goal = active & ((com_after[:, 0] < gx * 0.1) if left else (com_after[:, 0] > gx * 0.1))
            reward = np.where(goal, reward + bonus, reward)
            done |= goal
        if self.spec.termination is not None:
            extra, over = self.spec.termination(before, after)
            over = active & over
            reward = np.where(over, reward + extra, reward)
            done |= over
        reward = np.where(active, reward, 0.0).astype(self.dtype, copy=False)
        self.terminated |= done
        self.sim.deactivate(self.terminated)
        if self.fused:
            self._fused_blocks(obs, com_after, vcom_after, after)
            self._obs = obs
            self._last = (self.sim.state_version, com_after, vcom_after, pts, after)
        else:
            self._obs = self._observe(com_after, vcom_after)
        truncated = (self.elapsed >= self.episode_steps) & ~self.terminated
        info = {"unstable": unstable, "t": self.elapsed.copy()}
        return self._obs.copy(), reward, self.terminated.copy(), truncated, info

    # ------------------------------------------------------------------ measurements
    def _robot_coms(self) -> tuple[np.ndarray, np.ndarray]:
        """(B, 2) position and velocity COMs of the robots in one pass over the state; equal to
        `O.com` bit for bit (the same sums in point order; padding rows hold zeros unless a free
        object's points follow the robot's)."""
        rows = self.sim.read_state()[:, :self.sim.max_robot_points, 0:4]
        if self.sim.free_objects:
            rows = rows * self._mask[:, :, None]
        s = rows.sum(axis=1) / self.n_points[:, None]
        return s[:, 0:2], s[:, 2:4]

    def _observe(self, com: np.ndarray | None = None, vcom: np.ndarray | None = None) -> np.ndarray:
        """Observations of the current state, the spec's blocks in order; `com`, `vcom` from
        `_robot_coms` if already known."""
        if self.fused:
            obs, com, vcom, pts = self._fused_observe()
            self._fused_blocks(obs, com, vcom)
            self._last = (self.sim.state_version, com, vcom, pts, None)
            return obs
        if com is None or vcom is None:
            com, vcom = self._robot_coms()
        pos, vel = self._robot()
        m = self._mask
        B = self.n_worlds
        scene = self._scene(com, vcom)
        obs = np.zeros((B, self.max_obs_dim + 1), dtype=self.dtype)
        col, after_points = 0, None  # blocks after the points start at head + 2 n per robot
        for block in self.spec.observation:
            if block.width < 0:
                rel = (pos - com[:, None, :]) * m[:, :, None]  # = O.relative(pos, m)
                obs[np.arange(B)[:, None, None], self._rel_cols] = rel
                after_points = self._head + 2 * self.n_points
                continue
            values = block.fn(scene)
            if after_points is None:
                obs[:, col:col + block.width] = values
                col += block.width
            else:
                cols = after_points[:, None] + np.arange(block.width)[None, :]
                obs[np.arange(B)[:, None], cols] = values
                after_points = after_points + block.width
        return obs[:, :self.max_obs_dim]

    def observe(self) -> np.ndarray:
        """Observations of the current state, recomputed (e.g. after editing `sim.state`)."""
        self._points_now.clear()
        self._obs = self._observe()
        return self._obs.copy()

    def robot_obs(self, w: int) -> np.ndarray:
        """Robot w's observation without padding."""
        return self._obs[w, :self.obs_dims[w]].copy()
