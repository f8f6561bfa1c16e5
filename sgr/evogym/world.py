"""evogym 2.0's `EvoWorld` and `WorldObject` on sgr: the layout of a world before it is simulated.

Same data and semantics as evogym's: a world is a dict of named objects over a grid that grows to
hold them (row 0 of `grid` is the bottom); an object keeps its voxel grid (also bottom row first),
its position (grid cell of its bottom-left), its voxels and the neighbours each voxel is glued to.
Connections arrays are (2, k) flat indices into `structure.flatten()` of the top-row-first
structure, as in evogym. `sgr.evogym.EvoSim` turns a world into a simulation.
"""

from __future__ import annotations

import json
from typing import Any

import numpy as np

from sgr.evogym.utils import VOXEL_TYPES, Pair, get_full_connectivity
from tsim.body import as_connections

__all__ = ["EvoWorld", "WorldObject"]

_PRINT = {0: ". ", 1: "R ", 2: "S ", 3: "H ", 4: "V ", 5: "F "}


class EvoWorld:
    """A world layout: named objects on a grid (evogym's EvoWorld)."""

    def __init__(self) -> None:
        self.grid = np.array([[0]])
        self.grid_size = Pair(1, 1)
        self.objects: dict[str, WorldObject] = {}

    @classmethod
    def from_json(cls, file_path: str) -> EvoWorld:
        """A world read from an evogym world file (the Design Tool's JSON)."""
        out = cls()
        out.add_from_json(file_path)
        return out

    def add_from_json(self, file_path: str) -> None:
        """Add every object of an evogym world file (the Design Tool's JSON).

        Args:
            file_path: The world file.

        Raises:
            ValueError: A corrupted object, or a name already in the world.
        """
        with open(file_path) as f:
            state = json.load(f)
        size = Pair(int(state["grid_width"]), int(state["grid_height"]))
        for name, data in state["objects"].items():
            n = len(data["indices"])
            if n != len(data["types"]) or n != len(data["neighbors"]):
                raise ValueError(f"cannot read in file {file_path} with corrupted object {name}")
            if name in self.objects:
                raise ValueError(f"cannot read in file {file_path} with duplicate object name: {name}")
            obj = WorldObject()
            obj.load_from_parsed_json(name, data, size)
            self.add_object(obj)

    def add_from_array(self, name: str, structure: np.ndarray, x: int, y: int,
                       connections: np.ndarray | None = None) -> None:
        """Add one object from its structure, its bottom-left at grid cell (x, y).

        Args:
            name: The object's name.
            structure: Its voxel materials, top row first.
            x: The grid column of its bottom-left.
            y: The grid row of its bottom-left.
            connections: (2, k) glued pairs, flat indices into `structure.flatten()`; None: every
                adjacent pair.

        Raises:
            ValueError: A bad structure or connections, a negative position, a duplicate name, or
                an overlap with an object already there.
        """
        obj = WorldObject.from_array(name, structure, connections)
        obj.set_pos(x, y)
        self.add_object(obj)

    def add_object(self, obj: WorldObject) -> None:
        """Add `obj` at its position, growing the grid to hold it.

        Raises:
            ValueError: A duplicate name, or an overlap with an object already there.
        """
        if obj.name in self.objects:
            raise ValueError(f"cannot add object with duplicate name: {obj.name}")
        x0, y0 = obj.pos.x, obj.pos.y
        x1, y1 = x0 + obj.grid_size.x, y0 + obj.grid_size.y
        if x1 > self.grid_size.x or y1 > self.grid_size.y:
            w, h = max(x1, self.grid_size.x), max(y1, self.grid_size.y)
            grid = np.zeros((h, w), dtype=self.grid.dtype)
            grid[:self.grid_size.y, :self.grid_size.x] = self.grid
            self.grid = grid
            self.grid_size = Pair(w, h)
        if np.sum(self.grid[y0:y1, x0:x1]) != 0:
            raise ValueError(f"cannot add object {obj.name} to world since it overlaps with an "
                             "existing object")
        self.grid[y0:y1, x0:x1] = obj.grid.copy()
        self.objects[obj.name] = obj

    def remove_object(self, obj_name: str) -> WorldObject:
        """Remove the object called `obj_name` and return (a copy of) it."""
        obj = self._get(obj_name).copy()
        self.grid[obj.pos.y:obj.pos.y + obj.grid_size.y, obj.pos.x:obj.pos.x + obj.grid_size.x] = 0
        del self.objects[obj_name]
        return obj

    def translate_object(self, obj_name: str, dx: int, dy: int) -> None:
        """Move an object by (dx, dy) cells; ValueError if it would overlap another."""
        self._get(obj_name)
        obj = self.remove_object(obj_name)
        obj.translate(dx, dy)
        try:
            self.add_object(obj)
        except ValueError:
            raise ValueError(f"cannot translate object {obj.name} in world since the translated "
                             "object overlaps with an existing object") from None

    def move_object(self, obj_name: str, x: int, y: int) -> None:
        """Put an object's bottom-left at (x, y); ValueError if it would overlap another."""
        self._get(obj_name)
        obj = self.remove_object(obj_name)
        obj.set_pos(x, y)
        try:
            self.add_object(obj)
        except ValueError:
            raise ValueError(f"cannot move object {obj.name} to desired location since it will "
                             "overlap with an existing object") from None

    def _get(self, obj_name: str) -> WorldObject:
        if obj_name not in self.objects:
            raise ValueError(f"world does not contain object named {obj_name}")
        return self.objects[obj_name]

    def pretty_print(self, voxels_per_line: int = 50) -> None:
        """Print the grid, top row first, with the row and column numbers mod 10.

        Voxels print as (R)igid, (S)oft, (H)/(V) actuators, (F)ixed, '.' empty.

        Args:
            voxels_per_line: Columns per block: a wider world prints as several blocks.
        """
        for x0 in range(0, self.grid_size.x, voxels_per_line):
            cols = range(x0, min(self.grid_size.x, x0 + voxels_per_line))
            for y in reversed(range(self.grid_size.y)):
                print(f"\n{y % 10} | ", end="")
                for x in cols:
                    print(_PRINT[int(self.grid[y][x])], end="")
            print("\n   -" + "--" * len(cols), end="")
            print("\n    " + "".join(f"{x % 10} " for x in cols))


