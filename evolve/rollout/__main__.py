"""`python -m evolve.rollout`: a rollout worker process of `RolloutPool` (see evolve/rollout/worker.py)."""

from evolve.rollout.worker import main

main()
