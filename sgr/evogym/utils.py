"""evogym 2.0's `evogym.utils` on sgr: voxel codes, the 32 baseline ids, random robots and the
robot checks, with evogym's semantics.

`draw` and `sample_robot` consume Python's global `random` exactly as evogym does (one
`random.uniform(0, 1)` per cell, row by row, compared with the running sum of the normalised
distribution), so `random.seed(s)` followed by `sample_robot(shape)` gives evogym's robot for that
seed. (`tsim.sample_robot` is sgr's own sampler from an explicit numpy Generator.)
"""

from __future__ import annotations

import random
import time

import numpy as np

from tsim.body import has_actuator as _has_actuator
from tsim.body import is_connected as _is_connected

__all__ = ["BASELINE_ENV_NAMES", "VOXEL_TYPES", "Pair", "Timer", "draw", "get_full_connectivity",
           "get_uniform", "has_actuator", "hashable", "is_connected", "sample_robot"]

VOXEL_TYPES = {"EMPTY": 0, "RIGID": 1, "SOFT": 2, "H_ACT": 3, "V_ACT": 4, "FIXED": 5}

# evogym's list, in evogym's order (tests and scripts iterate over it)
BASELINE_ENV_NAMES = [
    "Walker-v0", "BridgeWalker-v0", "BidirectionalWalker-v0", "Carrier-v0", "Carrier-v1",
    "Pusher-v0", "Pusher-v1", "Thrower-v0", "Catcher-v0", "BeamToppler-v0", "BeamSlider-v0",
    "Lifter-v0", "Climber-v0", "Climber-v1", "Climber-v2", "UpStepper-v0", "DownStepper-v0",
    "ObstacleTraverser-v0", "ObstacleTraverser-v1", "Hurdler-v0", "PlatformJumper-v0",
    "GapJumper-v0", "Traverser-v0", "CaveCrawler-v0", "AreaMaximizer-v0", "AreaMinimizer-v0",
    "WingspanMazimizer-v0", "HeightMaximizer-v0", "Flipper-v0", "Jumper-v0", "Balancer-v0",
    "Balancer-v1",
]

# evogym's default cell weights when no distribution is given (normalised by `draw`)
_DEFAULT_PD = (0.6, 0.2, 0.2, 0.2, 0.2)


def get_uniform(x: int) -> np.ndarray:
    """(x,) uniform distribution; ValueError unless x > 0."""
    if not x > 0:
        raise ValueError(f"invalid size {x} for a uniform distribution: must be positive")
    return np.ones(x) / x


def draw(pd) -> int:
    """An index drawn from the relative weights `pd` with one `random.uniform(0, 1)`.

    It is the first index whose running sum of normalised weights reaches the draw, added in
    evogym's order, so the same global random state gives evogym's index.

    Raises:
        ValueError: `pd` is empty, negative or all zero.
    """
    p = np.array(pd, dtype=float).reshape(-1)
    if p.size == 0:
        raise ValueError("invalid probability distribution: it has no entries")
    if np.any(p < 0):
        raise ValueError(f"invalid probability distribution {p}: entries must be non-negative")
    if not np.sum(p) > 0:
        raise ValueError(f"invalid probability distribution {p}: entries must sum to more than 0")
    p = p / p.sum()
    u = random.uniform(0, 1)
    running = 0
    for i in range(p.size):
        running += p[i]
        if u <= running:
            return i
    # the normalised sum rounded below the draw (evogym returns None here): the last non-zero
    return int(np.nonzero(p)[0][-1])


