"""What one spring evaluation costs against what the divider allows (docs/BENCHMARKS.md).

    python bench/spring_microbench.py

Times, in one Taichi CPU thread on a 5x5 body's springs held in local arrays: (0) the spring force
with the scatter to its two points in the same loop; (1) the forces alone, stored per spring;
(2) forces then scatter of both ends in a second loop (the kernel now scatters in two loops, first
ends then second ends: evogym's order); a throughput loop of independent scalar
(sqrt, div) pairs; and the same pairs in a contiguous loop that LLVM vectorises (on the
Sapphire-Rapids VM both cost ~1.5 ns per pair: vectors do not raise the divider's throughput,
which is why SIMD across worlds would not speed up the springs there). Not run by CI.
"""

import time

import numpy as np

from tsim.backend import runtime
from tsim.body import build_body
from tsim.sampling import sample_robot

runtime.init()
ti = runtime.ti
PCAP, ECAP, REPS = 64, 160, 200_000
I32 = ti.types.ndarray(dtype=ti.i32, ndim=1)
F64 = ti.types.ndarray(dtype=ti.f64, ndim=1)


def spring_kernel(mode: int):
    @ti.kernel
    def k(ea: I32, eb: I32, x0: F64, reps: ti.i32, n: ti.i32, m: ti.i32) -> ti.f64:
        ti.loop_config(serialize=True)
        out = 0.0
        for _ in range(1):
            xs = ti.Vector.zero(ti.f64, 2 * PCAP)
            frc = ti.Vector.zero(ti.f64, 2 * PCAP)
            leq = ti.Vector.zero(ti.f64, ECAP)
            kk = ti.Vector.zero(ti.f64, ECAP)
            fx = ti.Vector.zero(ti.f64, ECAP)
            fy = ti.Vector.zero(ti.f64, ECAP)
            for i in range(2 * m):
                xs[i] = x0[i] * 1.01
            for e in range(n):
                leq[e] = 0.1
                kk[e] = 3000.0
            for _r in range(reps):
                for i in range(2 * m):
                    frc[i] = 0.0
                for e in range(n):
                    a = ea[e]
                    q = eb[e]
                    dx = xs[2 * a] - xs[2 * q]
                    dy = xs[2 * a + 1] - xs[2 * q + 1]
                    dist = ti.sqrt(dx * dx + dy * dy)
                    mag = (dist - leq[e]) * kk[e] / dist
                    dx *= mag
                    dy *= mag
                    if ti.static(mode == 0):
                        frc[2 * a] -= dx
                        frc[2 * a + 1] -= dy
                        frc[2 * q] += dx
                        frc[2 * q + 1] += dy
                    else:
                        fx[e] = dx
                        fy[e] = dy
                if ti.static(mode == 2):
                    for e in range(n):
                        a = ea[e]
                        q = eb[e]
                        frc[2 * a] -= fx[e]
                        frc[2 * a + 1] -= fy[e]
                        frc[2 * q] += fx[e]
                        frc[2 * q + 1] += fy[e]
                xs[0] += (frc[0] + fx[0]) * 1e-300  # keeps every loop's result alive
            out = frc[3] + fx[3]
        return out
    return k


@ti.kernel
def divider(x: F64, y: F64, reps: ti.i32) -> ti.f64:
    ti.loop_config(serialize=True)
    s = 0.0
    n = x.shape[0]
    for _r in range(reps):
        a0 = 0.0
        a1 = 0.0
        a2 = 0.0
        a3 = 0.0
        j = 0
        for _i in range(n // 4):  # scattered addresses: no vectorisation
            a0 += ti.sqrt(x[j]) / y[j]
            a1 += ti.sqrt(x[j ^ 4096]) / y[j ^ 8192]
            a2 += ti.sqrt(x[j ^ 1024]) / y[j ^ 16384]
            a3 += ti.sqrt(x[j ^ 256]) / y[j ^ 512]
            j = (j * 5 + 4) & (n - 4)
        s += a0 + a1 + a2 + a3
    return s


@ti.kernel
def divider_vector(x: F64, y: F64, reps: ti.i32) -> ti.f64:
    ti.loop_config(serialize=True)
    s = 0.0
    for _ in range(1):
        xs = ti.Vector.zero(ti.f64, 512)
        ys = ti.Vector.zero(ti.f64, 512)
        zs = ti.Vector.zero(ti.f64, 512)
        for i in range(512):
            xs[i] = x[i]
            ys[i] = y[i]
        for _r in range(reps):
            for i in range(512):  # contiguous, no stores to shared data: vectorised
                zs[i] = ti.sqrt(xs[i]) / ys[i]
            xs[0] += zs[5] * 1e-300
        s = zs[3]
    return s


def main() -> None:
    body = build_body(sample_robot((5, 5), np.random.default_rng(0)))
    ea, eb = body.edge_a.astype(np.int32), body.edge_b.astype(np.int32)
    pts = body.place(1, 1).T.reshape(-1).astype(np.float64)
    E, P = body.n_edges, body.n_points
    names = ["force + scatter (as in the kernel)", "forces alone", "forces, then scatter"]
    for mode, name in enumerate(names):
        k = spring_kernel(mode)
        k(ea, eb, pts, 10, E, P)
        t = time.perf_counter()
        k(ea, eb, pts, REPS, E, P)
        print(f"{name:<36} {(time.perf_counter() - t) / (REPS * E) * 1e9:.2f} ns per spring")
    n = 1 << 16
    x, y = np.random.rand(n) + 1, np.random.rand(n) + 1
    divider(x, y, 1)
    t = time.perf_counter()
    divider(x, y, 200)
    print(f"{'scalar (sqrt, div) pair, throughput':<36} {(time.perf_counter() - t) / (200 * n) * 1e9:.2f} ns")
    divider_vector(x, y, 1)
    t = time.perf_counter()
    divider_vector(x, y, 100_000)
    print(f"{'vectorised (sqrt, div) pair':<36} {(time.perf_counter() - t) / (100_000 * 512) * 1e9:.2f} ns")


if __name__ == "__main__":
    main()
