"""The contract of a task: `TaskSpec` holds every fact that makes one evogym task what it is.

`BatchEnv` is task-agnostic: it places the robot at `origin` in the world file `world`, writes the
observation as the spec's blocks in order, calls the spec's `reward` with the measurements taken
before and after each step, and ends an episode at the goal, at evogym's instability rule or at
the episode length. A task of sgr's is one file in `tasks/suite/` with its `SPEC` (and its reward),
plus one line in `tasks/specs.py`'s registry; a task of yours is `tasks.register(spec)` in your own
code (docs/TASKS.md).
"""

from __future__ import annotations

import random
from collections.abc import Callable
from dataclasses import dataclass, field
from functools import cached_property

import numpy as np

from tasks.orientation import orientation
from tsim.world import World, world_from_dict


@dataclass(frozen=True)
class Measure:
    """What rewards and terminations see of the state at one instant.

    The robot's points and orientation are computed only when read. `state` is the same dict in the
    measures before and after a step: a reward may update it in place.

    Attributes:
        com: (B, 2) the robots' centres of mass.
        objects: The COMs of the objects the spec tracks (`TaskSpec.tracked`), by name.
        points: (B, N, 2) the robots' point positions, zero-padded.
        mask: (B, N) which of `points` are real.
        pos0: (B, N, 2) the robots' points at reset (the reference of `orientation`).
        state: The task's per-world state (`TaskSpec.state`).
        orientation_of: How `orientation` is computed from (points, pos0, mask):
            `tasks.orientation.orientation`, or the env's kernels that give its bits.
        kernels: Whether the env's kernel path made this measure: a reward may then compute with
            `tasks.kernels` (the same bits), and with numpy where the numpy path (the kernels'
            oracle) made it.
    """

    com: np.ndarray
    objects: dict[str, np.ndarray]
    points: np.ndarray | None = None  # (B, N, 2) robot point positions, zero-padded
    mask: np.ndarray | None = None  # (B, N) which of them are real
    pos0: np.ndarray | None = None  # (B, N, 2) the robot's points at reset (orientation reference)
    state: dict[str, np.ndarray] = field(default_factory=dict)
    # how `orientation` is computed from (points, pos0, mask): `tasks.orientation.orientation`, or
    # the env's kernels that give its bits (`BatchEnv`'s kernel path)
    orientation_of: Callable[[np.ndarray, np.ndarray, np.ndarray], np.ndarray] = orientation
    # whether the env's kernel path made it: a reward may then compute with `tasks.kernels` (the
    # same bits), and with numpy where the numpy path (the kernels' oracle) made it
    kernels: bool = False
    # what rewards derived from this measure, by name (`derived`)
    _derived: dict[str, np.ndarray] = field(default_factory=dict, repr=False, compare=False)

    @cached_property
    def orientation(self) -> np.ndarray:
        """(B,) evogym's orientation of the robot (`object_orientation_at_time`)."""
        return self.orientation_of(self.points, self.pos0, self.mask)

    def derived(self, name: str, compute: Callable[[Measure], np.ndarray]) -> np.ndarray:
        """A quantity derived from this measure, `compute(self)`, computed once per measure.

        The env passes a step's `after` as the next step's `before`, so a reward that reads a
        costly quantity of both (a hull's area) computes it once per state.

        Args:
            name: The quantity's name, under which the measure keeps it.
            compute: Computes the quantity from a measure.

        Returns:
            The quantity. Treat it as read-only: the next step reads it again.
        """
        hit = self._derived.get(name)
        if hit is None:
            hit = self._derived[name] = compute(self)
        return hit


@dataclass(frozen=True)
class Block:
    """`width` consecutive observation entries computed by `fn(scene) -> (B, width)`; width -1
    stands for 2 x the robot's point count (the relative point positions)."""

    name: str
    width: int
    fn: Callable[[object], np.ndarray]


Reward = Callable[[Measure, Measure], np.ndarray]  # (before, after) -> (B,) reward of one step
# (before, after) -> ((B,) reward added, (B,) bool episode over), e.g. -3 and over when upside down
Termination = Callable[[Measure, Measure], tuple[np.ndarray, np.ndarray]]
# one world's task state at the start of an episode, drawn from that world's random stream
StateInit = Callable[[random.Random], dict[str, np.ndarray]]
# one world's task state -> grid cell of each object placed per episode (AddedObject.per_world)
Placement = Callable[[dict[str, np.ndarray]], dict[str, tuple[int, int]]]


@dataclass(frozen=True)
class AddedObject:
    """An object evogym's task code adds to the world (not in the world file): the one object of
    `file` (in tasks/worlds/), renamed `name`, with its bounding box's bottom-left at grid cell
    `cell`. `per_world`: placed anew at every reset of each world by `TaskSpec.placement` (then
    simulated even when all its voxels are fixed)."""
    name: str
    file: str
    cell: tuple[int, int]
    per_world: bool = False


