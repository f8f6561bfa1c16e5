"""f32 against evogym's recorded data (tests/data/evogym32) and evogym's own chaos floor, on 10 of
the 32 tasks (all 32 take ~1-2 minutes on 2 shared cores; their figures are in docs/VALIDATION.md,
"Single precision"): the median over the 24 robots of the largest COM error over the episode
within evogym's spread under +-1e-6 action changes (`parity.harness.chaos_check`, which `sgr
validate` reports in f32; the issue's criterion is 2x, every task now lies within 0.5x). The
subset: Walker-v0; 4 that failed by 56x to 1,714x before f32 kept positions as pairs
(tsim/kernels/pairs.py): Hurdler-v0 and HeightMaximizer-v0 (floors of 3e-7 to 6e-7), Pusher-v1
(an object), BridgeWalker-v0 (a simulated bridge), Traverser-v0 (passes only with the contacts
computed from the pairs); Climber-v2 (3.9x with the pairs: its robot starts flush between walls,
3.4e-16 above the terrain, tsim/rounding.py) and Jumper-v0 (2.5x: a COM summed in float32,
`BatchSim.robot_com`); and the last two to pass, Lifter-v0 (15.2x) and PlatformJumper-v0 (2.1x),
whose robots stand 1.1e-16 from walls and terrain corners: they need the placement and the terrain
as pairs and the contact tests on differences of pairs (`narrowphase.corner_less`,
`geometry.intersects_ends`). Runs in a subprocess: a process's precision is fixed when Taichi
starts."""

import json
import os
import subprocess
import sys

import pytest

pytestmark = pytest.mark.slow

PASSING = ["Walker-v0", "Hurdler-v0", "HeightMaximizer-v0", "Pusher-v1", "BridgeWalker-v0",
           "Traverser-v0", "Climber-v2", "Jumper-v0", "Lifter-v0", "PlatformJumper-v0"]

PROBE = """
import json, sys
from parity.harness import validate_evogym32
print(json.dumps(validate_evogym32(sys.argv[1], sys.argv[2:])))
"""


def test_f32_within_twice_evogyms_chaos_floor_on_its_passing_tasks(data_dir):
    env = {k: v for k, v in os.environ.items() if k not in ("SGR_ARCH",)}
    out = subprocess.run([sys.executable, "-c", PROBE, str(data_dir / "evogym32"), *PASSING],
                         env={**env, "SGR_PRECISION": "f32", "SGR_THREADS": "1"}, capture_output=True,
                         text=True, timeout=600)
    assert out.returncode == 0, out.stderr
    r = json.loads(out.stdout.strip().splitlines()[-1])
    for task in PASSING:
        t = r[task]
        assert t["com_ok"], (task, t["com_err_median"], t["chaos_floor"])
        assert t["com_err_median"] < t["chaos_floor"], (task, t["com_ratio"])  # measured <= 0.47
        assert t["spearman"] > 0.93, (task, t["spearman"])  # returns ranked as evogym's (24 robots)
        assert t["com_err_median"] > 1e-9, (task, t)  # f32 really ran (f64 agrees to ~1e-14)
