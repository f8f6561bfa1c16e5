"""The task registry: every task's spec by its evogym id, and its world."""

from __future__ import annotations

from functools import cache
from importlib import resources

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
from tsim.world import World, load_object, load_world

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


def task_spec(name: str) -> TaskSpec:
    """The spec of an evogym task id such as Walker-v0; ValueError listing the known ids otherwise."""
    try:
        return TASKS[name]
    except KeyError:
        raise ValueError(f"unknown task {name!r}; known tasks: {', '.join(TASKS)}") from None


@cache
def task_world(name: str) -> World:
    """The task's evogym world (files in tasks/worlds, MIT licence, see LICENSE-evogym there),
    with the objects its task code adds (`TaskSpec.objects`)."""
    spec = task_spec(name)
    worlds = resources.files("tasks") / "worlds"
    with resources.as_file(worlds / spec.world) as p:
        world = load_world(p)
    if not spec.objects:
        return world
    extra = []
    for a in spec.objects:
        with resources.as_file(worlds / a.file) as p:
            extra.append(load_object(p).placed(a.name, a.cell, per_world=a.per_world))
    return world.with_objects(tuple(extra))