@dataclass(frozen=True)
class TaskSpec:
    """Every fact of one evogym task; one frozen instance per task.

    Each is registered in `tasks.specs.TASKS` (`tasks.register` adds yours). How `BatchEnv` uses
    them is in `tasks.spec`'s module docstring.

    Attributes:
        name: The task's id, such as "Walker-v0".
        world: A world file in tasks/worlds/ (or any path), or a `World` (`tsim.world_from_matrix`);
            a dict in the world file's layout is made a `World`.
        origin: The grid cell of the bottom-left of the robot's body matrix.
        paper_steps: The episode length used by the SGR paper (sgr's default).
        evogym_steps: evogym's registered max_episode_steps.
        observation: The observation's blocks, in order; exactly one of width -1 (the robot's
            points).
        reward: (before, after) measures -> (B,) reward of one step.
        tracked: The objects whose COM the reward needs (`Measure.objects`).
        goal: (voxel x the robot's COM must pass, bonus[, "left"]); ends the episode. Passing
            means going right of x, or left of it with "left".
        termination: Further task ends (after the goal): (before, after) -> ((B,) reward added,
            (B,) bool episode over), e.g. -3 and over when upside down.
        state: Draws one world's task state, anew at each reset of that world, from that world's
            random stream.
        objects: The objects added in code, in the order evogym adds them.
        placement: The cells of the per_world objects from a world's task state.
        reads_points: Whether reward or termination read the robot's points (`Measure.points`,
            `.orientation`): False spares `BatchEnv` copying them twice a step (a measure's
            points are then None).

    Raises:
        ValueError: When `goal` is malformed, or a per_world object has no `placement` (or a
            `placement` no per_world object to place).
    """
    name: str
    world: str | World  # a world file in tasks/worlds/ (or any path), or a World (tsim.world_from_matrix)
    origin: tuple[int, int]  # grid cell of the bottom-left of the robot's body matrix
    paper_steps: int  # episode length used by the SGR paper (our default)
    evogym_steps: int  # evogym's registered max_episode_steps
    observation: tuple[Block, ...]  # in order; exactly one block of width -1 (the robot's points)
    reward: Reward
    tracked: tuple[str, ...] = ()  # objects whose COM the reward needs (Measure.objects)
    # (voxel x the robot's COM must pass, bonus[, "left"]); ends the episode. Passing means going
    # right of x, or left of it with "left"
    goal: tuple[int, float] | tuple[int, float, str] | None = None
    termination: Termination | None = None  # further task ends (after the goal); see `Termination`
    state: StateInit | None = None  # per-world task state, drawn anew at each reset of that world
    objects: tuple[AddedObject, ...] = ()  # objects added in code, in the order evogym adds them
    placement: Placement | None = None  # cells of the per_world objects from a world's state
    # whether reward or termination read the robot's points (`Measure.points`, `.orientation`):
    # False spares `BatchEnv` copying them twice a step (a measure's points are then None)
    reads_points: bool = True

    def episode_length(self, steps: int | str | None) -> int:
        """The episode length that `steps` stands for (the one place these are resolved).

        Args:
            steps: None for the paper's length, "evogym" for evogym's, or an int, which stands for
                itself.
        """
        return self.paper_steps if steps is None else self.evogym_steps if steps == "evogym" else steps

    def __post_init__(self) -> None:
        """A per_world object with no placement function (or a placement with no per_world object
        to place) would otherwise fail only at the first reset, far from the spec: fail here, at
        registration, naming the task and the object."""
        if isinstance(self.world, dict):  # a world given in the world file's layout
            object.__setattr__(self, "world", world_from_dict(self.world, self.name))
        if self.goal is not None and (len(self.goal) not in (2, 3)
                                      or len(self.goal) == 3 and self.goal[2] not in ("left", "right")):
            raise ValueError(f"task {self.name}: goal must be (voxel x, bonus) or (voxel x, bonus, "
                             f"'left' or 'right'), got {self.goal!r}")
        per_world = [o.name for o in self.objects if o.per_world]
        if per_world and self.placement is None:
            raise ValueError(f"task {self.name}: per_world object {per_world[0]!r} has no placement "
                             "(TaskSpec.placement is None)")
        if self.placement is not None and not per_world:
            raise ValueError(f"task {self.name}: placement given but no object is per_world")

    def check_placement(self, cells: dict[str, tuple[int, int]]) -> None:
        """Check that `cells`, what `placement` returned, places exactly the per_world objects.

        A name outside them would move a shared object or none at all, and a per_world object left
        out would silently keep the last episode's cell.

        Args:
            cells: The grid cell of each object, by name.

        Raises:
            ValueError: One line naming the task and the object, unless `cells` names exactly
                the per_world objects.
        """
        per_world = [o.name for o in self.objects if o.per_world]
        for name in cells:
            if name not in per_world:
                raise ValueError(f"task {self.name}: placement names {name!r}, which is not a "
                                 f"per_world object (per_world objects: {', '.join(per_world)})")
        for name in per_world:
            if name not in cells:
                raise ValueError(f"task {self.name}: per_world object {name!r} has no placement "
                                 "(missing from what TaskSpec.placement returned)")

    def obs_dim(self, n_points: int) -> int:
        """evogym's observation length for a robot of n points."""
        return sum(2 * n_points if b.width < 0 else b.width for b in self.observation)

    def head_width(self) -> int:
        """Entries before the robot's relative points (the same for every robot of a batch)."""
        w = 0
        for b in self.observation:
            if b.width < 0:
                return w
            w += b.width
        raise ValueError(f"task {self.name}: the observation has no block of the robot's points")
