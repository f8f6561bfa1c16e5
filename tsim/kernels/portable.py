"""Math functions the kernels need, written from operations every Taichi backend has in f64.

Why: SPIR-V (Taichi's Vulkan and Metal backends) has 64-bit floating-point arithmetic, square
roots and `floor`, but no 64-bit transcendental functions (GLSL.std.450's Exp, Tanh, ... take 16-
and 32-bit floats only): an f64 `ti.tanh` on Vulkan stops code generation with "Instruction
Tanh(21) does not 64bits operation". And the f32 `Tanh` that SPIR-V has need not be accurate:
lavapipe's is 0.1 % off at 1e-5 and 19 % at 1e-7 (as exp-based formulas are near 0), where the
ground's friction calls it with the product of a velocity and a penetration; f32 on Vulkan then
followed evogym ~700x less closely than f32 on the CPU (Walker-v0's COM). `tanh` below keeps
Taichi's own `ti.tanh` on the CPU and CUDA, so those results are bit for bit what they were; on a
SPIR-V backend it takes the formula in both precisions, decided when a kernel is compiled. In f32
the formula is within 2 ulp of the correctly rounded tanh on the arguments of
tests/tsim/backend/test_vulkan.py (its `k * _LN2_HI` is then not exact, which matters only near 1).

The formula (within 3 units in the last place of the correctly rounded tanh over |x| < 25, 81 %
of arguments exact; tests/tsim/backend/test_vulkan.py, `test_tanh_formula_is_within_3_ulp_of_libm`):
tanh(a) = -m / (2 + m) with m = expm1(-2a), a = |x|, and expm1 by the usual reduction
y = k ln 2 + r, |r| <= ln 2 / 2, a degree-14 Taylor polynomial for expm1(r) and 2^k built by exact
repeated squaring (no 64-bit integers or ldexp needed).
"""

import math

from tsim.backend import runtime
from tsim.backend.runtime import ti

_LN2_HI = 6.93147180369123816490e-01  # ln 2 with its low 32 bits zero: k * _LN2_HI is exact
_LN2_LO = 1.90821492927058770002e-10  # ln 2 - _LN2_HI
_INV_LN2 = 1.0 / math.log(2.0)
_TANH_ONE = 22.0  # tanh(a) rounds to 1.0 in f64 for every a above ~19.06
_INV_FACT = tuple(1.0 / math.factorial(n) for n in range(15))  # 1/n!, n = 0..14


@ti.func
def expm1_neg(y):
    """exp(y) - 1 for -64 < y <= 0 from +, -, *, / and floor (accurate also where y is tiny)."""
    k = ti.cast(ti.floor(y * _INV_LN2 + 0.5), ti.i32)  # the nearest multiple of ln 2, k <= 0
    r = (y - k * _LN2_HI) - k * _LN2_LO
    q = _INV_FACT[14]
    for n in ti.static(range(13, 1, -1)):
        q = _INV_FACT[n] + r * q
    p = r + (r * r) * q  # expm1(r)
    scale = 1.0  # 2^k by squaring: every product is a power of two, so exact
    half = 0.5
    m = -k
    while m > 0:
        if m & 1:
            scale *= half
        half *= half
        m >>= 1
    return (scale - 1.0) + scale * p


@ti.func
def tanh_formula(x):
    """tanh from `expm1_neg` (see the module docstring); any backend, f64."""
    a = ti.abs(x)
    t = 1.0
    if a < _TANH_ONE:
        m = expm1_neg(-2.0 * a)
        t = -m / (2.0 + m)
    if x < 0:
        t = -t
    return t


@ti.func
def tanh(x):
    """Taichi's `ti.tanh` where the backend has it in this precision, else `tanh_formula`."""
    if ti.static(runtime.native_tanh()):
        return ti.tanh(x)
    else:
        return tanh_formula(x)
