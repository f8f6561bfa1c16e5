"""Taichi start-up: one `ti.init` per process, on one arch and in one real type (f64 unless f32 is
asked for), CPU unless a GPU is asked for."""

import contextlib
import io
import os
import sys
import tempfile
import threading
import time

from tsim.backend import devices
from tsim.backend import tables as B
from tsim.backend.tables import DEFAULT_ARCH, DEFAULT_PRECISION, GPU, NO_F64, SPIRV_ARCHS, resolved
from tsim.errors import SgrError

# Taichi's version banner and "Starting on arch" line are not printed: a command's stderr holds its
# warnings and its one-line errors, its stdout its output (`sgr ... --json`). TI_ENABLE_PYBUF=0
# keeps Taichi from wrapping every kernel call because stdout is redirected meanwhile (no kernel
# prints)
os.environ.setdefault("TI_ENABLE_PYBUF", "0")
os.environ.setdefault("ENABLE_TAICHI_HEADER_PRINT", "0")  # no version banner
with contextlib.redirect_stdout(sys.stderr):
    import taichi as ti


def _source_line_info(ctx, node) -> str:
    """Where a kernel's AST node is (file, line, function) and its source line: what Taichi's
    compile errors name. Taichi 1.7's own `get_pos_info` also draws caret lines through textwrap,
    for every node it builds, whether an error comes or not: ~0.4 s of each process's start (its
    kernels are transformed again to find them in the offline cache) and ~5 % of a compile."""
    line = ctx.src[node.lineno - 1] if 0 < node.lineno <= len(ctx.src) else ""
    return (f'File "{ctx.file}", line {node.lineno + ctx.lineno_offset}, in {ctx.func.func.__name__}:\n'
            f"{line}\n")


def _lighter_source_info() -> None:
    """Taichi's AST transformer given `_source_line_info`, where it has the method (Taichi 1.7)."""
    try:
        from taichi.lang.ast.ast_transformer_utils import ASTTransformerContext
    except ImportError:
        return
    if callable(getattr(ASTTransformerContext, "get_pos_info", None)):
        ASTTransformerContext.get_pos_info = _source_line_info


_lighter_source_info()

# the archs' and precisions' names: tsim/backend/__init__.py's tables own them (and what follows from each)
ARCHS = tuple(B.ARCHS)
# profiling only (bench/profile_parts.py): kernel parts left out at compile time, e.g. "pairs,terrain";
# results are then wrong, so such a process neither reads nor writes Taichi's offline cache
PROFILE_SKIP = tuple(p for p in os.environ.get("SGR_PROFILE_SKIP", "").split(",") if p)
_ARCH: str | None = None
# the real type of the kernels, numpy arrays at their boundary and the tasks' numbers: f64 is
# evogym's (bit for bit), f32 is faster and within evogym's chaos floor (docs/VALIDATION.md)
PRECISIONS = tuple(B.PRECISIONS)
_PRECISION: str | None = None
_DEVICE: tuple[str, bool] | None = None  # `device()`


def requested_precision(precision: str | None = None) -> str:
    """`precision`, else $SGR_PRECISION, else f64; raises ValueError for a name that is not one."""
    if precision is None and os.environ.get("SGR_PRECISION"):
        precision = os.environ["SGR_PRECISION"]
        if precision not in PRECISIONS:
            raise ValueError(f"SGR_PRECISION={precision}: unknown precision; use one of "
                             f"{', '.join(PRECISIONS)}")
    precision = precision or DEFAULT_PRECISION
    if precision not in PRECISIONS:
        raise ValueError(f"unknown precision {precision!r}; use one of {', '.join(PRECISIONS)}")
    return precision


def use_precision(precision: str | None) -> str:
    """Choose the precision of this process and of the processes it starts (rollout workers read
    $SGR_PRECISION): `precision`, else $SGR_PRECISION, else f64. ValueError, one line, for an
    unknown name or when Taichi already runs in another precision. For CLI flags and run configs,
    before the first simulator is built."""
    p = requested_precision(precision)
    if _PRECISION is not None and p != _PRECISION:
        raise ValueError(f"Taichi already runs in {_PRECISION}; cannot switch to {p} in one process")
    os.environ["SGR_PRECISION"] = p
    return p


