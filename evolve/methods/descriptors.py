"""Descriptors for quality diversity (the map-elites method): what places a robot in the archive.

A descriptor is a name, a function of the decoded body giving a float, and its default range and
number of cells for a body grid of a given shape. They are pluggable like tasks: `register` adds
one (a config's `imports:` module may call it), and a config's `qd.descriptors` names them.

The built-in ones are body measures (evolve/methods/body_measures.py), read inside the body's
bounding box. Behaviour descriptors (a Walker's mean height, its gait frequency) would need what
the rollout returns beyond the episode return, which the batched rollouts do not keep: none yet.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from evolve.methods import body_measures

Shape = tuple[int, int]


@dataclass(frozen=True)
class Descriptor:
    """One descriptor: `fn(body) -> float`, and for a body grid of `shape` its default range
    (`range_of(shape)`) and number of cells (`cells_of(shape)`)."""
    name: str
    fn: Callable[[np.ndarray], float]
    range_of: Callable[[Shape], tuple[float, float]]
    cells_of: Callable[[Shape], int]
    doc: str = ""


DESCRIPTORS: dict[str, Descriptor] = {}


def register(name: str, fn: Callable[[np.ndarray], float], range_of: Callable[[Shape], tuple[float, float]],
             cells_of: Callable[[Shape], int] = lambda shape: 10, doc: str = "") -> Descriptor:
    """Make `name` a descriptor a config's `qd.descriptors` may name (a name registered again is
    replaced)."""
    d = Descriptor(name, fn, range_of, cells_of, doc)
    DESCRIPTORS[name] = d
    return d


def _measure(key: str) -> Callable[[np.ndarray], float]:
    def fn(body: np.ndarray) -> float:
        return float(body_measures.measures(body)[key])
    fn.__name__ = key
    return fn


def _share(shape: Shape) -> tuple[float, float]:
    return 0.0, 1.0


for _name, _doc in (("actuator", "share of the voxels that are actuators (both kinds)"),
                    ("rigid", "share of the voxels that are rigid"),
                    ("soft", "share of the voxels that are soft"),
                    ("fill", "voxels / cells of the bounding box"),
                    ("symmetry_lr", "left-right symmetry of the bounding box, 0 to 1"),
                    ("symmetry_tb", "top-bottom symmetry of the bounding box, 0 to 1")):
    register(_name, _measure(_name), _share, doc=_doc)
# integers 1..W (1..H): one cell per value
register("width", _measure("width"), lambda shape: (0.5, shape[1] + 0.5), lambda shape: shape[1],
         "columns of the bounding box")
register("height", _measure("height"), lambda shape: (0.5, shape[0] + 0.5), lambda shape: shape[0],
         "rows of the bounding box")
# zlib bytes beyond a uniform grid's: random 5x5 bodies reach ~19, random 10x10 ones ~48
register("irregularity", _measure("irregularity"), lambda shape: (0.0, 0.8 * shape[0] * shape[1]),
         doc="zlib size of the material grid beyond a uniform grid's, in bytes")
