"""f32 positions and velocities as unevaluated sums hi + lo of two float32 numbers (f32 only).

Why: float32 rounds a coordinate at ~6e-8 relative, 4.8e-7 at x = 5. A substep adds v dt (~1e-5)
to it and loses that rounding each time, and a spring of stiffness ~5e7 turns a length rounded at
4.8e-7 into ~25 force units of noise, more than a 1e-6 action change makes (~5). So in f32 the
state's column holds hi = the position rounded to float32 (what contacts, observations and the COM
read) and a local `lo` holds the remainder, into which the RK4 increments and the constraints'
corrections add; a spring's length comes from (hi_a - hi_b) + (lo_a - lo_b), where hi_a - hi_b is
exact for nearby points (Sterbenz), so its rounding is that of the length, not of the coordinate.
Velocities are kept the same way (their increments are small against them too). f64 compiles
without any of it (`layout.pairs`), so its bits are evogym's as before. Needs IEEE arithmetic
without reassociation, which `runtime.init` asks for (fast_math off).
"""

from tsim.backend.runtime import ti


def given(x: object) -> bool:
    """Whether an optional compile-time argument was given (Taichi's scope has no `is None`)."""
    return x is not None


@ti.func
def renormalize(hi: ti.template(), lo: ti.template(), i, one: ti.template()):
    """(hi[i], lo[i]) <- the same sum with hi[i] its float32 rounding, lo[i] the exact rest
    (Knuth's two-sum: exact whichever part is larger).

    `one`: None on the CPU; on SPIR-V an array whose one[0] holds 1.0, read at run time. A Vulkan
    driver may simplify float arithmetic as if it were exact (SPIR-V's operations are not exact
    unless decorated, and Taichi does not decorate them): lavapipe turns (a + b) - a into b, so
    the two-sum's rest came out 0 and f32 on Vulkan ran without its pairs (measured; tests/tsim/
    test_vulkan.py). Multiplying by a 1.0 that the compiler cannot see changes no value and hides
    the sum from such rewrites."""
    a = hi[i]
    b = lo[i]
    s = a + b
    if ti.static(given(one)):
        s = s * one[0]
    bb = s - a
    if ti.static(given(one)):
        bb = bb * one[0]
    r = (a - (s - bb)) + (b - bb)
    # the rest on float64's grid, so that hi + lo is float64's sum: evogym's float64 sum drops an
    # increment below half of its spacing (a point at x = 0.5 that float64 holds still to the bit,
    # where the pair kept 3e-21 and put it 3e-21 off a terrain voxel's side, out of a contact
    # evogym makes: Climber-v0). float64's spacing at s is u = float32's times 2^-29, or u / 2
    # when s is a power of two and r takes the sum below it. With m = 2^23 u carrying r's sign,
    # r + m lies in [2^23 u, 2^24 u], where float32's spacing is u: r + m - m is r rounded to a
    # multiple of u, ties to even as float64's. A rest of 2^23 u or more is a multiple of u already
    # (its own spacing is u or more). Exponents <= 29 (|s| < 2^-97): left as they are.
    bits = ti.bit_cast(s, ti.i32)
    k = ((bits >> 23) & 0xFF) - 29  # the biased exponent of 2^23 u
    if (bits & 0x7FFFFF) == 0 and r != 0.0 and (r < 0.0) != (bits < 0):
        k -= 1
    if k > 0:
        m = ti.bit_cast(k << 23, ti.f32)
        if ti.abs(r) < m:
            if r < 0.0:
                m = -m
            t = r + m
            if ti.static(given(one)):
                t = t * one[0]
            r = t - m
    lo[i] = r
    hi[i] = s