def switch_problem(precision: str) -> str | None:
    """Why this process cannot simulate in `precision` (Taichi already runs in another), or None.
    Asks only: nothing is started or set."""
    if _PRECISION is not None and precision != _PRECISION:
        return f"Taichi already runs in {_PRECISION}; cannot switch to {precision} in one process"
    return None


def check_real_type(arch: str, precision: str, arch_from_env: bool = False,
                    precision_from_env: bool = False) -> None:
    """ValueError, one line saying what is missing and what to use, when `arch` has no floats of
    `precision` (Metal: no 64-bit floats). Checked once the arch is known to run here, so that a
    missing device is reported as such first."""
    if B.PRECISIONS[precision].needs_f64 and arch in NO_F64:
        what = f"SGR_ARCH={arch}" if arch_from_env else f"arch {arch!r}"
        how = "SGR_PRECISION=f64" if precision_from_env else "precision f64"
        raise ValueError(f"{what} with {how}: {arch} has no 64-bit floats; use SGR_PRECISION=f32 "
                         "(or SGR_ARCH=cpu for f64)")


def precision() -> str:
    """The process's real type, "f64" or "f32": the one Taichi runs in once started, else the one
    it would start in (`requested_precision`). What the kernels compile for."""
    return _PRECISION or requested_precision()


def started() -> bool:
    """Whether Taichi has started in this process (`init`)."""
    return _ARCH is not None


def requested_arch(arch: str | None = None) -> str:
    """`arch`, else $SGR_ARCH, else cpu; raises ValueError for a name that is not an arch."""
    if arch is None and os.environ.get("SGR_ARCH"):
        arch = os.environ["SGR_ARCH"]
        if arch not in ARCHS:
            raise SgrError(f"SGR_ARCH={arch}: unknown arch; use one of {', '.join(ARCHS)}")
    arch = arch or DEFAULT_ARCH
    if arch not in ARCHS:
        raise SgrError(f"unknown arch {arch!r}; use one of {', '.join(ARCHS)}")
    return arch


def _taichi_archs(arch: str) -> list:
    # the Taichi archs tsim/backend/__init__.py's row for `arch` tries, in order
    return [getattr(ti, name) for name in B.ARCHS[arch].taichi]


