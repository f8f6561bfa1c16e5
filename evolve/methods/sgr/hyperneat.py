"""Querying a compiled CPPN over a substrate: connection weights, node biases, dense layers.

Weight expression (HyperNEAT): |w| <= threshold -> no connection, otherwise
sign(w) (|w| - threshold) / (1 - threshold) * max_weight. Node biases are CPPN queries from the
origin (0, 0, 0), a point on neither network (all nodes have z != 0); without them the centre
body cell (x = y = 0) would always decode to all-zero outputs and hence to "empty".
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from evolve.methods.sgr.substrates import Substrate


@dataclass(frozen=True)
class Expression:
    """HyperNEAT weight expression: CPPN outputs with |w| <= threshold become 0 (no link); the rest
    keep their sign, shifted toward 0 by threshold and scaled so that |w| = 1 gives max_weight."""
    threshold: float = 0.2
    max_weight: float = 1.0

    def __call__(self, w: np.ndarray) -> np.ndarray:
        a = np.abs(w)
        out = np.sign(w) * (a - self.threshold) / (1.0 - self.threshold) * self.max_weight
        return np.where(a <= self.threshold, 0.0, out)


def queries(src: np.ndarray, dst: np.ndarray) -> np.ndarray:
    """(S*D, 7) CPPN inputs (x1, y1, z1, x2, y2, z2, bias=1) for every src -> dst pair."""
    S, D = len(src), len(dst)
    q = np.empty((S, D, 7))
    q[:, :, 0:3] = src[:, None, :]
    q[:, :, 3:6] = dst[None, :, :]
    q[:, :, 6] = 1.0
    return q.reshape(S * D, 7)


def substrate_queries(sub: Substrate) -> tuple[np.ndarray, list[tuple[int, int, tuple]]]:
    """All queries of a substrate stacked, with (start, stop, shape) slices for each weight
    matrix and bias vector, in the order W1, b1, W2, b2, ..."""
    parts, slices, start = [], [], 0
    origin = np.zeros((1, 3))
    for src, dst in zip(sub.layers[:-1], sub.layers[1:], strict=True):
        for block, shape in ((queries(src, dst), (len(src), len(dst))),
                             (queries(origin, dst), (len(dst),))):
            parts.append(block)
            slices.append((start, start + len(block), shape))
            start += len(block)
    return np.concatenate(parts), slices


def dense_layers(raw: np.ndarray, slices, expr: Expression) -> list[np.ndarray]:
    """Split one output column of the CPPN into [W1, b1, W2, b2, ...] after the expression."""
    w = expr(raw)
    return [w[a:b].reshape(shape) for a, b, shape in slices]
