"""evogym 2.0's `EvoSim` on sgr's simulator: one world (a `tsim.BatchSim` of one), stepped,
reset and read back at any past step in evogym's units (voxels: positions / 0.1) and point order.

evogym loads the objects of a world in this order: robots (objects with an actuator) sorted by
name, then the others sorted by name; `pos_at_time` lists every point in that order, terrain
included. BatchSim keeps all-fixed objects as static terrain (their points never move) and
simulates the robots and the other objects (the first robot as BatchSim's robot, the others as
actuated objects); this module keeps the history evogym keeps (every
step's positions and velocities of the simulated points, a copy per step, ~1 us) and puts terrain
points back in their place when read. Worlds evogym accepts but sgr cannot simulate raise one
`ValueError` that names what is missing.
"""

from __future__ import annotations

import warnings

import numpy as np

from sgr.evogym.utils import VOXEL_TYPES
from sgr.evogym.world import EvoWorld
from tasks.orientation import orientation
from tsim.body import Body, build_body
from tsim.sim import NONFINITE, RUNNING, UNSTABLE, BatchSim
from tsim.world import WorldObject as _Placed
from tsim.world import make_world

__all__ = ["EvoSim"]


def _is_robot(grid: np.ndarray) -> bool:
    return bool(np.any((grid == VOXEL_TYPES["H_ACT"]) | (grid == VOXEL_TYPES["V_ACT"])))


def _connections(obj) -> np.ndarray:
    """(2, k) glued pairs of an EvoWorld object as flat indices into its top-row-first structure
    (what evogym hands its simulator)."""
    w, h = obj.grid_size.x, obj.grid_size.y
    pairs = [((h - 1 - v.y) * w + v.x, (h - 1 - n.y) * w + n.x)
             for v, ns in obj.neighbors.items() if obj.grid[v.y][v.x] != 0 for n in ns]
    return np.array(pairs, dtype=np.int64).T.reshape(2, -1)


def _body(name: str, structure: np.ndarray, conn: np.ndarray, robot: bool) -> Body:
    if not np.any(np.asarray(structure) != 0):
        raise ValueError(f"cannot simulate object {name!r}: it has no voxels")
    try:
        return build_body(structure, conn, allow_fixed=not robot)
    except ValueError as exc:
        what = "robot" if robot else "object"
        if robot and np.any(structure == VOXEL_TYPES["FIXED"]):
            raise ValueError(f"sgr cannot simulate robot {name!r}: it has fixed voxels (material 5); "
                             "sgr fixes voxels only in objects without actuators") from None
        raise ValueError(f"cannot simulate {what} {name!r}: {exc}") from None


