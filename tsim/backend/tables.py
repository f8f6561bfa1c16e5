"""The names and facts of sgr's precisions and archs: the one module that writes them.

The precisions (name -> numpy and Taichi real type, the kernels' tolerances, whether positions are
kept as float pairs, whether results are evogym's bits) and the archs (name -> the Taichi archs
tried, what is missing when none starts, whether it has 64-bit floats, how a step is launched).
The names "f64", "f32", "cpu", "gpu", "cuda", "vulkan" and "metal" are written as string literals
here only: other modules use `PRECISIONS`, `ARCHS`, `DEFAULT_PRECISION`, the `CPU`/`CUDA`/...
constants or a `tsim.backend.Backend`'s properties (tests/tsim/backend/test_backend_seam.py greps for
them). A leaf module (no Taichi, nothing of tsim but its constants), so that tsim.backend.runtime, which
starts Taichi, and tsim.backend.devices can read it; `tsim.backend` re-exports it with the process's
`Backend`.

Adding a precision: one `Precision` row in `PRECISIONS` (its numpy and Taichi types and its
`Tolerances`); the CLI's choices, the run config's check, tsim.backend.runtime and the kernels follow.
Adding a backend: one `Arch` row in `ARCHS` (the Taichi archs it tries, what is missing without
it, whether it has f64, and its launch path: a key of tsim/backend/launch.py's `LAUNCHERS`, to which a
backend that launches its step differently, e.g. the GPU lanes kernel of tsim/backend/lanes.py, adds its
launcher).
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
    launch: str = "device"  # how a step is launched: a key of tsim/backend/launch.py's LAUNCHERS
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
