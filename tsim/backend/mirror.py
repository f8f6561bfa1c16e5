"""An array the kernels step on the device and the host reads, copied across only when needed.

On a GPU (or Vulkan) a numpy array passed to a Taichi kernel crosses the bus at every launch: in
before the kernel, out after it. For the state, (B, P, columns) reals (2.3 KB a world at 5x5 in
f64, 150 MB at B = 65,536), that is every env step's largest cost outside the physics, and an
env step is 1 launch on CUDA and 3 or more on Vulkan (`tsim.backend.spirv`). A `DeviceMirror` keeps the
array in a Taichi ndarray between steps and a numpy copy on the host, and copies one to the other
only when the other side reads it after this side was written: a run whose host reads nothing
but the kernels' outputs never moves the state at all.

On the CPU the kernels take the numpy array itself (`HostArray`): nothing is copied, and a cached
launch (`tsim.backend.launch`) keeps its address.

The rule for callers: ask for the host array with `host(write=True)` if you may write it (the
next launch then copies it in), with `host()` to read only. A reference kept across a launch (any
`device()` call, reading or writing) sees neither the kernels' later writes nor, written after it,
reaches them (`BatchSim.state` says so too). On the CPU such a reference happens to work, so
`SGR_DEVICE_MIRROR=1` makes the CPU use a `DeviceMirror` too (over the CPU's Taichi ndarrays): a
test run under it catches code that relies on one.
"""

from __future__ import annotations

import os

import numpy as np

from tsim.backend.runtime import ti


class HostArray:
    """The CPU's case: one numpy array that both the host and the kernels use."""

    on_device = False  # the kernels step the host array itself

    def __init__(self, host: np.ndarray):
        self._host = host
        self._flat = host.reshape(-1)  # a view: the kernels write the host array in place
        self.shape = host.shape

    def host(self, write: bool = False, keep: bool = True) -> np.ndarray:
        """The host array (`write`, `keep`: see `DeviceMirror.host`; nothing to do here)."""
        return self._host

    def device(self, write: bool = True) -> np.ndarray:
        """The flat array the kernels take: the same object at every call."""
        return self._flat

    def assign(self, value: np.ndarray) -> None:
        """Copy `value` into the array (its shape; cast to its type)."""
        np.copyto(self._host, value, casting="unsafe")


class DeviceMirror:
    """A device backend's case: a flat Taichi ndarray the kernels step, and its numpy mirror.

    `_device_newer`: a kernel wrote the device array since the host's copy was made;
    `_host_newer`: the host array may have been written since the device's copy was made. Never
    both: each side is brought up to date before the other is handed out for writing."""

    on_device = True  # the kernels step `device()`'s array, which a kernel may also write

    def __init__(self, host: np.ndarray):
        self._host = host
        self._flat = host.reshape(-1)
        self._device = ti.ndarray(_taichi_type(host.dtype), self._flat.shape[0])
        self.shape = host.shape
        self._device_newer = False
        self._host_newer = True  # the device array is not written yet

    def host(self, write: bool = False, keep: bool = True) -> np.ndarray:
        """The host array, brought up to date from the device if a kernel wrote since. `write`:
        the caller may write it, so the next `device` call copies it in. `keep=False` (with
        `write`): the caller overwrites all of it, so the device's values need not come back."""
        if self._device_newer:
            if keep or not write:
                self._flat[:] = self._device.to_numpy()
            self._device_newer = False
        if write:
            self._host_newer = True
        return self._host

    def device(self, write: bool = True) -> object:
        """The device array, brought up to date from the host if it was written since. `write`:
        the kernel it is passed to may write it, so the next `host` call copies it out."""
        if self._host_newer:
            self._device.from_numpy(self._flat)
            self._host_newer = False
        if write:
            self._device_newer = True
        return self._device

    def assign(self, value: np.ndarray) -> None:
        """Copy `value` into the array (its shape; cast to its type). A `value` that views the host
        array itself reads what the host array holds after the device's newer values came back,
        as on the host, where such a view sees every launch."""
        keep = np.may_share_memory(value, self._host)
        np.copyto(self.host(write=True, keep=keep), value, casting="unsafe")


def mirror(host: np.ndarray, on_host: bool) -> HostArray | DeviceMirror:
    """The array's `HostArray` when the kernels run on the host's cores (unless
    SGR_DEVICE_MIRROR=1, a testing aid: see above), else its `DeviceMirror`."""
    if on_host and os.environ.get("SGR_DEVICE_MIRROR") != "1":
        return HostArray(host)
    return DeviceMirror(host)


def constant(a: np.ndarray, on_host: bool):
    """An array no kernel writes, as kernels take it: on the host the contiguous numpy array, on a
    device a Taichi ndarray copied there once (a numpy argument would cross at every launch)."""
    a = np.ascontiguousarray(a)
    if on_host:
        return a
    t = ti.ndarray(_taichi_type(a.dtype), a.shape)
    t.from_numpy(a)
    return t


def _taichi_type(dtype: np.dtype):
    return {np.dtype(np.float64): ti.f64, np.dtype(np.float32): ti.f32,
            np.dtype(np.int32): ti.i32}[np.dtype(dtype)]