def init(arch: str | None = None, precision: str | None = None) -> str:
    """Initialise Taichi once, on `arch` in `precision` (default: $SGR_ARCH, $SGR_PRECISION, else
    cpu, f64; once started, precision None is the one it runs in); later calls with another arch
    or precision raise (Taichi cannot switch).

    An arch that Taichi cannot use here (no device, driver or backend), or that has no 64-bit
    floats for f64, raises ValueError (one line: what is missing, what to use) rather than running
    on the CPU as Taichi would."""
    global _ARCH, _PRECISION, _DEVICE
    from_env = arch is None and bool(os.environ.get("SGR_ARCH"))
    prec_from_env = precision is None and bool(os.environ.get("SGR_PRECISION"))
    arch = requested_arch(arch)
    # None: the precision the process already runs in, if started (like a kernel's real type)
    precision = requested_precision(precision) if precision is not None or _PRECISION is None \
        else _PRECISION
    if _ARCH is not None:
        if arch != _ARCH:
            raise ValueError(f"Taichi already runs on {_ARCH}; cannot switch to {arch} in one process")
        if precision != _PRECISION:
            raise ValueError(f"Taichi already runs in {_PRECISION}; cannot switch to {precision} in "
                             "one process")
        return _ARCH
    threads = _threads_env()
    kwargs = {"cpu_max_num_threads": threads} if threads else {}
    if PROFILE_SKIP:
        kwargs["offline_cache"] = False
    # fast_math off: IEEE semantics like evogym's C++ build (no reassociation), so results do not
    # depend on how a kernel is written or optimised (the parallel and serial kernels and every
    # capacity tier agree bit for bit) and the parity with evogym's traces is as good or better
    # make_cpu_multithreading_loop off: Taichi 1.7 otherwise hands each CPU thread a block of at
    # least 512 iterations, so a batch of fewer than 1,024 worlds ran on one thread only; without
    # it the worlds are dealt to the threads in blocks of `block_dim` (1 for the step kernels)
    # advanced_optimization off: Taichi's own IR optimisations took ~25 s to compile the kernels
    # (cold cache) and gave no measurable speed over LLVM's; with them off it takes ~4 s
    # log_level ERROR while Taichi probes the arch: its probe warnings (e.g. "libcuda.so lib not
    # found") and its fallback to the CPU would otherwise print before our error
    # Taichi's C++ side prints its probe errors ("RHI Error: Can not create Vulkan instance") on
    # file descriptor 2: they are held back and shown only if the arch works
    out = io.StringIO()
    with contextlib.redirect_stdout(out), _held_stderr() as held:
        ti.init(arch=_taichi_archs(arch), default_fp=getattr(ti, B.PRECISIONS[precision].taichi),
                default_ip=ti.i32, fast_math=False, advanced_optimization=False,
                make_cpu_multithreading_loop=False, log_level=ti.ERROR, **kwargs)
    ti.set_logging_level(ti.WARN)
    what = f"SGR_ARCH={arch}" if from_env else f"arch {arch!r}"
    if ti.lang.impl.current_cfg().arch not in _taichi_archs(arch):  # Taichi fell back to the CPU
        ti.reset()
        raise SgrError(f"{what}: Taichi cannot run on {arch} here: {B.ARCHS[arch].missing}; "
                       "use SGR_ARCH=cpu")
    try:
        check_real_type(arch, precision, from_env, prec_from_env)
    except ValueError:
        ti.reset()
        raise
    name, software = devices.describe(backend())
    if arch == GPU and software:  # a software device is never what a GPU is asked for
        ti.reset()
        raise SgrError(f"{what}: the only GPU here is {name.split(': ')[0]}, a software Vulkan device "
                       f"(it runs on the CPU), {SOFTWARE_SPEED}; use SGR_ARCH=cpu (or SGR_ARCH=vulkan to "
                       "run on it anyway)")
    if B.PRECISIONS[precision].needs_f64 and backend() in SPIRV_ARCHS and not _runs_f64():
        ti.reset()
        raise SgrError(f"{what}: this {backend()} device has no 64-bit floats, which sgr's f64 "
                       "physics needs; use SGR_ARCH=cpu, or SGR_PRECISION=f32")
    sys.stderr.write(held.getvalue())
    for line in out.getvalue().splitlines():
        if not line.startswith("[Taichi] Starting on arch="):
            print(line, file=sys.stderr)
    _ARCH = arch
    _PRECISION = precision
    _DEVICE = (name, software)
    if B.ARCHS[arch].host:
        pin_threads()
    return _ARCH


# what a software Vulkan device costs (docs/BENCHMARKS.md "Backends"): `SGR_ARCH=gpu` refuses one
SOFTWARE_SPEED = ("25 to 60 times slower than SGR_ARCH=cpu (sgr bench: 307 against 7,991 robot-steps/s; "
                  "85 against 5,237)")


def resolved_arch() -> str:
    """What the kernels run on once Taichi started, as an arch name: "cpu" (for x64 or arm64),
    "cuda", "vulkan" or "metal" ("gpu" resolves to one of the last three)."""
    return resolved(backend())


def device() -> tuple[str, bool]:
    """(the device's name, whether it is a software device) of the started Taichi
    (tsim/backend/devices.py): "x64: <CPU model>", the CUDA GPU's name, "<Vulkan device>: <its type>"."""
    if _DEVICE is None:
        raise RuntimeError("Taichi has not started: call tsim.backend.runtime.init() first")
    return _DEVICE


