"""Taichi start-up: one `ti.init` per process, f64, CPU unless a GPU is asked for."""

from __future__ import annotations

import contextlib
import io
import os
import sys

# Taichi's banners go to stderr (they would corrupt `sgr ... --json` output); TI_ENABLE_PYBUF=0
# keeps Taichi from wrapping every kernel call because stdout is redirected meanwhile (no kernel prints)
os.environ.setdefault("TI_ENABLE_PYBUF", "0")
# no version banner: a command's stderr is for its warnings and its one-line errors
os.environ.setdefault("ENABLE_TAICHI_HEADER_PRINT", "0")
with contextlib.redirect_stdout(sys.stderr):
    import taichi as ti

_ARCH: str | None = None


def init(arch: str | None = None) -> str:
    """Initialise Taichi once; later calls with another arch raise (Taichi cannot switch)."""
    global _ARCH
    arch = arch or os.environ.get("SGR_ARCH", "cpu")
    if arch not in ("cpu", "gpu", "cuda", "vulkan", "metal"):
        raise ValueError(f"unknown arch {arch!r}; use cpu, gpu, cuda, vulkan or metal")
    if _ARCH is not None:
        if arch != _ARCH:
            raise ValueError(f"Taichi already runs on {_ARCH}; cannot switch to {arch} in one process")
        return _ARCH
    threads = os.environ.get("SGR_THREADS")
    kwargs = {"cpu_max_num_threads": int(threads)} if threads else {}
    # fast_math off: IEEE semantics like evogym's C++ build (no reassociation), so results do not
    # depend on how a kernel is written or optimised (the parallel and serial kernels and every
    # capacity tier agree bit for bit) and the parity with evogym's traces is as good or better
    # make_cpu_multithreading_loop off: Taichi 1.7 otherwise hands each CPU thread a block of at
    # least 512 iterations, so a batch of fewer than 1,024 worlds ran on one thread only; without
    # it the worlds are dealt to the threads in blocks of `block_dim` (1 for the step kernels)
    # advanced_optimization off: Taichi's own IR optimisations took ~25 s to compile the kernels
    # (cold cache) and gave no measurable speed over LLVM's; with them off it takes ~4 s
    said = io.StringIO()  # Taichi prints "[Taichi] Starting on arch=..."; other lines go to stderr
    with contextlib.redirect_stdout(said):
        ti.init(arch=getattr(ti, arch), default_fp=ti.f64, default_ip=ti.i32, fast_math=False,
                advanced_optimization=False, make_cpu_multithreading_loop=False,
                log_level=ti.WARN, **kwargs)
    for line in said.getvalue().splitlines():
        if not line.startswith("[Taichi] Starting on arch="):
            print(line, file=sys.stderr)
    _ARCH = arch
    return _ARCH


def threads() -> int:
    n = os.environ.get("SGR_THREADS")
    return int(n) if n else (os.cpu_count() or 1)
