"""`Backend`: where and in which real type the kernels run, decided once per process; and the one
module that names the precisions and the archs.

Every arch and precision decision asks this module: the precisions (name -> numpy and Taichi real
type, the kernels' tolerances, whether positions are kept as float pairs, whether results are
evogym's bits), the archs (name -> the Taichi archs tried, what is missing when none starts,
whether it has 64-bit floats, how a step is launched). The names "f64", "f32", "cpu", "gpu",
"cuda", "vulkan" and "metal" are written as string literals here only: other modules use
`PRECISIONS`, `ARCHS`, `DEFAULT_PRECISION`, the `CPU`/`CUDA`/... constants or a `Backend`'s
properties (tests/tsim/test_backend_seam.py greps for them).

One `Backend` value (arch, precision, threads) is what the simulator, the tasks' numpy arrays,
the rollout pools and a run's record read, instead of each asking $SGR_ARCH / $SGR_PRECISION on
its own. It owns what follows from those choices: numpy's dtype at the kernels' boundary, the
kernels' tolerances, and how a step is launched (`Backend.launcher`, tsim/launch.py: the CPU's
cached launch, the SPIR-V backends' split launches, a CUDA launch of the block size asked).

Adding a precision: one `Precision` row in `PRECISIONS` (its numpy and Taichi types and its
`Tolerances`); the CLI's choices, the run config's check and the kernels follow. Adding a backend:
one `Arch` row in `ARCHS` (the Taichi archs it tries, what is missing without it, whether it has
f64, and its launch path: one of tsim/launch.py's `LAUNCHERS`, or a new launcher there when its
step is launched differently, e.g. the GPU lanes kernel of docs/notes: a launcher keyed
"lanes" that picks its kernel and lane count).

This module imports no Taichi (the CLI's parsers read its tables without waiting for it); what
needs a started Taichi (`get`, `Backend.runs_on`, ...) asks `tsim.runtime` when called.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import NamedTuple

import numpy as np

from tsim import constants as C


class Tolerances(NamedTuple):
    """Margins that must lie far above the real type's rounding at world coordinates (and that
    f64 sets to the values evogym's parity was established with). Read at compile time."""

    box_margin: float  # a corner this far outside a voxel's box skips the point-in-voxel test
    skin_slack: float  # above the rounding of `box + SKIN` at coordinates below ref_max
    ref_max: float  # no pair list in worlds with a coordinate beyond this
    sort_slack: float  # widens the sweep's candidate range beyond rounding
    grid_slack: float  # widens the terrain grid range (in cells) beyond rounding


@dataclass(frozen=True)
class Precision:
    """A real type the kernels compile for, and what follows from it."""

    name: str
    dtype: type  # numpy's type of the real arrays at the kernels' boundary
    taichi: str  # Taichi's type, `getattr(ti, taichi)` (the `default_fp` of `ti.init`)
    tolerances: Tolerances
    pairs: bool  # positions and velocities kept as float pairs hi + lo (tsim.kernels.layout)
    bits: bool  # evogym's bits on the CPU (else statistically faithful: docs/VALIDATION.md)
    needs_f64: bool  # needs an arch with 64-bit floats (`Arch.f64`)


PRECISIONS: dict[str, Precision] = {
    "f64": Precision("f64", np.float64, "f64", bits=True, needs_f64=True, pairs=False, tolerances=Tolerances(
        box_margin=C.BOX_MARGIN, skin_slack=1e-9, ref_max=1e6, sort_slack=1e-6, grid_slack=1e-6)),
    # f32 rounds at ~6e-8 relative: ~6e-5 at coordinate 1,000, where its lists stop
    "f32": Precision("f32", np.float32, "f32", bits=False, needs_f64=False, pairs=True, tolerances=Tolerances(
        box_margin=1e-5, skin_slack=1e-3, ref_max=1e3, sort_slack=1e-3, grid_slack=1e-3)),
}
DEFAULT_PRECISION = "f64"  # evogym's bits

