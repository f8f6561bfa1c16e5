"""How a champion file's controller is read back, by its format tag: a registry the methods fill.

Each method module registers the controller formats it writes (`register`: the tag and a reader
taking the whole champion record, since a controller may be recorded as a function of the
record's genome), so adding a method, or a format, is one module: nothing here names one.
`controller_of` reads any registered format. A method's way of rewriting an older record in its
shortest exact format is its Problem's `compact_controller` (evolve/runs/migrate.py uses it).

The tags today: sgr-dense-controller-1 (SGR's dense layers in full; also an older sgr's untagged
ones), sgr-hyperneat-controller-1 (SGR's, as its genome's decoding: evolve/methods/sgr/record.py),
sgr-graph-controller-1 (direct's and nested's NEAT networks in full) and
sgr-genome-graph-controller-1 (direct's, as its genome compiled: evolve/nn/graph.py)."""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

# format tag (None: a controller without one) -> reader of the champion record
READERS: dict[str | None, Callable[[dict], Any]] = {}


def register(tag: str | None, read: Callable[[dict], Any]) -> None:
    """Read controllers tagged `tag` (None: untagged) with `read(champion record)`. Two methods may
    share a format (direct and nested: the graph) when they read it alike; ValueError when a tag
    is registered again with another reader."""
    if tag in READERS and READERS[tag] != read:
        raise ValueError(f"controller format {tag!r} is registered already, with another reader")
    READERS[tag] = read


def controller_of(champ: dict):
    """The controller of a champion record, whatever its (registered) format: in full, or as a
    function of the record's genome, rebuilt and checked against its digest. KeyError, TypeError
    or ValueError when it is none of these."""
    c = champ["controller"]
    fmt = c.get("format") if isinstance(c, dict) else None
    if fmt not in READERS:
        known = ", ".join(sorted(t for t in READERS if t is not None))
        raise ValueError(f"unknown controller format {fmt!r}; known formats: {known}")
    return READERS[fmt](champ)