def sample_robot(robot_shape: tuple[int, int], pd: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
    """A random valid robot and its full connectivity, drawn from Python's global `random`.

    Cells are drawn row by row with `draw` until the matrix is connected and has an actuator.

    Args:
        robot_shape: The body's (height, width).
        pd: (5,) weights of empty, rigid, soft, H_ACT, V_ACT; None: 0.6 for empty and 0.2 for each
            other.

    Returns:
        The body, a float array as evogym's, and its connections (`get_full_connectivity`).

    Raises:
        ValueError: `pd` is not (5,), gives actuators no chance, or gives non-empty voxels none.
    """
    if pd is not None:
        pd = np.asarray(pd, dtype=float)
        if pd.shape != (5,):
            raise ValueError(f"invalid probability distribution {pd}: must have shape (5,)")
        if pd[VOXEL_TYPES["H_ACT"]] + pd[VOXEL_TYPES["V_ACT"]] == 0:
            raise ValueError(f"invalid probability distribution {pd}: an actuator must have a "
                             "non-zero probability")
        if sum(pd) - pd[VOXEL_TYPES["EMPTY"]] == 0:
            raise ValueError(f"invalid probability distribution {pd}: a non-empty voxel must have a "
                             "non-zero probability")
    else:
        pd = np.array(_DEFAULT_PD)
    h, w = robot_shape
    while True:
        robot = np.zeros((h, w))
        for i in range(h):
            for j in range(w):
                robot[i][j] = draw(pd)
        if is_connected(robot) and has_actuator(robot):
            return robot, get_full_connectivity(robot)


def is_connected(robot: np.ndarray) -> bool:
    """True when the non-empty voxels form one 4-connected piece (an all-empty robot is not)."""
    return _is_connected(np.asarray(robot))


def has_actuator(robot: np.ndarray) -> bool:
    """True when some voxel is an actuator (H_ACT or V_ACT)."""
    return _has_actuator(np.asarray(robot))


def get_full_connectivity(robot: np.ndarray) -> np.ndarray:
    """(2, k) connections of every pair of 4-adjacent non-empty voxels, flat indices into `robot.flatten()`.

    Pairs go cell by cell in row-major order, each cell's right then its lower neighbour. An int
    array; (2, 0) floats when there is none, as evogym's.
    """
    m = np.asarray(robot)
    h, w = m.shape
    pairs = []
    for i in range(m.size):
        r, c = divmod(i, w)
        if m[r][c] == 0:
            continue
        if c + 1 < w and m[r][c + 1] != 0:
            pairs.append([i, i + 1])
        if r + 1 < h and m[r + 1][c] != 0:
            pairs.append([i, i + w])
    if not pairs:
        return np.empty((0, 2)).T
    return np.array(pairs).T


def hashable(robot: np.ndarray) -> str:
    """The robot's voxel codes as one string, row by row (a key for sets and dicts)."""
    return "".join(str(int(v)) for v in np.asarray(robot).reshape(-1))


class Timer:
    """Paces a loop at a target number of steps per second, as evogym's viewer does for its target rps.

    Args:
        target_step_frequency: Steps per second; None: never waits.
    """

    def __init__(self, target_step_frequency: int | None = None) -> None:
        self._target_rps = float("inf") if target_step_frequency is None else target_step_frequency
        self._total_steps = 0
        self.total_count = 0
        self._steps = 0
        self._old_time = self._current_time()

    def _current_time(self) -> int:
        return int(round(time.time() * 1000))

    def should_step(self) -> bool:
        """True while fewer steps than the target were taken in the current second."""
        elapsed = self._current_time() - self._old_time
        return not self._steps >= (self._target_rps - 1) * elapsed / 1000

    def step(self, verbose: bool = False) -> None:
        """Count one step; each full second, optionally print the rate and the mean rate."""
        self._steps += 1
        if self._current_time() - self._old_time > 1000:
            self._total_steps += self._steps
            self.total_count += 1
            self._old_time += 1000
            if verbose:
                mean = round(self._total_steps / self.total_count * 100.0) / 100.0
                print(f"rps: {self._steps} | avg rps: {mean}")
            self._steps = 0


class Pair:
    """Two ints with element-wise arithmetic (a scalar int applies to both); division floors."""

    def __init__(self, x: int, y: int):
        for v in (x, y):
            if not isinstance(v, int):
                raise TypeError(f"{v} is not instance of int")
        self.x = x
        self.y = y

    def __getitem__(self, key: int) -> int:
        if key not in (0, 1):
            raise IndexError("Pair can only be indexed with values 0 or 1")
        return self.x if key == 0 else self.y

    def _other(self, b, what: str) -> tuple[int, int]:
        if isinstance(b, int):
            return b, b
        if isinstance(b, Pair):
            return b.x, b.y
        raise TypeError(f"cannot {what} Pair and {type(b)}")

    def __add__(self, b) -> Pair:
        bx, by = self._other(b, "add")
        return Pair(self.x + bx, self.y + by)

    def __sub__(self, b) -> Pair:
        bx, by = self._other(b, "subtract")
        return Pair(self.x - bx, self.y - by)

    def __mul__(self, b) -> Pair:
        bx, by = self._other(b, "multiply")
        return Pair(self.x * bx, self.y * by)

    def __floordiv__(self, b) -> Pair:
        bx, by = self._other(b, "divide")
        return Pair(self.x // bx, self.y // by)

    __truediv__ = __floordiv__

    def __mod__(self, b) -> Pair:
        bx, by = self._other(b, "compute mod of")
        return Pair(self.x % bx, self.y % by)

    def __eq__(self, b) -> bool:
        if isinstance(b, int):
            return self.x == b and self.y == b
        if isinstance(b, Pair):
            return self.x == b.x and self.y == b.y
        return False

    def __hash__(self) -> int:
        return hash(repr(self))

    def abs(self) -> Pair:
        """Element-wise absolute value."""
        return Pair(abs(self.x), abs(self.y))

    def each_max(self, b: Pair) -> Pair:
        """Element-wise maximum with another Pair."""
        if not isinstance(b, Pair):
            raise TypeError(f"cannot compute element-wise max of Pair and {type(b)}")
        return Pair(max(self.x, b.x), max(self.y, b.y))

    def each_min(self, b: Pair) -> Pair:
        """Element-wise minimum with another Pair."""
        if not isinstance(b, Pair):
            raise TypeError(f"cannot compute element-wise min of Pair and {type(b)}")
        return Pair(min(self.x, b.x), min(self.y, b.y))

    def copy(self) -> Pair:
        """A new Pair with the same values."""
        return Pair(self.x, self.y)

    __copy__ = copy

    def __str__(self) -> str:
        return f"({self.x}, {self.y})"

    def __repr__(self) -> str:
        return f"Pair{self}"
