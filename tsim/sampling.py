"""Random robot bodies with evogym's default distribution (`sample_robot`), seeded with numpy."""

from __future__ import annotations

import numpy as np

from tsim.body import has_actuator, is_connected

DEFAULT_PD = (0.6, 0.2, 0.2, 0.2, 0.2)  # empty, rigid, soft, H, V (normalised: 3/7, 1/7 x 4)


def sample_robot(shape: tuple[int, int], rng: np.random.Generator,
                 pd: tuple[float, ...] = DEFAULT_PD, max_tries: int = 100_000) -> np.ndarray:
    """Draw cells independently from `pd`, redrawing the whole matrix until it is connected and
    has an actuator (evogym's rejection sampling)."""
    p = np.asarray(pd, dtype=float)
    if p.shape != (5,) or np.any(p < 0) or p[1:].sum() <= 0 or p[3:].sum() <= 0:
        raise ValueError(f"bad voxel distribution {pd}: need 5 non-negative weights with non-zero "
                         "non-empty and actuator mass")
    p = p / p.sum()
    for _ in range(max_tries):
        m = rng.choice(5, size=shape, p=p)
        if is_connected(m) and has_actuator(m):
            return m.astype(np.int64)
    raise RuntimeError(f"no valid robot found in {max_tries} draws")
