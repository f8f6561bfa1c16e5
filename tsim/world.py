"""Worlds: evogym world files turned into static terrain and free objects (the files themselves
belong to the tasks that use them; see tasks/worlds).

A world file is JSON (evogym's layout, docs/TASKS.md "World files"):
    {"grid_width": W, "grid_height": H,
     "objects": {NAME: {"indices": [...], "types": [...], "neighbors": {"i": [j, ...], ...}}, ...}}
cell index i = x + y * W (x from the left, y from the bottom, in voxels); `types` are the materials
of the cells in `indices` (0 empty .. 5 fixed, `tsim.constants`); `neighbors` lists, for each cell,
the cells it is glued to. `world_from_dict` takes the same layout as a dict, `world_from_matrix` a
material matrix (row 0 = top) with every filled cell glued to its filled 4-neighbours.

Fixed terrain never moves in evogym (material 5: every corner point is fixed), so it is kept as
static geometry with a dense cell grid for contact look-ups, not as simulated points. Free objects
(Thrower's package) are simulated like the robot; so are objects that mix fixed and free voxels
(their material-5 corners are the simulator's fixed points) and all-fixed objects placed anew in
each world and episode (`per_world`: Catcher-v0's pegs), whose points are then all fixed.
"""

from __future__ import annotations

import json
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from tsim import constants as C
from tsim.body import Body, build_body


@dataclass(frozen=True, eq=False)
class WorldObject:
    """One object of a world file: its body (FIXED voxels allowed), the grid cell of its bounding
    box's bottom-left, and `pos0`, evogym's exact initial point positions (2, n)."""
    name: str
    body: Body
    cell: tuple[int, int]  # grid cell of the bottom-left of the object's bounding box
    pos0: np.ndarray  # (2, n) exact initial positions
    per_world: bool = False  # placed per world and episode (BatchSim.place_object): never terrain
    # driven like the robot (evogym lets any object with actuators be a robot): its actuators
    # read BatchSim.actions after the robot's and earlier actuated objects' (sgr.evogym's worlds)
    actuated: bool = False

    @property
    def is_fixed(self) -> bool:
        """True when every voxel is FIXED (material 5)."""
        return bool(np.all(self.body.voxel_type == C.FIXED))

    @property
    def is_terrain(self) -> bool:
        """All fixed and in the same place in every world: static terrain, never simulated."""
        return self.is_fixed and not self.per_world

    def placed(self, name: str, cell: tuple[int, int], per_world: bool = False) -> WorldObject:
        """This object renamed and moved with its bounding box's bottom-left at grid cell `cell`
        (evogym's `WorldObject.rename` and `set_pos`)."""
        cell = (int(cell[0]), int(cell[1]))
        return WorldObject(name=name, body=self.body, cell=cell, pos0=self.body.place(*cell),
                           per_world=per_world)


@dataclass(frozen=True)
class Terrain:
    """Static surface voxels of every fixed object, with a cell -> voxel look-up grid.

    `corners[i]` holds voxel i's corners (TL, TR, BR, BL) as exact doubles; `open[i]` flags its
    sides without a connection (top, right, bottom, left), the only sides that can be contact edges;
    `edge_corners[i, s]` are the two corner slots of side s in evogym's edge orientation.
    """

    corners: np.ndarray  # (n, 4, 2)
    open: np.ndarray  # (n, 4) bool
    edge_corners: np.ndarray  # (n, 4, 2) corner slots (0..3) of each side's endpoints a, b
    grid: np.ndarray  # (grid_w, grid_h) int voxel index or -1 (includes cells off the surface: -1)
    n_points: int  # number of terrain points (for evogym's global point count)


