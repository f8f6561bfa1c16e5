"""Methods behind one contract (`Problem`, evolve/methods/base.py) and their registry: a method is
one file and one registration, a line here for sgr's own, `register(MyProblem)` in a module of
your own that a config's `imports:` names (docs/EVOLVE.md "Adding a method")."""

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
BUILTIN = frozenset(METHODS)  # sgr's own


def register(problem: type[Problem]) -> type[Problem]:
    """Make `problem` the method of configs whose `method` is its `name` (usable as a class
    decorator); a name registered again by a module of the user's is replaced.

    Raises:
        SgrError: when it is not a named Problem subclass, or the name is one of sgr's own methods.
    """
    name = getattr(problem, "name", None)
    if not (isinstance(problem, type) and issubclass(problem, Problem) and isinstance(name, str) and name):
        raise SgrError(f"register: a method is a Problem subclass with a name, got {problem!r}")
    if name in BUILTIN and METHODS[name] is not problem:
        raise SgrError(f"register: {name!r} is one of sgr's own methods; give yours another name")
    METHODS[name] = problem
    return problem


def method(name: str) -> type[Problem]:
    """The Problem class registered as `name` (a config's `method`); ValueError listing the known
    ones."""
    try:
        return METHODS[name]
    except KeyError:
        raise SgrError(f"unknown method {name!r}; known methods: {', '.join(METHODS)}") from None


__all__ = ["METHODS", "DirectProblem", "GaPpoProblem", "MapElitesProblem", "NestedProblem", "Problem",
           "SgrProblem", "method", "register"]
