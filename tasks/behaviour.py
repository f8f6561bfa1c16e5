"""What a robot did in an episode, measured while the batch runs: behaviour features.

`BehaviourRecorder` watches a `BatchEnv` step by step (one call per env step, batched over every
world, no loop over robots) and gives each world's features at the end (`FEATURES`, in order):

- `dx`, `dy`: the centre of mass's net displacement from the start to the last step, in voxels;
- `height_mean`, `height_max`: the COM's height above its start, mean and max over the steps, in
  voxels;
- `gait_frequency`: the dominant frequency of the actuation, in Hz of simulated time (an env step
  is `STEP_SECONDS`): the peak of the actuators' summed power spectrum, mean removed; 0 when the
  actuation does not change;
- `contact`: the share of steps with a robot point touching the top of the static terrain (within
  `CONTACT_TOL` of a terrain top in the point's column);
- `orientation`: the body's orientation at the last step (evogym's estimate, counter-clockwise),
  in radians within (-pi, pi] (with evogym's pi, 3.1415926).

A world that terminates is measured up to its last step; a step on which it went unstable is not
measured. The recorder reads the state the env already holds (no extra simulation) and is built
only when asked for, so episodes without it run exactly as before.
"""

from __future__ import annotations

import numpy as np

from tasks import observations as O
from tasks.orientation import PI_EVOGYM, orientation
from tsim import constants as C

FEATURES = ("dx", "dy", "height_mean", "height_max", "gait_frequency", "contact", "orientation")
STEP_SECONDS = C.DT * C.SUBSTEPS  # simulated time of one env step: 3 ms
CONTACT_TOL = 0.1 * C.CELL  # a point this close to a terrain top touches it (world units)
_QUIET = 1e-12  # summed spectral power (action units squared) below which the actuation is still


def terrain_tops(points: np.ndarray) -> tuple[int, np.ndarray]:
    """The static terrain's tops as a lookup table: (first column, table (columns, rows + 2)) where
    table[c, r] is the highest top row <= r in column c, -1 where none. `points` (2, M) are the
    terrain's lattice points; a top is a terrain point with no terrain point right above it."""
    if points.shape[1] == 0:
        return 0, np.full((1, 2), -1, dtype=np.int64)
    cols = np.rint(points[0] / C.CELL).astype(np.int64)
    rows = np.rint(points[1] / C.CELL).astype(np.int64)
    c0, r_hi = int(cols.min()), int(max(rows.max(), 0))
    occupied = np.zeros((int(cols.max()) - c0 + 1, r_hi + 2), dtype=bool)
    keep = rows >= 0
    occupied[cols[keep] - c0, rows[keep]] = True
    top = occupied & ~np.roll(occupied, -1, axis=1)  # (the last row is never occupied)
    rank = np.where(top, np.arange(occupied.shape[1])[None, :], -1)
    return c0, np.maximum.accumulate(rank, axis=1)