@dataclass(frozen=True, eq=False)
class World:
    """A loaded evogym world file: its grid, its objects and its static terrain.

    Attributes:
        name: The world's name (a world file's stem).
        grid_w: The grid's width in cells.
        grid_h: The grid's height in cells.
        objects: Every object, in evogym's load order (after the robot): sorted by name.
        terrain: The static terrain, built from the fixed objects.
    """
    name: str
    grid_w: int
    grid_h: int
    objects: tuple[WorldObject, ...]  # in evogym load order after the robot: sorted by name
    terrain: Terrain

    @property
    def free_objects(self) -> tuple[WorldObject, ...]:
        """Objects simulated as points after the robot's (e.g. Thrower's package), in load order."""
        return tuple(o for o in self.objects if not o.is_terrain)

    @property
    def fixed_objects(self) -> tuple[WorldObject, ...]:
        """Objects that are static terrain, in load order.

        Their voxels are all FIXED, and they are in the same place in every world.
        """
        return tuple(o for o in self.objects if o.is_terrain)

    def with_objects(self, extra: tuple[WorldObject, ...]) -> World:
        """This world plus objects added in code (evogym's `EvoWorld.add_object`).

        All objects are in load order again (sorted by name as strings); the grid grows to hold
        them, as evogym's does.

        Args:
            extra: The objects to add.

        Returns:
            A new world; this one is left as it is.

        Raises:
            ValueError: When two objects have the same name.
        """
        names = [o.name for o in self.objects] + [o.name for o in extra]
        if len(set(names)) != len(names):
            raise ValueError(f"world {self.name}: duplicate object names in {names}")
        objects = tuple(sorted(self.objects + tuple(extra), key=lambda o: o.name))
        grid_w = max([self.grid_w] + [o.cell[0] + o.body.matrix.shape[1] for o in extra])
        grid_h = max([self.grid_h] + [o.cell[1] + o.body.matrix.shape[0] for o in extra])
        return World(name=self.name, grid_w=grid_w, grid_h=grid_h, objects=objects,
                     terrain=_build_terrain(objects, grid_w, grid_h))

    def object(self, name: str) -> WorldObject:
        """The object called `name`, fixed or free; KeyError when the world has none."""
        for o in self.objects:
            if o.name == name:
                return o
        raise KeyError(f"world {self.name} has no object {name!r}")


