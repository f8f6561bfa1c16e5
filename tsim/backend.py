"""`Backend`: where and in which real type the kernels run, decided once per process.

One value (arch, precision, threads) that the simulator, the tasks' numpy arrays, the rollout
pools and a run's record read, instead of each asking $SGR_ARCH / $SGR_PRECISION on its own. It
owns what follows from those choices: numpy's dtype at the kernels' boundary, the kernels'
tolerances for the real type (`tsim.kernels.layout.Tolerances`), and how a step is launched (the
CPU's cached launch context, `tsim/launch.py`).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from tsim import runtime
from tsim.kernels.layout import TOLERANCES, Tolerances


@dataclass(frozen=True)
class Backend:
    """The process's Taichi arch ("cpu", "cuda", ...), real type ("f64" or "f32") and CPU threads."""

    arch: str
    precision: str
    threads: int

    @property
    def dtype(self) -> type:
        """numpy's type of the real arrays the kernels read and write."""
        return np.float32 if self.precision == "f32" else np.float64

    @property
    def tolerances(self) -> Tolerances:
        """The kernels' margins for this real type."""
        return TOLERANCES[self.precision]

    @property
    def cached_launch(self) -> bool:
        """Whether a step re-launches from a cached launch context (the CPU only)."""
        return self.arch == "cpu"

    @property
    def bit_faithful(self) -> bool:
        """Whether results are evogym's bit for bit (f64 on the CPU; f32 is statistically
        faithful, within evogym's chaos floor: docs/VALIDATION.md)."""
        return self.arch == "cpu" and self.precision == "f64"

    @property
    def runs_on(self) -> str:
        """The arch the kernels really run on: "cpu", "cuda", "vulkan" or "metal" (what "gpu"
        resolved to)."""
        return runtime.resolved_arch()

    @property
    def device(self) -> str:
        """The device's name ("x64: <CPU model>", the GPU's name, "<Vulkan device>: <type>")."""
        return runtime.device()[0]

    @property
    def software(self) -> bool:
        """Whether the device is a software one (Mesa's lavapipe: a GPU API run on the CPU)."""
        return runtime.device()[1]

    def line(self) -> str:
        """One line naming the backend, the device and the precision (`tsim.runtime.describe`)."""
        return runtime.describe()

    def record(self) -> dict:
        """What a run folder records of it (a segment of the run's life: evolve/records/segments.py)."""
        return {"arch": self.runs_on, "asked": self.arch, "device": self.device, "software": self.software,
                "precision": self.precision, "threads": self.threads}


def get(arch: str | None = None, precision: str | None = None) -> Backend:
    """The process's backend, starting Taichi on first use (`tsim.runtime.init`: None means
    $SGR_ARCH / $SGR_PRECISION, else cpu / f64); ValueError, one line, for one that cannot run
    here or that differs from the one already started."""
    arch = runtime.init(arch, precision)
    return Backend(arch=arch, precision=runtime.precision(), threads=runtime.threads())
