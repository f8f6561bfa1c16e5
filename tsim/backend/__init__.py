"""`Backend`: where and in which real type the kernels run, decided once per process.

One value (arch, precision, threads) that the simulator, the tasks' numpy arrays, the rollout
pools and a run's record read, instead of each asking $SGR_ARCH / $SGR_PRECISION on its own. It
owns what follows from those choices: numpy's dtype at the kernels' boundary, the kernels'
tolerances for the real type, and how a step is launched (`Backend.launch_path`, tsim/backend/launch.py:
the CPU's cached launch, the SPIR-V backends' split launches, a CUDA launch). The precisions and
archs themselves, their names and facts, are tsim/backend/tables.py's tables, re-exported here: every
arch and precision decision asks this module or that one (docs/VALIDATION.md says how to add one).
"""

from __future__ import annotations

from dataclasses import dataclass

from tsim.backend.tables import (  # noqa: F401 - re-exported: the seam's tables
    ARCHS,
    CPU,
    CUDA,
    DEFAULT_ARCH,
    DEFAULT_PRECISION,
    GPU,
    METAL,
    NO_F64,
    PRECISIONS,
    SPIRV_ARCHS,
    TAICHI_CPUS,
    VULKAN,
    Arch,
    Precision,
    Tolerances,
    resolved,
)


def real() -> Precision:
    """The process's real type: the one Taichi runs in once started, else the one it would start
    in. What the kernels compile for (read at compile time, under `ti.static`)."""
    from tsim.backend import runtime

    return PRECISIONS[runtime.precision()]


@dataclass(frozen=True)
class Backend:
    """The process's Taichi arch ("cpu", "cuda", ...), real type ("f64" or "f32") and CPU threads."""

    arch: str
    precision: str
    threads: int

    @property
    def real(self) -> Precision:
        """The real type's row in `PRECISIONS`."""
        return PRECISIONS[self.precision]

    @property
    def dtype(self) -> type:
        """numpy's type of the real arrays the kernels read and write."""
        return PRECISIONS[self.precision].dtype

    @property
    def tolerances(self) -> Tolerances:
        """The kernels' margins for this real type."""
        return PRECISIONS[self.precision].tolerances

    @property
    def on_host(self) -> bool:
        """Whether the kernels run on the host's CPU cores (one thread runs serially, arrays are
        the numpy arrays themselves)."""
        return ARCHS[self.arch].host

    @property
    def cached_launch(self) -> bool:
        """Whether a step re-launches from a cached launch context (the CPU only)."""
        return ARCHS[self.arch].host

    @property
    def bit_faithful(self) -> bool:
        """Whether results are evogym's bit for bit (f64 on the CPU; f32 is statistically
        faithful, within evogym's chaos floor: docs/VALIDATION.md)."""
        return ARCHS[self.arch].host and PRECISIONS[self.precision].bits

    @property
    def launch_path(self) -> str:
        """How a step is launched on the arch the kernels really run on: a key of
        tsim/backend/launch.py's `LAUNCHERS` ("host", "device" or "spirv")."""
        from tsim.backend import runtime

        if runtime.backend() in SPIRV_ARCHS:  # opengl/gles too, which no `Arch` names
            return "spirv"
        return ARCHS[self.runs_on].launch

    @property
    def kernel_path(self) -> str:
        """The launch path of one `step_kernel` launch per step here ("host" or "device"): what
        a step takes when the SPIR-V launch is turned off (`BatchSim.choose_kernel`)."""
        return "host" if ARCHS[self.arch].host else "device"

    @property
    def runs_on(self) -> str:
        """The arch the kernels really run on: "cpu", "cuda", "vulkan" or "metal" (what "gpu"
        resolved to)."""
        from tsim.backend import runtime

        return runtime.resolved_arch()

    @property
    def device(self) -> str:
        """The device's name ("x64: <CPU model>", the GPU's name, "<Vulkan device>: <type>")."""
        from tsim.backend import runtime

        return runtime.device()[0]

    @property
    def software(self) -> bool:
        """Whether the device is a software one (Mesa's lavapipe: a GPU API run on the CPU)."""
        from tsim.backend import runtime

        return runtime.device()[1]

    def line(self) -> str:
        """One line naming the backend, the device and the precision (`tsim.backend.runtime.describe`)."""
        from tsim.backend import runtime

        return runtime.describe()

    def record(self) -> dict:
        """What a run folder records of it (a segment of the run's life: evolve/records/segments.py)."""
        return {"arch": self.runs_on, "asked": self.arch, "device": self.device, "software": self.software,
                "precision": self.precision, "threads": self.threads}


def get(arch: str | None = None, precision: str | None = None) -> Backend:
    """The process's backend, starting Taichi on first use (`tsim.backend.runtime.init`: None means
    $SGR_ARCH / $SGR_PRECISION, else cpu / f64); ValueError, one line, for one that cannot run
    here or that differs from the one already started."""
    from tsim.backend import runtime

    arch = runtime.init(arch, precision)
    return Backend(arch=arch, precision=runtime.precision(), threads=runtime.threads())