def _object_from_json(name: str, data: dict, grid_w: int) -> WorldObject:
    idx = [int(i) for i in data["indices"]]
    xs = [i % grid_w for i in idx]
    ys = [i // grid_w for i in idx]
    x0, x1, y0, y1 = min(xs), max(xs), min(ys), max(ys)
    w, h = x1 - x0 + 1, y1 - y0 + 1
    m = np.zeros((h, w), dtype=np.int64)

    def local(i: int) -> int:
        return (y1 - i // grid_w) * w + (i % grid_w - x0)

    for i, t in zip(idx, data["types"], strict=False):
        m.flat[local(i)] = int(t)
    pairs = {tuple(sorted((local(int(a)), local(int(b)))))
             for a, nbs in data["neighbors"].items() for b in nbs}
    conn = np.array(sorted(pairs), dtype=np.int64).T.reshape(2, -1)
    body = build_body(m, conn, allow_fixed=True)
    return WorldObject(name=name, body=body, cell=(x0, y0), pos0=body.place(x0, y0))


def _items(data: object, source: str) -> tuple[int, int, list]:
    try:
        grid_w, grid_h = int(data["grid_width"]), int(data["grid_height"])
        if grid_w < 1 or grid_h < 1:
            raise ValueError(f"the grid must be at least 1x1, got {grid_w}x{grid_h}")
        items = sorted(data["objects"].items())
        for obj, d in items:
            if len(d["indices"]) != len(d["types"]):
                raise ValueError(f"{len(d['indices'])} indices but {len(d['types'])} types")
            # a negative index would wrap round into another row; a free object may start above
            # the grid (evogym loads it), the terrain's cells are the grid's
            terrain = all(int(t) == C.FIXED for t in d["types"])
            top = grid_w * grid_h if terrain else None
            outside = [i for i in d["indices"] if int(i) < 0 or top is not None and int(i) >= top]
            if outside:
                where = f"0..{grid_w * grid_h - 1}" if terrain else "0 or more"
                raise ValueError(f"object {obj!r}: cell index {outside[0]} is outside the "
                                 f"{grid_w}x{grid_h} grid ({where}{' for terrain' if terrain else ''})")
    except (ValueError, KeyError, AttributeError, TypeError) as exc:
        raise ValueError(f"bad world {source}: {type(exc).__name__}: {exc}") from None
    return grid_w, grid_h, items


def _read(path: Path) -> tuple[int, int, list]:
    try:
        data = json.loads(path.read_text())
    except (OSError, ValueError) as exc:
        raise ValueError(f"bad world file {path}: {exc}") from None
    return _items(data, f"file {path}")


def _world(name: str, grid_w: int, grid_h: int, items: list, source: str) -> World:
    try:
        objects = tuple(_object_from_json(n, d, grid_w) for n, d in items)
    except (ValueError, KeyError, TypeError) as exc:
        raise ValueError(f"bad world {source}: {exc}") from None
    terrain = _build_terrain(objects, grid_w, grid_h)
    return World(name=name, grid_w=grid_w, grid_h=grid_h, objects=objects, terrain=terrain)


def load_world(path: str | Path) -> World:
    """Read an evogym world JSON file (grid size, objects with indices, types, neighbours)."""
    path = Path(path)
    grid_w, grid_h, items = _read(path)
    return _world(path.stem, grid_w, grid_h, items, f"file {path}")


def make_world(name: str, grid_w: int, grid_h: int, objects: tuple[WorldObject, ...]) -> World:
    """A world built in code rather than read from a file (evogym's `EvoWorld`, for sgr.evogym):
    the objects in the load order given (evogym's: robots, then the others, each sorted by name)
    and the static terrain of the fixed ones."""
    objects = tuple(objects)
    return World(name=name, grid_w=grid_w, grid_h=grid_h, objects=objects,
                 terrain=_build_terrain(objects, grid_w, grid_h))


def load_object(path: str | Path) -> WorldObject:
    """The one object of an evogym object file (e.g. `rigid_2x2.json`), as it sits in that file;
    `WorldObject.placed` renames and moves it (evogym's `WorldObject.from_json`)."""
    path = Path(path)
    grid_w, _, items = _read(path)
    if len(items) != 1:
        raise ValueError(f"bad object file {path}: {len(items)} objects, expected 1")
    return _object_from_json(items[0][0], items[0][1], grid_w)


def world_from_dict(data: dict, name: str = "custom") -> World:
    """A world from a dict in the world file's layout (module docstring), without writing JSON."""
    grid_w, grid_h, items = _items(data, repr(name))
    return _world(name, grid_w, grid_h, items, repr(name))


def world_from_matrix(matrix: object, name: str = "custom") -> World:
    """A world drawn as a material matrix.

    Row 0 is the top, as in body matrices; 5 is fixed terrain, and other materials make simulated
    objects. Every filled cell is glued to its filled 4-neighbours, and each connected group of
    cells is one object, named terrain, terrain_1, ... in reading order. The grid is the matrix's
    size: leave empty rows above the terrain for the robot.

    Args:
        matrix: A non-empty 2-D array of ints, material codes 0 to 5.
        name: The world's name.

    Raises:
        ValueError: When `matrix` is not such an array, or has no material > 0.
    """
    m = np.asarray(matrix)
    if m.ndim != 2 or m.size == 0 or not np.issubdtype(m.dtype, np.integer):
        raise ValueError(f"world {name!r}: a terrain matrix must be a non-empty 2-D array of ints")
    if m.min() < C.EMPTY or m.max() > C.FIXED:
        raise ValueError(f"world {name!r}: materials must be {C.EMPTY}..{C.FIXED}, got {m.min()}..{m.max()}")
    h, w = m.shape
    index = lambda r, c: c + (h - 1 - r) * w  # evogym's cell index: x + y * width, y from the bottom
    seen = np.zeros(m.shape, dtype=bool)
    objects = {}
    for r0 in range(h):
        for c0 in range(w):
            if m[r0, c0] == C.EMPTY or seen[r0, c0]:
                continue
            seen[r0, c0] = True
            stack, cells = [(r0, c0)], []
            while stack:  # one connected group (4-neighbours), grown from its first cell
                r, c = stack.pop()
                cells.append((r, c))
                for rr, cc in ((r - 1, c), (r + 1, c), (r, c - 1), (r, c + 1)):
                    if 0 <= rr < h and 0 <= cc < w and m[rr, cc] != C.EMPTY and not seen[rr, cc]:
                        seen[rr, cc] = True
                        stack.append((rr, cc))
            cells.sort()
            members = set(cells)
            objects[f"terrain_{len(objects)}" if objects else "terrain"] = {
                "indices": [index(r, c) for r, c in cells],
                "types": [int(m[r, c]) for r, c in cells],
                "neighbors": {str(index(r, c)): [index(rr, cc) for rr, cc in
                                                 ((r - 1, c), (r + 1, c), (r, c - 1), (r, c + 1))
                                                 if (rr, cc) in members]
                              for r, c in cells}}
    if not objects:
        raise ValueError(f"world {name!r}: the terrain matrix is empty (no material > 0)")
    return world_from_dict({"grid_width": w, "grid_height": h, "objects": objects}, name)


# Where a world given by name comes from: a layer above the simulator (tasks) adds a finder that
# maps its names (task ids) to worlds, so `Renderer("Walker-v0", body)` works without tsim knowing
# any task.
_FINDERS: list[Callable[[str], World | None]] = []


def add_world_finder(find: Callable[[str], World | None]) -> None:
    """Let `resolve_world` look names up with `find(name) -> World or None` (idempotent)."""
    if find not in _FINDERS:
        _FINDERS.append(find)


def resolve_world(world: World | str | Path) -> World:
    """A World as is; a path to a world file, loaded; else a name a finder knows (a task id once
    `import tasks` has run). ValueError saying which of these it is not."""
    if isinstance(world, World):
        return world
    if Path(world).is_file():
        return load_world(world)
    for find in _FINDERS:
        found = find(str(world))
        if found is not None:
            return found
    raise ValueError(f"no world {str(world)!r}: not a world file, nor a task name "
                     f"({'import tasks first' if not _FINDERS else 'no task of that name'})")


# evogym edge orientation of a voxel's sides in corner slots (TL=0, TR=1, BR=2, BL=3):
# surface sides run clockwise (outward normal = direction rotated +90 deg); inner sides keep
# their creation direction (top TL->TR, right TR->BR, bottom BL->BR, left TL->BL).
_SURFACE_SIDES = np.array([[0, 1], [1, 2], [2, 3], [3, 0]])
_INNER_SIDES = np.array([[0, 1], [1, 2], [3, 2], [0, 3]])


def _build_terrain(objects: tuple[WorldObject, ...], grid_w: int, grid_h: int) -> Terrain:
    corners, opens, sides, cells = [], [], [], []
    n_points = 0
    for obj in (o for o in objects if o.is_terrain):
        b = obj.body
        n_points += b.n_points
        surface = b.voxel_is_surface
        for v in range(b.n_voxels):
            if not surface[v]:
                continue
            corners.append(obj.pos0[:, b.voxel_points[v]].T)
            opens.append(b.voxel_open[v])
            sides.append(np.where(b.voxel_open[v][:, None], _SURFACE_SIDES, _INNER_SIDES))
            r, c = b.voxel_rc[v]
            cells.append((obj.cell[0] + c, obj.cell[1] + b.matrix.shape[0] - 1 - r))
    grid = -np.ones((grid_w, grid_h), dtype=np.int64)
    for i, (gx, gy) in enumerate(cells):
        grid[gx, gy] = i
    return Terrain(
        corners=np.array(corners, dtype=np.float64).reshape(-1, 4, 2),
        open=np.array(opens, dtype=bool).reshape(-1, 4),
        edge_corners=np.array(sides, dtype=np.int64).reshape(-1, 4, 2),
        grid=grid, n_points=n_points,
    )
