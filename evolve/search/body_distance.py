"""Morphological distance of the SGR paper (eq. 2): summed over cells, 0 for the same material,
0.5 for two different non-empty materials, 1 for empty against non-empty."""

from __future__ import annotations

import numpy as np


def body_distance(a: np.ndarray, b: np.ndarray) -> float:
    """Eq. 2 distance between two bodies of the same shape (ValueError otherwise), from 0 to H * W."""
    a, b = np.asarray(a), np.asarray(b)
    if a.shape != b.shape:
        raise ValueError(f"bodies of different shapes {a.shape} and {b.shape}")
    ea, eb = a == 0, b == 0
    return float(np.sum(ea != eb) + 0.5 * np.sum(~ea & ~eb & (a != b)))
