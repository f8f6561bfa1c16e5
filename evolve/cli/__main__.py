"""`python -m evolve.cli ...`: the `sgr` command (the rollout and sweep processes start it so)."""

import sys

from evolve.cli import main

sys.exit(main())
