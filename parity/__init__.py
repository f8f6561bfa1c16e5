"""parity: the evogym comparison harness. evogym's recorded data (trajectories, returns,
observations; ../shared/reference) replayed through sgr's tasks, and the disagreement measured.

    from parity.harness import validate
    report = validate("tests/data/traces")  # per case and per task: COM, observation and return errors

It sits above `tasks` (it drives `tasks.env.BatchEnv`) and below `evolve`, whose dispatcher adds
its command, `sgr validate DIR` (parity/cli.py). docs/VALIDATION.md states the tolerances.
"""
