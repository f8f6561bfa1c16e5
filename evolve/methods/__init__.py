"""Methods behind one contract (`Problem`, evolve/methods/base.py) and their registry: a method is
one file and one line here."""

from __future__ import annotations

from evolve.methods.base import Problem
from evolve.methods.direct import DirectProblem
from evolve.methods.ga_ppo import GaPpoProblem
from evolve.methods.map_elites import MapElitesProblem
from evolve.methods.nested import NestedProblem
from evolve.methods.sgr import SgrProblem
from tsim.errors import SgrError

METHODS: dict[str, type[Problem]] = {p.name: p for p in (
    SgrProblem,
    DirectProblem,
    NestedProblem,
    MapElitesProblem,
    GaPpoProblem,
)}


def method(name: str) -> type[Problem]:
    """The Problem class registered as `name` (a config's `method`); ValueError listing the known
    ones."""
    try:
        return METHODS[name]
    except KeyError:
        raise SgrError(f"unknown method {name!r}; known methods: {', '.join(METHODS)}") from None


__all__ = ["METHODS", "DirectProblem", "GaPpoProblem", "MapElitesProblem", "NestedProblem", "Problem",
           "SgrProblem", "method"]
