"""sgr: the face users import. Re-exports the public API of the three layers below it (what the
`__all__` of `tsim`, `tasks` and `evolve` hold), so `import sgr` is enough for a notebook:

    import sgr
    env = sgr.BatchEnv("Walker-v0", [body])
    exp = sgr.Experiment.from_config({"method": "sgr", "task": "Walker-v0"}, out="runs/nb")

`sgr.evogym` is evogym 2.0's own API (EvoWorld, EvoSim, EvoViewer, EvoGymBase, utils, the bare gym
ids) on our simulator, so evogym code ports by changing `evogym` to `sgr.evogym` in its imports.
Nothing in tsim, tasks or evolve imports this package.
"""

import evolve as _evolve
import tasks as _tasks
import tsim as _tsim
from evolve import *  # noqa: F403
from tasks import *  # noqa: F403
from tsim import *  # noqa: F403

__all__ = sorted(set(_tsim.__all__) | set(_tasks.__all__) | set(_evolve.__all__))