class EvoSim:
    """Create, step, reset and read an evogym simulation of `world` (an `EvoWorld`)."""

    VOXEL_SIZE = 0.1

    def __init__(self, world: EvoWorld) -> None:
        if not isinstance(world, EvoWorld):
            raise TypeError(f"EvoSim needs an EvoWorld, got {type(world).__name__}")
        names = sorted(world.objects, key=lambda n: (0 if _is_robot(world.objects[n].grid) else 1, n))
        robots = [n for n in names if _is_robot(world.objects[n].grid)]
        parts: dict[str, _Placed] = {}
        for n in names:
            obj = world.objects[n]
            structure = np.flipud(obj.grid)
            body = _body(n, structure, _connections(obj), n in robots)
            cell = (obj.pos.x, obj.pos.y)
            parts[n] = _Placed(name=n, body=body, cell=cell, pos0=body.place(*cell),
                               actuated=n in robots[1:])
        # BatchSim's robot: the first robot, or (no robot) the first object without fixed voxels
        # (BatchSim fixes points of its objects only), in evogym's order
        leads = robots or [n for n in names if not np.any(parts[n].body.voxel_type == VOXEL_TYPES["FIXED"])]
        if not parts:
            raise ValueError("sgr cannot simulate this world: it has no objects (add a robot with "
                             "EvoWorld.add_from_array)")
        if not leads:
            what = ("all fixed (material 5): nothing in it moves" if all(p.is_terrain for p in parts.values())
                    else "fixed voxels in every object, and no robot (sgr needs one object without "
                    "fixed voxels to lead the simulation)")
            raise ValueError(f"sgr cannot simulate this world: its objects have {what}")
        lead = leads[0]
        others = tuple(parts[n] for n in names if n != lead)
        grid = world.grid_size
        self._world_layout = make_world("EvoWorld", grid.x, grid.y, others)
        try:
            self._bs = BatchSim(self._world_layout, [parts[lead].body], parts[lead].cell,
                                passive_ok=not robots)
        except ValueError as exc:
            raise ValueError(f"cannot simulate {lead!r}: {exc}") from None
        if not robots:  # evogym's instability rule counts only robots' self-collisions
            self._bs.ignore_robot_self_collisions()
        self._robots = {n: parts[n].body for n in robots}
        # action columns of each robot in BatchSim.actions: the lead's first, then the others'
        self._act_cols, col = {}, 0
        for n in robots:
            self._act_cols[n] = col
            col += parts[n].body.n_actuators
        # evogym's instability rule for the robots after the first (BatchSim's kernel applies it
        # to the lead robot at every substep): their surface voxels' corners and grid cells
        self._extra_rule = []
        for n in robots[1:]:
            b = parts[n].body
            surf = np.nonzero(b.voxel_is_surface)[0]
            rc = b.voxel_rc[surf]
            near = ((np.abs(rc[:, None, 0] - rc[None, :, 0]) <= 1)
                    & (np.abs(rc[:, None, 1] - rc[None, :, 1]) <= 1))
            self._extra_rule.append((n, b.voxel_points[surf], near, len(surf)))
        self._object_names = set(names)
        # where each object's points sit: simulated ones in BatchSim's state, terrain after them
        offsets = {lead: 0}
        for k, o in enumerate(self._bs.free_objects):
            offsets[o.name] = int(self._bs.object_offsets(k)[0])
        self._n_sim = int(self._bs.n_points[0])
        terrain = [parts[n] for n in names if n not in offsets]
        self._terrain_pos = (np.concatenate([t.pos0.T for t in terrain]) if terrain
                             else np.zeros((0, 2)))
        t_off, self._slices = self._n_sim, {}
        for t in terrain:
            offsets[t.name] = t_off
            t_off += t.body.n_points
        for n in names:
            self._slices[n] = np.arange(offsets[n], offsets[n] + parts[n].body.n_points)
        self._all = np.concatenate([self._slices[n] for n in names])
        # the simulated objects' rows in a snapshot, as slices (reading them copies nothing)
        self._sim_rows = {n: slice(offsets[n], offsets[n] + parts[n].body.n_points) for n in names
                          if offsets[n] + parts[n].body.n_points <= self._n_sim}
        self._unstable_warned = False
        self.reset()

    # ------------------------------------------------------------------ control
    def reset(self) -> None:
        """Back to time 0: the initial placement at rest; later history is dropped."""
        self._bs.reset()
        self._time = 0
        self._history = [self._snapshot()]

    def revert(self, time: int) -> None:
        """Back to step `time`: its positions and velocities, later history dropped (evogym's `revert`).

        Args:
            time: A step from 0 to `get_time()`.

        Raises:
            TypeError: `time` is not an int.
            ValueError: `time` is outside [0, `get_time()`].
        """
        self._check_time(time)
        snap = self._history[time]
        s = self._bs.state[0, :self._n_sim]
        s[:, 0:2] = snap[:, 0:2]
        s[:, 2:4] = snap[:, 2:4]
        s[:, 4:6] = snap[:, 0:2]
        s[:, 6:8] = snap[:, 2:4]
        self._bs.set_world_status(0, RUNNING)
        self._time = time
        del self._history[time + 1:]

    def _snapshot(self) -> np.ndarray:
        return self._bs.read_state()[0, :self._n_sim, 0:4].copy()

    def set_action(self, robot_name: str, action: np.ndarray) -> None:
        """Set the actuator targets of robot `robot_name` for the next steps, as given.

        evogym does not clip here; EvoGymBase.step clips to [0.6, 1.6].

        Args:
            robot_name: The robot's name in the world.
            action: One target per actuator, in `get_actuator_indices` order.

        Raises:
            ValueError: An unknown robot, the wrong number of values, or a non-finite one.
        """
        body = self._robot(robot_name)
        a = np.asarray(action, dtype=np.float64).reshape(-1)
        if a.shape != (body.n_actuators,):
            raise ValueError(f"expected action with {body.n_actuators} values but got action with "
                             f"{a.size} values for {robot_name}")
        if not np.isfinite(a).all():
            raise ValueError(f"non-finite action for {robot_name}: {a[~np.isfinite(a)][:3]}")
        col = self._act_cols[robot_name]
        self._bs.actions[0, col:col + body.n_actuators] = a

    def step(self) -> bool:
        """Advance one step (30 substeps of dt = 1e-4).

        When evogym's instability rule fires, time does not advance and the last snapshot stays the
        current state. Unlike evogym, which goes on from the unstable state, later steps do nothing
        (and warn once) until `reset` or `revert`.

        Returns:
            True when evogym's instability rule fired (or the state stopped being finite).
        """
        if self._stopped():
            if not self._unstable_warned:
                warnings.warn("EvoSim.step after an unstable step: sgr keeps the last stable state "
                              "(evogym goes on from the unstable one); reset() or revert() to go on",
                              stacklevel=2)
                self._unstable_warned = True
            return True
        self._bs.step()
        if self._stopped():
            return True
        if self._extra_unstable():
            self.revert(self._time)  # evogym keeps the last snapshot
            self._bs.set_world_status(0, UNSTABLE)
            return True
        self._time += 1
        self._history.append(self._snapshot())
        return False

    def _stopped(self) -> bool:
        """The world is frozen by the instability rule or a non-finite state (`BatchSim.unstable`
        for the one world, read as a scalar: this runs twice per step)."""
        return self._bs.world_status(0) in (UNSTABLE, NONFINITE)

    def _extra_unstable(self) -> bool:
        """evogym's rule for the robots after the first, at the end of the step: more ordered
        pairs of non-adjacent surface voxels of one robot with touching bounding boxes than the
        robot has surface voxels. (evogym tests it at every substep: a robot that crosses the
        threshold and comes back within one step is not caught; see docs/EVOGYM_COMPAT.md.)"""
        for name, corners, near, n_surf in self._extra_rule:
            pts = self._bs.read_state()[0, self._slices[name][corners], 0:2]  # (n_surf, 4, 2)
            lo, hi = pts.min(axis=1), pts.max(axis=1)
            touch = np.all((lo[:, None, :] <= hi[None, :, :]) & (lo[None, :, :] <= hi[:, None, :]), axis=2)
            if int(np.sum(touch & ~near)) > n_surf:
                return True
        return False

    def get_time(self) -> int:
        """Steps since the last reset (an int)."""
        return self._time

    # ------------------------------------------------------------------ robots
    def _robot(self, robot_name: str) -> Body:
        if robot_name not in self._robots:
            known = ", ".join(sorted(self._robots)) or "none"
            raise ValueError(f"{robot_name} is not a valid robot name (robots: {known})")
        return self._robots[robot_name]

    def get_actuator_indices(self, robot_name: str) -> np.ndarray:
        """(n,) flat indices of the robot's actuator voxels in its structure, in action order."""
        return np.asarray(self._robot(robot_name).actuator_flat, dtype=np.int64).copy()

    def get_dim_action_space(self, robot_name: str) -> int:
        """Number of actuators of robot `robot_name`."""
        return int(self._robot(robot_name).n_actuators)

    # ------------------------------------------------------------------ read-out
    def _check_time(self, time: int) -> None:
        if not isinstance(time, (int, np.integer)) or isinstance(time, bool):
            raise TypeError(f"time {time} is not of type int")
        if time < 0 or time > self._time:
            raise ValueError(f"time {time} is outside valid range [0, {self._time}]")

    def _check_object(self, name: str) -> None:
        if name not in self._object_names:
            raise ValueError(f"{name} is not a valid object name (objects: "
                             f"{', '.join(sorted(self._object_names))})")

    def _render_scene(self):
        """What EvoViewer draws now: tsim's world, the lead body, its points and the other
        simulated objects' points (world units)."""
        snap = self._history[self._time]
        lead = snap[:self._bs.n_robot_points[0], 0:2].T
        objects = {o.name: snap[self._slices[o.name], 0:2].T for o in self._bs.free_objects}
        return self._bs.world, self._bs.bodies[0], lead, objects

    def _points(self, time: int, col: int) -> np.ndarray:
        """(n_all, 2) positions (col 0) or velocities (col 2) of every point at `time`, our
        layout (simulated points, then terrain)."""
        snap = self._history[time][:, col:col + 2]
        ter = self._terrain_pos if col == 0 else np.zeros_like(self._terrain_pos)
        return np.concatenate([snap, ter])

    def pos_at_time(self, time: int) -> np.ndarray:
        """(2, n) positions of every point of the world at step `time`, in voxels."""
        self._check_time(time)
        return self._points(time, 0)[self._all].T / self.VOXEL_SIZE

    def vel_at_time(self, time: int) -> np.ndarray:
        """(2, n) velocities of every point of the world at step `time`, in voxels per unit time."""
        self._check_time(time)
        return self._points(time, 2)[self._all].T / self.VOXEL_SIZE

    def _object_points(self, time: int, object_name: str, col: int) -> np.ndarray:
        """(n, 2) positions (col 0) or velocities (col 2) of one object at `time`, world units: a
        simulated object's rows of the snapshot (no terrain appended), a fixed one's from
        `_points`."""
        rows = self._sim_rows.get(object_name)
        if rows is not None:
            return self._history[time][rows, col:col + 2]
        return self._points(time, col)[self._slices[object_name]]

    def object_pos_at_time(self, time: int, object_name: str) -> np.ndarray:
        """(2, n) positions of object `object_name`'s points at step `time`, in voxels."""
        self._check_time(time)
        self._check_object(object_name)
        return self._object_points(time, object_name, 0).T / self.VOXEL_SIZE

    def object_vel_at_time(self, time: int, object_name: str) -> np.ndarray:
        """(2, n) velocities of object `object_name`'s points at step `time`, voxels per unit time."""
        self._check_time(time)
        self._check_object(object_name)
        return self._object_points(time, object_name, 2).T / self.VOXEL_SIZE

    def object_orientation_at_time(self, time: int, object_name: str) -> float:
        """evogym's orientation estimate of the object at step `time` against step 0.

        Args:
            time: A step from 0 to `get_time()`.
            object_name: The object's name in the world.

        Returns:
            The angle in radians, in [0, 2 pi), counter-clockwise.
        """
        self._check_time(time)
        self._check_object(object_name)
        idx = self._slices[object_name]
        now = self._points(time, 0)[idx][None]
        then = self._points(0, 0)[idx][None]
        return float(orientation(now, then, np.ones(now.shape[:2], dtype=bool))[0])