def describe() -> str:
    """One line naming the backend, its device and the precision, e.g. "backend: cpu (x64: AMD
    EPYC), f64" or "backend: vulkan (llvmpipe (LLVM 15.0.6, 128 bits): software, on the CPU),
    f32"; the first line `sgr evolve`, `sgr bench` and `sgr validate` print."""
    name, _ = device()
    asked = f"; asked for {_ARCH}" if _ARCH != resolved_arch() else ""
    return f"backend: {resolved_arch()} ({name}{asked}), {_PRECISION}"




@contextlib.contextmanager
def _held_stderr():
    """Collects what is written to file descriptor 2 meanwhile (C++ code included) into a
    StringIO, yielded; nothing is shown."""
    held = io.StringIO()
    try:
        sys.stderr.flush()
        saved = os.dup(2)
    except (OSError, ValueError):  # no real stderr (e.g. under some test runners)
        yield held
        return
    with tempfile.TemporaryFile(mode="w+b") as tmp:
        os.dup2(tmp.fileno(), 2)
        try:
            yield held
        finally:
            sys.stderr.flush()
            os.dup2(saved, 2)
            os.close(saved)
            tmp.seek(0)
            held.write(tmp.read().decode(errors="replace"))


def _runs_f64() -> bool:
    """Whether a small f64 kernel (multiply-add, square root, division) compiles and runs here:
    a SPIR-V device may lack 64-bit floats (Metal always does)."""
    try:
        with _held_stderr():
            a = ti.ndarray(ti.f64, 2)
            _f64_probe(a)
            ti.sync()
            return abs(a.to_numpy()[1] - 0.5) < 1e-12
    except Exception:  # noqa: BLE001 - Taichi raises RuntimeError or its own errors
        return False


@ti.kernel
def _f64_probe(a: ti.types.ndarray(dtype=ti.f64, ndim=1)):
    a[0] = 3.0
    a[1] = ti.sqrt(a[0] * a[0] + 7.0) / 8.0  # sqrt(16) / 8


PINNED: dict[int, int] = {}  # Taichi worker thread id -> the CPU it is pinned to
PIN_TRIES = 8  # rendezvous loops at most to single out the workers, PIN_PAUSE_S apart
PIN_PAUSE_S = 0.005  # lets another thread's burst (Taichi's, after a first launch) end
PIN_WORK = 1_000_000  # multiply-adds each worker runs after the rendezvous (~1.3 ms)
PIN_SPIN_LIMIT = 20_000_000  # spins (~0.1-0.5 s) after which a task stops waiting for the others


def backend() -> str:
    """The Taichi arch the kernels run on ("x64", "arm64", "cuda", "vulkan", "metal", ...):
    what "cpu" or "gpu" resolved to."""
    return ti.lang.impl.current_cfg().arch.name


def native_tanh() -> bool:
    """Whether the kernels use `ti.tanh` (not on SPIR-V: no f64 `tanh` there, and lavapipe's f32
    one is 0.1 % off at 1e-5 and 19 % at 1e-7, where the ground's friction reads it): read when a
    kernel is compiled (tsim/kernels/portable.py)."""
    return backend() not in SPIRV_ARCHS