class BehaviourRecorder:
    """Behaviour features of every world of `env` over one episode: call `step(actions, active)`
    after each env step, then `features()`.

    Args:
        env: the `BatchEnv`, just reset (its state is the episode's start).
    """

    def __init__(self, env) -> None:
        self.env = env
        sim = env.sim
        self._n = sim.max_robot_points
        self._mask = np.arange(self._n)[None, :] < env.n_points[:, None]
        self._act_mask = np.arange(sim.max_actuators)[None, :] < env.n_actuators[:, None]
        fixed = sim.world.fixed_objects
        terrain = np.concatenate([o.pos0 for o in fixed], axis=1) if fixed else np.zeros((2, 0))
        self._c0, self._tops = terrain_tops(np.asarray(terrain, dtype=np.float64))
        pos = self._points()
        self._pos0 = pos.copy()
        self._com0 = O.com(pos, self._mask)
        B = env.n_worlds
        self._com_last = self._com0.copy()
        self._height_sum = np.zeros(B)
        self._height_max = np.full(B, -np.inf)
        self._contacts = np.zeros(B)
        self._steps = np.zeros(B, dtype=np.int64)
        self._pos_last = pos.copy()
        self._actions: list[np.ndarray] = []

    def _points(self) -> np.ndarray:
        """(B, N, 2) the robots' point positions now, float64, zero on padding."""
        pos = np.asarray(self.env.sim.read_state()[:, :self._n, 0:2], dtype=np.float64)
        return pos * self._mask[:, :, None]

    def _touching(self, pos: np.ndarray) -> np.ndarray:
        """(B,) whether any robot point touches a terrain top (`CONTACT_TOL`)."""
        tops = self._tops
        col = np.rint(pos[..., 0] / C.CELL).astype(np.int64) - self._c0
        row = np.floor((pos[..., 1] + CONTACT_TOL) / C.CELL).astype(np.int64)
        inside = (col >= 0) & (col < tops.shape[0]) & (row >= 0)
        top = tops[np.clip(col, 0, tops.shape[0] - 1), np.clip(row, 0, tops.shape[1] - 1)]
        gap = pos[..., 1] - top * C.CELL
        hit = inside & (top >= 0) & (gap < CONTACT_TOL) & self._mask
        return hit.any(axis=1)

    def step(self, actions: np.ndarray, active: np.ndarray) -> None:
        """Measure the state after one env step.

        Args:
            actions: (B, max_actuators) the policy's actions of this step (before any noise).
            active: (B,) the worlds this step moved and left stable (running before it, and not
                unstable after it).
        """
        pos = self._points()
        com = O.com(pos, self._mask)
        ok = active & np.isfinite(com).all(axis=1)
        h = (com[:, 1] - self._com0[:, 1]) / C.CELL
        self._height_sum += np.where(ok, h, 0.0)
        self._height_max = np.where(ok, np.maximum(self._height_max, h), self._height_max)
        self._contacts += ok & self._touching(pos)
        self._steps += ok
        self._com_last = np.where(ok[:, None], com, self._com_last)
        self._pos_last = np.where(ok[:, None, None], pos, self._pos_last)
        act = np.clip(np.asarray(actions, dtype=np.float64), C.ACTION_MIN, C.ACTION_MAX)
        self._actions.append(np.where(self._act_mask, act, 0.0))

    def features(self) -> np.ndarray:
        """(B, len(FEATURES)) each world's features (a world never measured: its start's, zeros)."""
        steps = np.maximum(self._steps, 1)
        d = (self._com_last - self._com0) / C.CELL
        height_max = np.where(self._steps > 0, self._height_max, 0.0)
        angle = orientation(self._pos_last, self._pos0, self._mask)
        angle = np.where(angle > PI_EVOGYM, angle - 2 * PI_EVOGYM, angle)  # evogym's [0, 2 pi) as signed
        return np.stack([d[:, 0], d[:, 1], self._height_sum / steps, height_max, self._gait(),
                         self._contacts / steps, angle], axis=1)

    def _gait(self) -> np.ndarray:
        """(B,) the dominant actuation frequency over each world's measured steps (Hz)."""
        B = self.env.n_worlds
        out = np.zeros(B)
        if not self._actions:
            return out
        acts = np.stack(self._actions)  # (T, B, A), zero on padding
        for n in np.unique(self._steps):  # worlds measured for n steps (a batch has few lengths)
            if n < 3:
                continue
            rows = np.nonzero(self._steps == n)[0]
            x = acts[:n, rows]  # a world's measured steps are the episode's first ones
            x = x - x.mean(axis=0, keepdims=True)
            power = (np.abs(np.fft.rfft(x, axis=0)) ** 2).sum(axis=2)  # (F, len(rows))
            k = 1 + np.argmax(power[1:], axis=0)
            still = power[1:].max(axis=0) <= _QUIET
            out[rows] = np.where(still, 0.0, k / (n * STEP_SECONDS))
        return out