CPU, GPU, CUDA, VULKAN, METAL = "cpu", "gpu", "cuda", "vulkan", "metal"


@dataclass(frozen=True)
class Arch:
    """An arch a user may ask for ($SGR_ARCH), and how the kernels run on it."""

    name: str
    taichi: tuple[str, ...]  # Taichi's archs tried, in order (`getattr(ti, name)`)
    missing: str  # what is missing when Taichi cannot start it (Taichi does not say why)
    f64: bool = True  # has 64-bit floats
    launch: str = "device"  # how a step is launched: a key of tsim/launch.py's LAUNCHERS
    host: bool = False  # runs on the host's CPU cores (threads, pinning, cached launches)


ARCHS: dict[str, Arch] = {
    "cpu": Arch("cpu", ("cpu",), "no CPU backend", launch="host", host=True),
    # "gpu" tries only the GPU backends this package supports: Taichi's own ti.gpu list also probes
    # OpenGL, whose probe crashes the process on some machines without a display
    "gpu": Arch("gpu", ("cuda", "metal", "vulkan"), "no GPU (tried CUDA, Metal and Vulkan)"),
    "cuda": Arch("cuda", ("cuda",), "no CUDA device (it needs an NVIDIA GPU and its driver, libcuda.so)"),
    "vulkan": Arch("vulkan", ("vulkan",), "no Vulkan device (it needs a Vulkan driver: a GPU's, or Mesa's "
                   "software one, Debian's mesa-vulkan-drivers)", launch="spirv"),
    "metal": Arch("metal", ("metal",), "no Metal device (Metal exists only on macOS with an Apple or AMD "
                  "GPU)", f64=False, launch="spirv"),
}
DEFAULT_ARCH = CPU
# Taichi's own arch names (`ti.lang.impl.current_cfg().arch.name`) -> the arch they run as
TAICHI_CPUS = ("x64", "arm64")
# Taichi's backends that compile to SPIR-V: they have no 64-bit transcendental functions
SPIRV_ARCHS = ("vulkan", "metal", "opengl", "gles")
NO_F64 = tuple(a for a, arch in ARCHS.items() if not arch.f64)  # archs without 64-bit floats


def resolved(taichi_arch: str) -> str:
    """The arch name Taichi's arch `taichi_arch` ("x64", "cuda", ...) runs as: "cpu" for a CPU."""
    return CPU if taichi_arch in TAICHI_CPUS else taichi_arch


def real() -> Precision:
    """The process's real type: the one Taichi runs in once started, else the one it would start
    in. What the kernels compile for (read at compile time, under `ti.static`)."""
    from tsim import runtime

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
        tsim/launch.py's `LAUNCHERS` ("host", "device" or "spirv")."""
        from tsim import runtime

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
        from tsim import runtime

        return runtime.resolved_arch()

    @property
    def device(self) -> str:
        """The device's name ("x64: <CPU model>", the GPU's name, "<Vulkan device>: <type>")."""
        from tsim import runtime

        return runtime.device()[0]

    @property
    def software(self) -> bool:
        """Whether the device is a software one (Mesa's lavapipe: a GPU API run on the CPU)."""
        from tsim import runtime

        return runtime.device()[1]

    def line(self) -> str:
        """One line naming the backend, the device and the precision (`tsim.runtime.describe`)."""
        from tsim import runtime

        return runtime.describe()

    def record(self) -> dict:
        """What a run folder records of it (a segment of the run's life: evolve/runs/segments.py)."""
        return {"arch": self.runs_on, "asked": self.arch, "device": self.device, "software": self.software,
                "precision": self.precision, "threads": self.threads}


def get(arch: str | None = None, precision: str | None = None) -> Backend:
    """The process's backend, starting Taichi on first use (`tsim.runtime.init`: None means
    $SGR_ARCH / $SGR_PRECISION, else cpu / f64); ValueError, one line, for one that cannot run
    here or that differs from the one already started."""
    from tsim import runtime

    arch = runtime.init(arch, precision)
    return Backend(arch=arch, precision=runtime.precision(), threads=runtime.threads())
