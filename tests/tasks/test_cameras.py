"""Every task's default camera (what `render_mode="rgb_array"` and the GIFs use) shows what the task
is about at the start of an episode: the whole robot, and the objects it is to move or cross where
they fit beside it (Traverser-v0's blocks, BeamToppler-v0's beam). Catcher-v0's package starts
4 units above the robot, twice the view's height: it comes into the picture as it falls."""

import numpy as np
import pytest

from tasks.specs import BUILTIN, TASKS, task_world
from tsim import Renderer, build_body

BODY = build_body(np.full((5, 5), 3))
FALLS_INTO_VIEW = {"Catcher-v0"}


def in_view(r: Renderer, points: np.ndarray) -> bool:
    px = r.to_pixels(points.T)
    return bool((px[:, 0] >= 0).all() and (px[:, 0] <= r.width).all() and (px[:, 1] >= 0).all()
                and (px[:, 1] <= r.height).all())


@pytest.mark.parametrize("task", sorted(BUILTIN))
def test_the_first_frame_shows_the_robot_and_the_task_s_objects(task):
    world = task_world(task)
    r = Renderer(world, BODY, 640, 320)
    robot = BODY.place(*TASKS[task].origin)
    r.frame(robot)  # objects at their start
    assert in_view(r, robot)
    loose = [o for o in world.free_objects if not np.any(o.body.voxel_type == 5)]
    shown = sum(in_view(r, o.pos0) for o in loose)
    if loose and task not in FALLS_INTO_VIEW:
        assert shown >= max(1, len(loose) // 3), f"{task}: {shown} of {len(loose)} objects in view"


def test_traverser_v0_rgb_array_frames_show_its_blocks():
    """Through gymnasium: most of the pit's blocks are in the first rgb_array frame."""
    import gymnasium as gym

    import tasks  # noqa: F401

    env = gym.make("sgr/Traverser-v0", body=np.full((5, 5), 3), render_mode="rgb_array")
    env.reset(seed=0)
    frame = env.render()
    r = env.unwrapped._renderer
    blocks = [o.name for o in r.world.free_objects if o.name.startswith("block_")]
    sim = env.unwrapped._env.sim
    assert frame.shape == (320, 640, 3)
    assert sum(in_view(r, sim.object_pos(0, b)) for b in blocks) >= 9
