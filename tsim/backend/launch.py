"""Re-launching a compiled Taichi kernel with the same arguments, without Taichi's per-call work.

A Taichi call spends most of its launch in Python on `BatchSim.step`'s 18-19 arguments (matching
them to a compiled instance, then checking and setting each one): a launch in which no world runs
took 94 us through Taichi's call and 27 us cached (one thread), against ~1 ms of physics for a
16-robot Walker-v0 step. Between two steps the arguments do not change: the same numpy arrays
(updated in place), the same Taichi ndarrays, the same integers. `CachedLaunch` sets them once into
a launch context and re-launches with it. It uses Taichi 1.7's kernel internals
(`Kernel.ensure_compiled`, `make_launch_context`, `Program.launch_kernel`); if they are not there,
`build` returns None and the caller keeps calling the kernel normally. CPU only: on a GPU the
launch also moves numpy arrays to and from the device, which this has not been checked to keep.
"""

from __future__ import annotations

import numpy as np

from tsim.backend import runtime


class CachedLaunch:
    """A kernel's launch context with `args` set, valid while `matches(args)` holds.

    Made for `step_kernel`'s kinds of arguments only: C-contiguous numpy arrays and Taichi
    ndarrays of scalar dtype without gradients, 32-bit ints and template values (vector-dtype
    arrays, gradients, floats and structs are set differently by Taichi and are not handled)."""

    def __init__(self, kernel, prog, t_kernel, ctx, ndarrays: list, args: tuple):
        self._kernel = kernel
        self._prog = prog
        self._t_kernel = t_kernel
        self._ctx = ctx
        self._ndarrays = ndarrays
        self._args = args  # holds the arrays, so their memory outlives the context's pointers

    @classmethod
    def build(cls, kernel, args: tuple) -> CachedLaunch | None:
        """After `kernel(*args)` ran once (compiled). None if an argument is of a kind this
        does not handle, or Taichi's internals differ from 1.7's."""
        ti = runtime.ti
        try:
            primal = kernel._primal
            key = primal.ensure_compiled(*args)
            t_kernel = primal.compiled_kernels[key]
            ctx = t_kernel.make_launch_context()
            ndarrays = []
            slot = 0
            for arg, spec in zip(args, primal.arguments, strict=True):
                if isinstance(spec.annotation, ti.template):
                    continue
                if isinstance(arg, np.ndarray):
                    if not arg.flags.c_contiguous:
                        return None
                    ctx.set_arg_external_array_with_shape((slot,), int(arg.ctypes.data), arg.nbytes,
                                                          list(arg.shape), 0)
                elif isinstance(arg, ti.lang._ndarray.Ndarray):
                    ndarrays.append(((slot,), arg.arr))
                elif isinstance(arg, int | np.integer):
                    ctx.set_arg_int((slot,), int(arg))
                else:
                    return None
                slot += 1
            prog = ti.lang.impl.get_runtime().prog
        except (AttributeError, KeyError, TypeError, ValueError, RuntimeError):
            return None
        return cls(kernel, prog, t_kernel, ctx, ndarrays, args)

    def matches(self, kernel, args: tuple) -> bool:
        """The same kernel with the same arguments: the very same array objects (an array's
        address, shape and strides are fixed for its lifetime; a new view of the same memory is
        another object, and the caller then rebuilds) and equal integers. Identity, not the
        arrays' data pointers: reading `ndarray.ctypes` costs ~1.5 us per array per launch."""
        if kernel is not self._kernel or len(args) != len(self._args):
            return False
        for a, b in zip(args, self._args, strict=True):
            if a is b:
                continue
            if isinstance(a, int | np.integer) and isinstance(b, int | np.integer) and a == b:
                continue
            return False
        return True

    def launch(self) -> None:
        """Run the kernel once more with the cached arguments (call `matches` first).

        Taichi ndarray arguments are set anew each time: a launch replaces them in the context by
        their raw addresses (~1 us each). The compiled code is looked up at every launch (a cache
        hit), as Taichi does: the reference it returns need not outlive other compilations."""
        for slot, arr in self._ndarrays:
            self._ctx.set_arg_ndarray(slot, arr)
        prog = self._prog
        prog.launch_kernel(prog.compile_kernel(prog.config(), prog.get_device_caps(), self._t_kernel),
                           self._ctx)


class KernelLaunch:
    """An env step as one launch of `step_kernel` (worlds over the thread pool or a GPU's blocks of
    `block` worlds) or `step_kernel_serial` (on the calling thread), re-launched from a
    `CachedLaunch` where `cache` (the CPU)."""

    def __init__(self, serial: bool, block: int, cache: bool):
        from tsim import kernels as K

        self.kernel = K.step_kernel_serial if serial else K.step_kernel
        self._extra = () if serial else (block,)  # the serial kernel has no block size
        self._cache = cache
        self.cached: CachedLaunch | None = None  # None: the next step calls the kernel through Taichi

    def __call__(self, args: tuple) -> None:
        """One env step: args are `step_kernel`'s, less the block size."""
        args = args + self._extra
        # the arguments rarely change between steps (arrays are updated in place), so after the
        # first launch the same launch context is reused
        cached = self.cached
        if cached is not None and cached.matches(self.kernel, args):
            cached.launch()
        else:
            self.kernel(*args)
            self.cached = CachedLaunch.build(self.kernel, args) if self._cache else None


class SplitLaunch:
    """An env step as the SPIR-V backends' launches (tsim/backend/spirv.py: maybe several per step)."""

    def __init__(self, split, block: int, batch_tier: int):
        self._split = split  # a `tsim.backend.spirv.Launcher`, kept by the simulator (it learns `chunk`)
        self._tail = (block, batch_tier)
        self.cached = None  # no cached launch context (`KernelLaunch.cached`)

    def __call__(self, args: tuple) -> None:
        """One env step: args are `step_kernel`'s, less the block size."""
        self._split.step((*args, *self._tail))


# how a step is launched, by `tsim.backend.Arch.launch`: (serial, block, split launcher, worlds,
# lanes per world) -> a callable taking `step_kernel`'s arguments less the block size. A backend
# that launches differently adds its entry here and names it in its `Arch`. "lanes" is the lanes
# kernel (tsim/backend/lanes.py: a world on `lanes` threads of a block; GPU and Vulkan only), which no
# backend takes by default yet: `BatchSim.choose_kernel(lanes=L)` forces it
LAUNCHERS = {
    "host": lambda serial, block, split, n, lanes: KernelLaunch(serial, 1, cache=True),
    "device": lambda serial, block, split, n, lanes: KernelLaunch(serial, block, cache=False),
    "spirv": lambda serial, block, split, n, lanes: SplitLaunch(split, block, _batch_tier(n)),
    "lanes": lambda serial, block, split, n, lanes: SplitLaunch(_lanes_launcher(n, lanes), block,
                                                               _batch_tier(n)),
}


def _batch_tier(n_worlds: int) -> int:
    from tsim.backend import spirv

    return spirv.batch_tier(n_worlds)


def _lanes_launcher(n_worlds: int, lanes: int):
    from tsim.backend.lanes import LanesLauncher

    return LanesLauncher(n_worlds, lanes)


def launcher(path: str, *, serial: bool, block: int, split, n_worlds: int, lanes: int = 1):
    """The step launcher of launch path `path` (`tsim.backend.Backend.launch_path`, or the one
    `BatchSim.choose_kernel` forces); `lanes`: the lanes kernel's lanes per world."""
    return LAUNCHERS[path](serial, block, split, n_worlds, lanes)
