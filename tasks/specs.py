"""The task registry: every task's spec by its evogym id, and its world. sgr's own tasks are listed
here; `tasks.register` (tasks/registry.py) adds yours."""

from __future__ import annotations

import difflib
from functools import cache
from importlib import resources
from pathlib import Path

import numpy as np

from tasks.spec import TaskSpec
from tasks.suite import (
    balancer,
    bidirectional_walker,
    carry_push,
    catcher,
    climber,
    climber_v0,
    flipper,
    jumper,
    jumpers,
    mixed_terrain,
    obstacle_traverser,
    rigid_objects,
    shape,
    steppers,
    thrower,
    traverser,
    walker,
)
from tsim.errors import SgrError
from tsim.world import World, add_world_finder, load_object, load_world

# the most env steps of one episode a command line, a config or a record may ask for: more is a typo
MAX_STEPS = 1_000_000

TASKS: dict[str, TaskSpec] = {s.name: s for s in (
    walker.SPEC,
    obstacle_traverser.SPEC,
    climber.SPEC,
    thrower.SPEC,
    jumper.SPEC,
    flipper.SPEC,
    balancer.SPEC_V0,
    balancer.SPEC_V1,
    steppers.UP,
    steppers.DOWN,
    steppers.OBSTACLE_V0,
    steppers.HURDLER,
    jumpers.GAP,
    jumpers.PLATFORM,
    carry_push.CARRIER,
    carry_push.PUSHER,
    shape.AREA_MAX,
    shape.AREA_MIN,
    shape.WINGSPAN,
    shape.HEIGHT,
    climber_v0.SPEC,
    bidirectional_walker.SPEC,
    rigid_objects.LIFTER,
    rigid_objects.CARRIER_V1,
    rigid_objects.PUSHER_V1,
    rigid_objects.BEAM_TOPPLER,
    rigid_objects.BEAM_SLIDER,
    mixed_terrain.BRIDGE_WALKER,
    mixed_terrain.CAVE_CRAWLER,
    mixed_terrain.CLIMBER_V1,
    traverser.SPEC,
    catcher.SPEC,
)}


BUILTIN = frozenset(TASKS)  # sgr's own tasks; the others were added by tasks.register


def closest(name: object, known) -> str:
    """ "; did you mean X or Y?" for the known names closest to a misspelt one, else ""."""
    near = difflib.get_close_matches(str(name), list(known), n=2, cutoff=0.6)
    return f"; did you mean {' or '.join(near)}?" if near else ""


def unknown_name(what: str, name: object, known) -> str:
    """One line for a name that is not known: the closest known names, then all of them."""
    hint = closest(name, known)
    return f"unknown {what} {name!r}{hint}{' Known' if hint else '; known'} {what}s: {', '.join(known)}"


def unknown_task(name: object) -> str:
    """One line for a task name that is not registered: the closest names, then every name."""
    return unknown_name("task", name, TASKS)


def task_spec(name: str) -> TaskSpec:
    """The spec of a task id such as Walker-v0; ValueError naming the closest ids otherwise."""
    try:
        return TASKS[name]
    except (KeyError, TypeError):
        raise SgrError(unknown_task(name)) from None


@cache
def task_world(name: str) -> World:
    """The task's world: an evogym world file in tasks/worlds (MIT licence, see LICENSE-evogym
    there), any world file by path, or the spec's own `World`, with the objects its task code adds
    (`TaskSpec.objects`)."""
    spec = task_spec(name)
    worlds = resources.files("tasks") / "worlds"
    if isinstance(spec.world, World):
        world = spec.world
    elif (worlds / spec.world).is_file():
        with resources.as_file(worlds / spec.world) as p:
            world = load_world(p)
    elif Path(spec.world).is_file():
        world = load_world(spec.world)
    else:
        raise SgrError(f"task {name}: world file {spec.world!r} is neither in tasks/worlds nor a path "
                       "that exists")
    if not spec.objects:
        return world
    extra = []
    for a in spec.objects:
        with resources.as_file(worlds / a.file) as p:
            extra.append(load_object(p).placed(a.name, a.cell, per_world=a.per_world))
    return world.with_objects(tuple(extra))


def _world_of_task(name: str) -> World | None:
    return task_world(name) if name in TASKS else None


add_world_finder(_world_of_task)  # Renderer("Walker-v0", body) draws the task's world


def forget_worlds() -> None:
    """Drop the worlds (and the room they leave a body) built so far: a task was (re)registered."""
    task_world.cache_clear()
    _occupied.cache_clear()


@cache
def _occupied(name: str) -> np.ndarray:
    """(grid_w + margin, grid_h + margin) bool: the cells an object of the task's world fills at the
    start (terrain, free objects, objects added in code at their first cell)."""
    world = task_world(name)
    spec = TASKS[name]
    occ = np.zeros((max(world.grid_w, spec.origin[0]) + MAX_SIDE + 1,
                    max(world.grid_h, spec.origin[1]) + MAX_SIDE + 1), dtype=bool)
    for o in world.objects:
        m = o.body.matrix
        rows, cols = np.nonzero(m)
        occ[o.cell[0] + cols, o.cell[1] + m.shape[0] - 1 - rows] = True
    return occ


MAX_SIDE = 64  # the largest body side `body_fit_problem` looks for room up to


def body_fits(name: str, shape: tuple[int, int]) -> bool:
    """Whether a body of `shape` (rows, cols), placed with its bottom-left cell at the task's origin,
    fills no cell that an object of the world fills at the start. Above and right of the world's grid
    is open space (evogym grows its grid for the robot; nothing there collides), so only the objects
    bound a body."""
    rows, cols = shape
    if rows > MAX_SIDE or cols > MAX_SIDE:
        return False
    x0, y0 = TASKS[name].origin
    return not _occupied(name)[x0:x0 + cols, y0:y0 + rows].any()


def largest_square_body(name: str) -> int:
    """The side of the largest square body that fits the task's world (`body_fits`); 0: none."""
    return max((s for s in range(1, MAX_SIDE + 1) if body_fits(name, (s, s))), default=0)


def body_fit_problem(name: str, shape: tuple[int, int]) -> str | None:
    """None when a body of `shape` fits the task's world (`body_fits`), else one line saying which
    object is in the way and the largest bodies that do fit."""
    if body_fits(name, shape):
        return None
    rows, cols = shape
    if rows > MAX_SIDE or cols > MAX_SIDE:
        return f"sgr places bodies of up to {MAX_SIDE}x{MAX_SIDE}, not {rows}x{cols}"
    side = largest_square_body(name)
    most_rows = max((r for r in range(1, MAX_SIDE + 1) if body_fits(name, (r, cols))), default=0)
    most_cols = max((c for c in range(1, MAX_SIDE + 1) if body_fits(name, (rows, c))), default=0)
    x0, y0 = TASKS[name].origin
    also = [f"with {cols} columns: [{most_rows}, {cols}]"] if most_rows and most_rows != side else []
    also += [f"with {rows} rows: [{rows}, {most_cols}]"] if most_cols and most_cols != side else []
    more = f" ({'; '.join(also)})" if also else ""
    return (f"a {rows}x{cols} body placed at cell ({x0}, {y0}) of {name}'s world overlaps its terrain or "
            f"objects; the largest square that fits is [{side}, {side}]{more}")
