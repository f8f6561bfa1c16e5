"""evogym's 32 tasks under their bare gym ids ("Walker-v0", ...), as `import evogym.envs`
registers them: evogym's `max_episode_steps` and keyword arguments (`body`, `connections`,
`render_mode` None / 'img' / 'rgb_array' / 'screen' / 'human', `render_options`).

They compute through `tasks` (the validated `BatchEnv` and the tasks' `TaskSpec`s): `TaskEnv` is
`tasks.SgrEnv` with evogym's arguments and rendering, and `gym.make_vec` on a bare id gives
`TaskVectorEnv`, the batched `tasks.SgrVectorEnv` (one Taichi batch for all robots).
"""

from __future__ import annotations

from typing import Any

import gymnasium as gym
import numpy as np

from sgr.evogym.envs.base import RENDER_MODES, check_render_mode, render_with
from sgr.evogym.viewer import EvoViewer
from tasks.gym_env import SgrEnv, SgrVectorEnv, register_id
from tasks.specs import TASKS
from tsim.body import build_body

# evogym's env class of each task (what its registration's entry point names)
EVOGYM_CLASSES = {
    "Walker-v0": "WalkingFlat", "BridgeWalker-v0": "SoftBridge", "BidirectionalWalker-v0": "BiWalk",
    "Carrier-v0": "CarrySmallRect", "Carrier-v1": "CarrySmallRectToTable", "Pusher-v0": "PushSmallRect",
    "Pusher-v1": "PushSmallRectOnOppositeSide", "Thrower-v0": "ThrowSmallRect",
    "Catcher-v0": "CatchSmallRect", "BeamToppler-v0": "ToppleBeam", "BeamSlider-v0": "SlideBeam",
    "Lifter-v0": "LiftSmallRect", "Climber-v0": "Climb0", "Climber-v1": "Climb1", "Climber-v2": "Climb2",
    "UpStepper-v0": "StepsUp", "DownStepper-v0": "StepsDown", "ObstacleTraverser-v0": "WalkingBumpy",
    "ObstacleTraverser-v1": "WalkingBumpy2", "Hurdler-v0": "VerticalBarrier",
    "PlatformJumper-v0": "FloatingPlatform", "GapJumper-v0": "Gaps", "Traverser-v0": "BlockSoup",
    "CaveCrawler-v0": "Duck", "AreaMaximizer-v0": "MaximizeShape", "AreaMinimizer-v0": "MinimizeShape",
    "WingspanMazimizer-v0": "MaximizeXShape", "HeightMaximizer-v0": "MaximizeYShape",
    "Flipper-v0": "Flipping", "Jumper-v0": "StationaryJump", "Balancer-v0": "Balance",
    "Balancer-v1": "BalanceJump",
}

__all__ = ["EVOGYM_CLASSES", "TaskEnv", "TaskVectorEnv", "register_bare_ids", "task_classes"]


def _robot(body: Any, connections: Any):
    """The body as BatchEnv takes it: the matrix, or (with connections) its built topology."""
    if body is None:
        raise ValueError("evogym's tasks need a body= (a voxel matrix, e.g. from sample_robot)")
    if connections is None:
        return body
    return build_body(np.asarray(body), np.asarray(connections))


class _TaskScene:
    """What EvoViewer reads of a one-world BatchEnv: the current points by evogym's object names
    ('robot', then the world's objects), in voxels, and the scene to draw."""

    def __init__(self, env: SgrEnv):
        self._env = env

    @property
    def _sim(self):
        return self._env.batch_env.sim

    def get_time(self) -> int:
        """Steps since the last reset."""
        return int(self._env.batch_env.elapsed[0])

    def _check_object(self, name: str) -> None:
        if name != "robot":
            self._sim.world.object(name)  # KeyError naming the world when absent

    def object_pos_at_time(self, time: int, object_name: str) -> np.ndarray:
        """Current points of an object in voxels (the viewer asks only for the current time)."""
        sim = self._sim
        if object_name == "robot":
            return sim.robot_pos(0) / 0.1
        if any(o.name == object_name for o in sim.free_objects):
            return sim.object_pos(0, object_name) / 0.1
        return sim.world.object(object_name).pos0 / 0.1

    def _render_scene(self):
        sim = self._sim
        return sim.world, sim.bodies[0], sim.robot_pos(0), sim.objects_pos(0)


class TaskEnv(SgrEnv):
    """One evogym task under its bare id (evogym's BenchmarkBase envs): gymnasium's API computed
    by `tasks.SgrEnv`; `render()` as evogym's, the viewer tracking the robot."""

    metadata = {"render_modes": list(RENDER_MODES), "render_fps": 50}

    def __init__(self, body: np.ndarray | None = None, connections: np.ndarray | None = None,
                 render_mode: str | None = None, render_options: dict[str, Any] | None = None, *,
                 task: str):
        check_render_mode(render_mode)
        super().__init__(task, _robot(body, connections))
        self.render_mode = render_mode
        self._render_options = render_options
        self._default_viewer = EvoViewer(_TaskScene(self))
        self._default_viewer.track_objects("robot")

    @property
    def default_viewer(self) -> EvoViewer:
        """The viewer `render()` uses (tracks the robot)."""
        return self._default_viewer

    def step(self, action):
        """gymnasium's step; draws to the window each step in 'screen' / 'human' mode."""
        out = super().step(action)
        if self.render_mode in ("human", "screen"):
            self.render()
        return out

    def render(self) -> np.ndarray | None:
        """None without a render mode; an (H, W, 3) uint8 image for 'img' / 'rgb_array'."""
        return render_with(self._default_viewer, self.render_mode, self._render_options)

    def close(self) -> None:
        """Close the viewer's window if one is open."""
        self._default_viewer.close()


class TaskVectorEnv(SgrVectorEnv):
    """`gym.make_vec` of a bare id: all robots in one batched simulation (`tasks.SgrVectorEnv`),
    with evogym's `connections` accepted for `body` (rendering is per env: use `gym.make`)."""

    def __init__(self, task: str, bodies=None, *, body=None, connections=None, num_envs=None,
                 max_episode_steps=None, render_mode: str | None = None, render_options=None):
        if render_mode is not None:
            raise ValueError("the batched vector env does not render; make single envs with "
                             "gym.make(id, render_mode=...) to render")
        if body is not None:
            body = _robot(body, connections)
        super().__init__(task, bodies, body=body, num_envs=num_envs,
                         max_episode_steps=max_episode_steps)


def register_bare_ids() -> None:
    """Register every task under its bare evogym id with evogym's episode length (idempotent)."""
    for name, spec in TASKS.items():
        if name in gym.registry:
            continue
        register_id(name, entry_point="sgr.evogym.envs.benchmark:TaskEnv",
                    vector_entry_point="sgr.evogym.envs.benchmark:TaskVectorEnv",
                    kwargs={"task": name}, max_episode_steps=spec.evogym_steps)


def task_classes() -> dict[str, type]:
    """evogym's env classes by name (`WalkingFlat(body)` is Walker-v0 without gym's wrappers), each
    a `TaskEnv` bound to its task."""
    def init(self, body=None, connections=None, render_mode=None, render_options=None):
        TaskEnv.__init__(self, body, connections, render_mode, render_options, task=self.TASK)

    return {cls_name: type(cls_name, (TaskEnv,), {
        "TASK": task, "__init__": init, "__module__": __name__,
        "__doc__": f"evogym's {cls_name}: the task {task} (see TaskEnv)."})
        for task, cls_name in EVOGYM_CLASSES.items()}