class WorldObject:
    """One named object of a world, its voxels and their neighbours (evogym's WorldObject).

    Attributes:
        name (str): The object's name.
        pos (Pair): The grid cell of its bottom-left.
        grid_size (Pair): Its grid's (width, height).
        voxels: Its non-empty cells, in its grid.
        grid: Its voxel materials, bottom row first.
        neighbors: The cells each voxel is glued to.
    """

    def __init__(self) -> None:
        self.name = ""
        self.pos = Pair(0, 0)
        self.grid_size = Pair(0, 0)
        self.voxels: list[Pair] = []
        self.grid: np.ndarray = np.zeros((0, 0))
        self.neighbors: dict[Pair, list[Pair]] = {}

    @classmethod
    def from_json(cls, file_path: str) -> WorldObject:
        """The one object of an evogym file; ValueError when it holds more than one."""
        world = EvoWorld.from_json(file_path)
        if len(world.objects) != 1:
            raise ValueError(f"loaded file, {file_path}, contains more than one object")
        return next(iter(world.objects.values()))

    def load_from_json(self, file_path: str) -> None:
        """Become the one object of an evogym file (see `from_json`)."""
        other = WorldObject.from_json(file_path)
        self.__dict__.update(other.__dict__)

    @classmethod
    def from_array(cls, name: str, structure: np.ndarray,
                   connections: np.ndarray | None = None) -> WorldObject:
        """An object from its structure (top row first) and connections (default: full)."""
        out = cls()
        out.load_from_array(name, structure, connections)
        return out

    def load_from_array(self, name: str, structure: np.ndarray,
                        connections: np.ndarray | None = None) -> None:
        """Become an object from a structure and its connections, at position (0, 0).

        Args:
            name: The object's name.
            structure: Its voxel materials, top row first (2-D).
            connections: (2, k) glued pairs, flat indices into `structure.flatten()`; None: every
                adjacent pair.

        Raises:
            ValueError: The structure is not 2-D, or a connection names an empty or missing cell.
        """
        structure = np.asarray(structure)
        if structure.ndim != 2:
            raise ValueError(f"could not load object {name} from array -- structure must be 2-D, "
                             f"got shape {structure.shape}")
        self.name = name
        try:
            conn = (get_full_connectivity(structure) if connections is None
                    else as_connections(connections)).T
        except ValueError as exc:
            raise ValueError(f"could not load object {name} from array -- {exc}") from None
        self.grid = np.flipud(structure)
        w, h = self.grid.shape[1], self.grid.shape[0]
        self.grid_size = Pair(w, h)
        self.pos = Pair(0, 0)
        self.voxels = []
        self.neighbors = {}
        at = {}
        for y in range(h):
            for x in range(w):
                if self.grid[y][x] != VOXEL_TYPES["EMPTY"]:
                    self.voxels.append(Pair(x, y))
                    at[y * w + x] = Pair(x, y)

        def flipped(i) -> int:  # flat index in the structure -> flat index in the flipped grid
            x, y = int(i) % w, int(i) // w
            return (h - 1 - y) * w + x

        for a, b in conn:
            fa, fb = flipped(a), flipped(b)
            if fa not in at or fb not in at:
                raise ValueError(f"could not load object {self.name} from array -- connections "
                                 "matrix contains invalid elements")
            self.neighbors.setdefault(at[fa], []).append(at[fb])
            self.neighbors.setdefault(at[fb], []).append(at[fa])

    def load_from_parsed_json(self, name: str, json_data: Any, grid_size: Pair) -> None:
        """Become object `name` of a parsed world file.

        Args:
            name: The object's name.
            json_data: Its entry in the file's `objects`: `indices`, `types` and `neighbors`.
            grid_size: The world's grid size: its width reads the flat indices.

        Raises:
            ValueError: The object has no voxels, or a neighbour outside it.
        """
        self.name = name
        idx = [int(i) for i in json_data["indices"]]
        if not idx:
            raise ValueError(f"object {self.name} has no voxels")
        cells = [Pair(i % grid_size.x, i // grid_size.x) for i in idx]
        lo, hi = cells[0].copy(), cells[0].copy()
        for c in cells:
            lo, hi = lo.each_min(c), hi.each_max(c)
        self.pos = lo.copy()
        self.grid_size = hi - lo + Pair(1, 1)
        self.voxels = [c - self.pos for c in cells]
        local = {i: c - self.pos for i, c in zip(idx, cells, strict=True)}
        grid = np.zeros((self.grid_size.y, self.grid_size.x), dtype=int)
        self.neighbors = {v: [] for v in self.voxels}
        for i, t in zip(idx, json_data["types"], strict=True):
            v = local[i]
            grid[v.y][v.x] = t
            for nb in json_data["neighbors"][f"{i}"]:
                if nb not in local:
                    raise ValueError(f"object {self.name} has voxels with invalid neighbors")
                self.neighbors[v].append(local[nb])
        self.grid = grid

    def translate(self, dx: int, dy: int) -> None:
        """Move by (dx, dy) cells; ValueError if the position would become negative."""
        self.set_pos(self.pos.x + dx, self.pos.y + dy)

    def set_pos(self, x: int, y: int) -> None:
        """Put the bottom-left at grid cell (x, y); ValueError for a negative position."""
        new = Pair(int(x), int(y))
        if new.x < 0 or new.y < 0:
            raise ValueError(f"new pos for object {self.name}, {new}, is invalid. Pos must be "
                             "strictly non-negative")
        self.pos = new

    def get_structure(self) -> np.ndarray:
        """The structure, top row first (evogym's `structure` argument)."""
        return np.flipud(self.grid)

    def get_connections(self) -> np.ndarray:
        """(2, k) connections as flat indices into the structure, each glued pair both ways."""
        h, w = self.grid_size.y, self.grid_size.x
        out = [[(h - p.y - 1) * w + p.x, (h - n.y - 1) * w + n.x]
               for p, ns in self.neighbors.items() for n in ns]
        return np.array(out).T

    def get_pos(self) -> tuple[int, int]:
        """(x, y) grid cell of the bottom-left."""
        return (self.pos.x, self.pos.y)

    def rename(self, name: str) -> None:
        """Give the object another name."""
        self.name = name

    def get_name(self) -> str:
        """The object's name."""
        return self.name

    def copy(self) -> WorldObject:
        """A deep copy."""
        out = WorldObject()
        out.name = self.name
        out.pos = self.pos.copy()
        out.grid_size = self.grid_size.copy()
        out.voxels = [v.copy() for v in self.voxels]
        out.grid = self.grid.copy()
        out.neighbors = {v.copy(): [n.copy() for n in ns] for v, ns in self.neighbors.items()}
        return out

    __copy__ = copy

    def __str__(self) -> str:
        return f"Size {self.grid_size} object named {self.name} at {self.pos}."

    __repr__ = __str__