def pin_threads() -> dict[int, int]:
    """Pin each of Taichi's CPU worker threads to its own CPU when they are as many as the CPUs
    this process may use (the `sgr bench` / one-process case); $SGR_PIN=0 turns it off.

    Why: Taichi's master thread wakes its workers at every launch. On the 2-vCPU VM, when the
    Python thread had just been busy (observations, rewards), Linux often woke both workers on the
    same CPU and moved one only after milliseconds: a 2-thread step kernel then took 6.5 ms
    instead of 4.8 ms (BatchEnv 18k instead of 24k robot-steps/s, docs/BENCHMARKS.md). Where the
    process has more CPUs than workers the scheduler has room and nothing is pinned.

    The workers are found by their CPU time in a parallel loop of as many tasks as workers, each
    of which waits until all have started and then does ~1 ms of work: a worker cannot take a
    second task before every task is taken, so each worker runs exactly one, however late the
    scheduler wakes it. A plain busy loop promised nothing of the kind (one worker often took
    every task) and its CPU times were added up over loops, so a burst of another thread stayed
    in the sum: in CI a process once failed all eight loops and ran unpinned. Here each try is
    judged alone and tries are PIN_PAUSE_S apart, since another thread busy at the same time
    spoils a try (Taichi runs one for a few ms after the first launch). If no try singles out
    the workers, nothing is pinned. Results do not depend on pinning (worlds are independent)."""
    if PINNED or os.environ.get("SGR_PIN", "1") == "0" or not hasattr(os, "sched_setaffinity"):
        return PINNED
    n = threads()
    try:
        cpus = sorted(os.sched_getaffinity(0))
    except OSError:
        return PINNED
    if n < 2 or n != len(cpus) or not os.path.isdir("/proc/self/task"):
        return PINNED
    arrived = ti.ndarray(ti.i32, 1)
    out = ti.ndarray(ti.f64, n)
    _rendezvous(arrived, out, 0, 0)  # compiles, and starts the pool
    me = threading.get_native_id()
    for _ in range(PIN_TRIES):
        arrived.fill(0)
        before = _thread_cpu_ns()
        _rendezvous(arrived, out, PIN_SPIN_LIMIT, PIN_WORK)
        after = _thread_cpu_ns()
        used = sorted(((after[t] - before.get(t, 0), t) for t in after if t != me), reverse=True)
        workers = used[:n]
        rest = used[n][0] if len(used) > n else 0
        if len(workers) == n and workers[-1][0] >= 4 * rest + 500_000:
            break
        time.sleep(PIN_PAUSE_S)
    else:
        return PINNED
    for (_, tid), cpu in zip(workers, cpus, strict=True):
        try:
            os.sched_setaffinity(tid, {cpu})
            PINNED[tid] = cpu
        except OSError:
            pass
    return PINNED


def _thread_cpu_ns() -> dict[int, int]:
    """CPU time (ns) of each thread of this process, from /proc/self/task/<tid>/schedstat."""
    times = {}
    for name in os.listdir("/proc/self/task"):
        try:
            with open(f"/proc/self/task/{name}/schedstat") as f:
                times[int(name)] = int(f.read().split()[0])
        except (OSError, ValueError, IndexError):
            pass
    return times


@ti.kernel
def _rendezvous(arrived: ti.types.ndarray(dtype=ti.i32, ndim=1),
                out: ti.types.ndarray(dtype=ti.f64, ndim=1), spin_limit: ti.i32, work: ti.i32):
    """len(out) parallel tasks; each counts itself in `arrived`, waits (at most `spin_limit`
    spins) until all have, then runs `work` dependent multiply-adds."""
    ti.loop_config(block_dim=1)
    for i in range(out.shape[0]):
        ti.atomic_add(arrived[0], 1)
        spins = 0
        while spins < spin_limit:
            if ti.atomic_add(arrived[0], 0) >= out.shape[0]:  # an atomic read: not hoisted
                break
            spins += 1
        x = 1.0 + i
        for _ in range(work):
            x = x * 0.999999 + 1e-7
        out[i] = x


def _threads_env() -> int | None:
    """$SGR_THREADS as a positive int, None when unset."""
    text = os.environ.get("SGR_THREADS")
    if not text:
        return None
    try:
        n = int(text)
    except ValueError:
        n = 0
    if n < 1:
        raise SgrError(f"SGR_THREADS={text}: must be a positive int")
    return n


def threads() -> int:
    """CPU threads Taichi is given: $SGR_THREADS, else the CPU count (Taichi's own default);
    ValueError when $SGR_THREADS is not a positive int."""
    return _threads_env() or os.cpu_count() or 1
