"""Descriptors for quality diversity (the map-elites method): what places a robot in the archive.

A descriptor is a name, a function of the decoded body giving a float, and its default range and
number of cells for a body grid of a given shape. They are pluggable like tasks: `register` adds
one (a config's `imports:` module may call it), and a config's `qd.descriptors` names them.

Two kinds: body descriptors are functions of the decoded body (evolve/methods/body_measures.py,
read inside the body's bounding box); behaviour descriptors are functions of what the robot did,
the behaviour features the batched rollout records (tasks/behaviour.py: displacement, height,
gait frequency, ground contact, orientation), each the mean over the robot's scored episodes.
Every feature is a behaviour descriptor of its own name; `register_behaviour` adds others made
from them.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass

import numpy as np

from evolve.methods import body_measures
from tasks.behaviour import FEATURES

Shape = tuple[int, int]


@dataclass(frozen=True)
class Descriptor:
    """One descriptor: `fn(body) -> float` (kind "body") or `fn(features) -> float` (kind
    "behaviour": `features` maps each name of tasks.behaviour.FEATURES to its value), and for a
    body grid of `shape` its default range (`range_of(shape)`) and number of cells
    (`cells_of(shape)`)."""
    name: str
    fn: Callable
    range_of: Callable[[Shape], tuple[float, float]]
    cells_of: Callable[[Shape], int]
    doc: str = ""
    kind: str = "body"


DESCRIPTORS: dict[str, Descriptor] = {}


def register(name: str, fn: Callable[[np.ndarray], float], range_of: Callable[[Shape], tuple[float, float]],
             cells_of: Callable[[Shape], int] = lambda shape: 10, doc: str = "") -> Descriptor:
    """Make `name` a descriptor a config's `qd.descriptors` may name (a name registered again is
    replaced)."""
    d = Descriptor(name, fn, range_of, cells_of, doc)
    DESCRIPTORS[name] = d
    return d


def register_behaviour(name: str, fn: Callable[[Mapping[str, float]], float], low: float, high: float,
                       cells: int = 10, doc: str = "") -> Descriptor:
    """Make `name` a behaviour descriptor: `fn` of the robot's behaviour features (a mapping of
    tasks.behaviour.FEATURES' names to the mean over its scored episodes) on [low, high] in
    `cells` cells (a name registered again is replaced)."""
    d = Descriptor(name, fn, lambda shape: (low, high), lambda shape: cells, doc, kind="behaviour")
    DESCRIPTORS[name] = d
    return d


def measure(names: Sequence[str], body: np.ndarray, features: np.ndarray | None) -> np.ndarray:
    """The descriptors `names` of a (valid) body whose behaviour features (in FEATURES' order) are
    `features` (None: the body's descriptors only are asked for)."""
    got = None if features is None else dict(zip(FEATURES, map(float, features), strict=True))
    out = []
    for n in names:
        d = DESCRIPTORS[n]
        if d.kind == "behaviour":
            if got is None:
                raise ValueError(f"descriptor {n!r} describes behaviour: it needs the episode's features")
            out.append(float(d.fn(got)))
        else:
            out.append(float(d.fn(body)))
    return np.array(out, dtype=np.float64)


def needs_behaviour(names: Sequence[str]) -> bool:
    """Whether any of the descriptors `names` describes behaviour (the rollout must record it)."""
    return any(DESCRIPTORS[n].kind == "behaviour" for n in names)


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


def _feature(key: str) -> Callable[[Mapping[str, float]], float]:
    def fn(features: Mapping[str, float]) -> float:
        return features[key]
    fn.__name__ = key
    return fn


# the recorded features (tasks/behaviour.py), each on a range wide enough for most tasks' episodes;
# a study narrows them per task with qd.ranges
for _name, (_low, _high), _doc in (
        ("dx", (-20.0, 80.0), "the COM's net x displacement over the episode, voxels"),
        ("dy", (-10.0, 40.0), "the COM's net y displacement over the episode, voxels"),
        ("height_mean", (-2.0, 8.0), "the COM's mean height above its start, voxels"),
        ("height_max", (-2.0, 12.0), "the COM's highest point above its start, voxels"),
        ("gait_frequency", (0.0, 10.0), "the dominant frequency of the actuation, Hz of simulated time"),
        ("contact", (0.0, 1.0), "the share of steps with the body touching the terrain's top"),
        ("orientation", (-3.1416, 3.1416), "the body's orientation at the end, radians")):
    register_behaviour(_name, _feature(_name), _low, _high, doc=_doc)
