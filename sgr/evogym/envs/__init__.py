"""evogym 2.0's `evogym.envs` on sgr: the base classes for custom environments (`EvoGymBase`,
`BenchmarkBase`); importing it registers evogym's 32 tasks under their bare gym ids."""

from sgr.evogym.envs.base import BenchmarkBase, EvoGymBase

__all__ = ["BenchmarkBase", "EvoGymBase"]
