"""What a kernel launch costs per array argument: numpy arrays against Taichi ndarrays.

    python bench/launch_args_bench.py

Why `BatchSim` passes its static arrays as Taichi ndarrays: Taichi inspects and wraps every numpy
argument at each launch. One Taichi thread; the kernel itself does next to nothing.
"""

import os
import time

import numpy as np

os.environ.setdefault("SGR_THREADS", "1")

from tsim.backend import runtime  # noqa: E402

ti = runtime.ti
I2 = ti.types.ndarray(dtype=ti.i32, ndim=2)


@ti.kernel
def _six(a: I2, b: I2, c: I2, d: I2, e: I2, f: I2):
    a[0, 0] += 1


@ti.kernel
def _one(a: I2):
    a[0, 0] += 1


def _per_launch_us(fn, args, n: int = 3000) -> float:
    for _ in range(100):
        fn(*args)
    t0 = time.perf_counter()
    for _ in range(n):
        fn(*args)
    return (time.perf_counter() - t0) / n * 1e6


def main() -> None:
    runtime.init("cpu")
    arrays = [np.zeros((64, 64), np.int32) for _ in range(6)]
    owned = []
    for a in arrays:
        t = ti.ndarray(ti.i32, a.shape)
        t.from_numpy(a)
        owned.append(t)
    for name, fn, args in [("1 numpy array", _one, arrays[:1]), ("1 Taichi ndarray", _one, owned[:1]),
                           ("6 numpy arrays", _six, arrays), ("6 Taichi ndarrays", _six, owned)]:
        print(f"{name:18s} {_per_launch_us(fn, args):6.1f} us per launch")


if __name__ == "__main__":
    main()
