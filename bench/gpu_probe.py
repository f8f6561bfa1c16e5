"""A probe of today's step kernel on a GPU, in one short run (issue #48 item 5; not run by CI).

    SGR_ARCH=cuda python bench/gpu_probe.py --out DIR [--precision f32]     # <= ~5 min on a GPU
    SGR_ARCH=cpu  python bench/gpu_probe.py --quick --out /tmp/p            # the rehearsal, < 1 min

Parts, each in its own process under its own time limit (`LIMITS`; a part that runs out keeps
what it measured so far and says so), results written as they come:
- throughput (one part per body shape, 5x5 and 10x10): 1,024 bodies (`tsim.sample_robots`) tiled
  to B = 8k, 32k, 64k, 128k; physics robot-steps/s (`BatchSim.step`) at each GPU block size
  (`BatchSim.choose_kernel(gpu_block=...)`: 32, 64, 128 worlds per thread block) and lanes per
  world (`choose_kernel(lanes=L)`: 1 today's kernel; L > 1 the lanes kernel, tsim/backend/lanes.py, a
  world on one block of L threads, so measured once per batch size whatever the block size;
  skipped on a CPU, whose Taichi backend has no block barrier), and the env's (`BatchEnv.step`:
  observations, rewards, termination on the host) at the default block; the batch build per
  robot beside them.
  On CUDA, Taichi writes each compiled module's PTX (`ti.init(print_kernel_asm=True)`).
- kernels (CUDA): the step kernels' PTX loaded through libcuda (ctypes): registers, local
  (stack) bytes per thread, shared and constant bytes, ptxas' own info log (spill stores), and
  blocks, warps and occupancy per SM at each block size (cuOccupancyMaxActiveBlocksPerMultiprocessor);
  `ptxas -v` beside them where a CUDA toolkit is installed. On a CPU: "n/a (cpu)".
- parity: the GPU against this machine's CPU backend on the paper's four tasks
  (device/arch_returns.py; the whole 32 are device/gpu_check.sh's last step), and the lanes
  kernel at the largest --lanes against the CPU too (not on a CPU).
Into --out: probe.json (everything), summary.txt (the tables), part_*.json, part_*.log and, on
CUDA, ptx/ (the step kernels' PTX, gzipped).
"""

from __future__ import annotations

import argparse
import functools
import json
import os
import re
import subprocess
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

# seconds per part on a GPU (--limit NAME=S overrides; --quick divides them)
LIMITS = {"throughput_5x5": 80, "throughput_10x10": 110, "kernels": 45, "parity": 60}
BUDGET = 300  # the whole probe: a part gets its limit or what is left, whichever is less
SIZES = [8192, 32768, 65536, 131072]
BLOCKS = [32, 64, 128]
LANES = [1, 32]  # lanes per world: 1 today's kernel, 32 the lanes kernel (a warp per world)
SHAPES = ["5x5", "10x10"]
PARITY_TASKS = ["Walker-v0", "ObstacleTraverser-v1", "Climber-v2", "Thrower-v0"]
BODIES = 1024  # distinct bodies, tiled to each B
STEP_SECONDS = 0.7  # each figure times steps until this much time has passed (at least min_steps)
DEFAULT_BLOCK = 64  # tsim.kernels.GPU_BLOCK


# ------------------------------------------------------------------------------------------------ parts
def _write(path: Path, obj: dict) -> None:
    tmp = path.with_suffix(".tmp")
    tmp.write_text(json.dumps(obj, indent=1))
    tmp.replace(path)


def _shape(text: str) -> tuple[int, int]:
    h, w = text.lower().split("x")
    return int(h), int(w)


def _tiled(bodies, n: int):
    """The first n of the bodies repeated: world b runs body b % len(bodies)."""
    import numpy as np

    reps = -(-n // len(bodies))
    return np.tile(bodies, (reps, 1, 1))[:n]


def _time_steps(step, min_steps: int, seconds: float, deadline: float) -> tuple[float, int]:
    """Seconds per step of `step()`, run until `seconds` have passed (at least min_steps, fewer
    only when the part's deadline comes first); the device is synchronised before and after (a
    step with numpy arguments is synchronous today, one on device arrays need not be)."""
    import taichi as ti

    ti.sync()
    t0 = time.perf_counter()
    n = 0
    while n < min_steps or time.perf_counter() - t0 < seconds:
        step()
        n += 1
        if time.perf_counter() > deadline:
            break
    ti.sync()
    return (time.perf_counter() - t0) / n, n


def _physics_step(sim, acts: list, t: list) -> None:
    sim.set_actions(acts[t[0] % len(acts)])
    sim.step()
    t[0] += 1


def _env_step(env, acts: list, t: list) -> None:
    env.step(acts[t[0] % len(acts)])
    t[0] += 1


def _measure_size(args, rec: dict, path: Path, bodies, B: int, blocks: list, cpu: bool, takes_lanes: bool,
                  deadline: float) -> None:
    """The rows of batch size B: the bodies tiled to B, physics at each block size and lane count,
    the env at the default block."""
    import numpy as np

    from tasks.bench import sinusoid
    from tasks.env import BatchEnv

    t0 = time.perf_counter()
    env = BatchEnv("Walker-v0", _tiled(bodies, B), episode_steps=10_000)
    build = time.perf_counter() - t0
    A = env.sim.max_actuators
    acts = [np.repeat(sinusoid(t, A)[None, :], B, 0) for t in range(20)]
    sim = env.sim
    for block in blocks:
        for lanes in args.lanes:
            row = {"B": B, "block": "1 (cpu)" if cpu else block, "lanes": lanes,
                   "build_us_per_robot": 1e6 * build / B}
            if lanes != 1 and not takes_lanes:
                row["skipped"] = "no lanes kernel in this tree (#48 item 1)"
                rec["rows"].append(row)
                continue
            if lanes != 1 and cpu:
                row["skipped"] = "the lanes kernel runs on a GPU or Vulkan only (no block barrier on a CPU)"
                rec["rows"].append(row)
                continue
            if lanes != 1 and block != blocks[0]:
                continue  # one world per block of `lanes` threads: the block size does not apply
            if lanes != 1:
                row["block"] = f"{lanes} thr"
            if time.perf_counter() > deadline:
                row["skipped"] = "out of time"
                rec["rows"].append(row)
                continue
            kw = {} if cpu else {"gpu_block": block}
            if takes_lanes:
                kw["lanes"] = lanes
            sim.choose_kernel(**kw)
            env.reset()
            t = [0]
            physics = functools.partial(_physics_step, sim, acts, t)
            ptx = os.environ.get("SGR_ARCH") == "cuda"  # the cwd is the part's PTX folder
            before = set(os.listdir()) if ptx else set()
            t1 = time.perf_counter()
            physics()  # compiles this variant (or loads it from Taichi's cache)
            row["first_step_s"] = time.perf_counter() - t1
            if ptx:  # the PTX modules this variant's first step compiled
                row["ptx"] = sorted(set(os.listdir()) - before)
            s, n = _time_steps(physics, args.min_steps, args.step_seconds, deadline)
            row.update(physics_robot_steps_per_s=B / s, physics_steps_timed=n)
            if (cpu or block == DEFAULT_BLOCK) and lanes == 1 and time.perf_counter() < deadline:
                env.reset()
                s, n = _time_steps(functools.partial(_env_step, env, acts, t), args.min_steps,
                                   args.step_seconds, deadline)
                row.update(env_robot_steps_per_s=B / s, env_steps_timed=n)
            rec["rows"].append(row)
            _write(path, rec)


def part_throughput(args, out: Path) -> dict:
    """Physics and env robot-steps/s of tiled batches at each size, block size and lane count."""
    import inspect

    import numpy as np

    if os.environ.get("SGR_ARCH", "cpu") == "cuda":  # Taichi writes each module's PTX to the cwd
        import taichi as ti

        ptx = out / "ptx" / args.part
        ptx.mkdir(parents=True, exist_ok=True)
        os.chdir(ptx)
        ti.init = functools.partial(ti.init, print_kernel_asm=True)
    from tsim.backend import runtime
    from tsim.sampling import sample_robots
    from tsim.sim import BatchSim

    runtime.init()
    deadline = time.perf_counter() + args.limit - 5
    cpu = runtime.resolved_arch() == "cpu"
    takes_lanes = "lanes" in inspect.signature(BatchSim.choose_kernel).parameters
    shape = _shape(args.part.split("_", 1)[1])
    rec: dict = {"part": args.part, "shape": list(shape), "device": runtime.describe(),
                 "threads": runtime.threads(), "precision": runtime.precision(), "rows": [],
                 "skipped": []}
    path = out / f"part_{args.part}.json"
    t0 = time.perf_counter()
    bodies = sample_robots(BODIES if not args.quick else min(BODIES, max(args.sizes)), shape,
                           np.random.default_rng(0))
    rec["sample_us_per_robot"] = 1e6 * (time.perf_counter() - t0) / len(bodies)
    blocks = [1] if cpu else sorted(args.blocks, key=lambda b: b != DEFAULT_BLOCK)  # the default first
    for B in args.sizes:
        if time.perf_counter() > deadline:
            rec["skipped"].append(f"B={B}: out of time")
            continue
        try:
            _measure_size(args, rec, path, bodies, B, blocks, cpu, takes_lanes, deadline)
        except Exception as e:  # noqa: BLE001 -- e.g. a batch that does not fit: the next size still runs
            rec["skipped"].append(f"B={B}: {type(e).__name__}: {str(e)[:300]}")
            _write(path, rec)
    rec["done"] = True
    _write(path, rec)
    if os.environ.get("SGR_ARCH") == "cuda":
        _keep_step_ptx(out / "ptx" / args.part)
    return rec


def _keep_step_ptx(folder: Path) -> None:
    """Keep (gzipped) only the PTX modules that hold a step kernel."""
    import gzip

    for f in sorted(folder.glob("*.ptx")):
        text = f.read_text(errors="replace")
        if "step_kernel" in text or "lanes_kernel" in text:
            with gzip.open(f.with_suffix(".ptx.gz"), "wt") as g:
                g.write(text)
        f.unlink()


def _ptx_blocks(out: Path) -> dict[str, int]:
    """"<part>/<file>.ptx.gz" -> the block size whose first step compiled it (the throughput parts
    list the files each variant's first step wrote)."""
    blocks = {}
    for part in sorted(out.glob("part_throughput_*.json")):
        for row in json.loads(part.read_text()).get("rows", []):
            for name in row.get("ptx", []):
                blocks[f"{part.stem[5:]}/{name}.gz"] = row["block"]
    return blocks


def _cuda():
    """libcuda's functions by name (the _v2 ones where they exist), or None without libcuda."""
    import ctypes

    try:
        lib = ctypes.CDLL("libcuda.so.1")
    except OSError:
        return None

    def fn(name):
        for n in (name + "_v2", name):
            if hasattr(lib, n):
                return getattr(lib, n)
        raise AttributeError(name)

    def call(name, *a):
        rc = fn(name)(*a)
        if rc != 0:
            raise RuntimeError(f"{name} failed: CUDA error {rc}")
    return call


def part_kernels(args, out: Path) -> dict:
    """Registers, local bytes and occupancy of the step kernels the throughput parts compiled."""
    path = out / "part_kernels.json"
    if os.environ.get("SGR_ARCH", "cpu") == "cpu":
        rec = {"part": "kernels", "kernels": "n/a (cpu)"}
        _write(path, rec)
        return rec
    call = _cuda()
    rec: dict = {"part": "kernels", "kernels": [], "errors": []}
    if call is None:
        rec["kernels"] = "n/a (no libcuda.so.1)"
        _write(path, rec)
        return rec
    try:
        _kernel_attributes(call, args, out, rec)
    except Exception as e:  # noqa: BLE001 -- what failed goes into the record, the probe goes on
        rec["errors"].append(f"{type(e).__name__}: {e}")
    _write(path, rec)
    return rec


def _kernel_attributes(call, args, out: Path, rec: dict) -> None:
    import ctypes
    import gzip
    import shutil

    path = out / "part_kernels.json"
    c_int = ctypes.c_int
    call("cuInit", 0)
    dev = c_int()
    call("cuDeviceGet", ctypes.byref(dev), 0)
    name = ctypes.create_string_buffer(256)
    call("cuDeviceGetName", name, 256, dev)

    def dattr(a: int) -> int:
        v = c_int()
        call("cuDeviceGetAttribute", ctypes.byref(v), a, dev)
        return v.value
    d = {"name": name.value.decode(), "sms": dattr(16), "cc": f"{dattr(75)}.{dattr(76)}",
         "max_threads_per_sm": dattr(39), "regs_per_sm": dattr(82), "smem_per_sm": dattr(81),
         "l2_bytes": dattr(38)}
    rec["device"] = d
    ctx = ctypes.c_void_p()
    call("cuDevicePrimaryCtxRetain", ctypes.byref(ctx), dev)
    call("cuCtxPushCurrent", ctx)
    ptxas = shutil.which("ptxas")
    deadline = time.perf_counter() + args.limit - 5
    for folder in sorted((out / "ptx").glob("*")):  # a part cut short left its PTX as it was written
        _keep_step_ptx(folder)
    compiled_for = _ptx_blocks(out)
    files = sorted((out / "ptx").glob("*/*.ptx.gz"),  # the default block size's first
                   key=lambda f: (compiled_for.get(f"{f.parent.name}/{f.name}") != DEFAULT_BLOCK, str(f)))
    for f in files:
        if time.perf_counter() > deadline:
            rec["errors"].append(f"{f.parent.name}/{f.name}: not loaded, out of time")
            continue
        text = gzip.open(f, "rt").read()
        entries = [e for e in re.findall(r"\.entry\s+([\w.$]+)\s*\(", text)
                   if "step_kernel" in e or "lanes_kernel" in e]
        log = ctypes.create_string_buffer(1 << 16)
        opts = (c_int * 3)(3, 4, 12)  # CU_JIT_INFO_LOG_BUFFER, ..._SIZE_BYTES, CU_JIT_LOG_VERBOSE
        vals = (ctypes.c_void_p * 3)(ctypes.cast(log, ctypes.c_void_p), ctypes.c_void_p(1 << 16),
                                     ctypes.c_void_p(1))
        mod = ctypes.c_void_p()
        src = ctypes.create_string_buffer(text.encode())
        try:
            call("cuModuleLoadDataEx", ctypes.byref(mod), src, 3, opts, vals)
        except RuntimeError as e:
            rec["errors"].append(f"{f.name}: {e}")
            continue
        info = log.value.decode(errors="replace")
        for e in entries:
            func = ctypes.c_void_p()
            call("cuModuleGetFunction", ctypes.byref(func), mod, e.encode())

            fa = {}
            for key, a in (("registers", 4), ("local_bytes", 3), ("shared_bytes", 1), ("const_bytes", 2),
                           ("max_threads_per_block", 0)):  # CU_FUNC_ATTRIBUTE_*
                v = c_int()
                call("cuFuncGetAttribute", ctypes.byref(v), a, func)
                fa[key] = v.value
            k = {"module": f"{f.parent.name}/{f.name}", "entry": e, **fa, "occupancy": {},
                 "compiled_for_block": compiled_for.get(f"{f.parent.name}/{f.name}"),
                 "ptxas_info": [ln for ln in info.splitlines() if e in ln or "spill" in ln
                                or "registers" in ln][:8]}
            for block in sorted(set(args.blocks) | {x for x in args.lanes if x > 1}):
                n = c_int()
                if block <= k["max_threads_per_block"]:
                    call("cuOccupancyMaxActiveBlocksPerMultiprocessor", ctypes.byref(n), func, block,
                         ctypes.c_size_t(0))
                warps = n.value * block // 32
                k["occupancy"][str(block)] = {
                    "blocks_per_sm": n.value, "warps_per_sm": warps,
                    "occupancy": warps / (d["max_threads_per_sm"] // 32),
                    "resident_worlds": n.value * block * d["sms"]}
            rec["kernels"].append(k)
        call("cuModuleUnload", mod)
        if ptxas and time.perf_counter() < deadline:
            plain = f.with_suffix("")
            plain.write_text(text)
            try:
                r = subprocess.run([ptxas, "-v", f"--gpu-name=sm_{d['cc'].replace('.', '')}", str(plain),
                                    "-o", os.devnull], capture_output=True, text=True,
                                   timeout=max(1.0, deadline - time.perf_counter()))
                said = (r.stdout + r.stderr)[-4000:]
            except subprocess.TimeoutExpired:
                said = "ptxas ran out of the part's time"
            plain.unlink()
            rec.setdefault("ptxas_v", {})[f"{f.parent.name}/{f.name}"] = said
        _write(path, rec)
    if not files:
        rec["errors"].append("no step kernel PTX under ptx/ (did a throughput part run?)")
    if ptxas is None:
        rec["ptxas_v"] = "n/a (no ptxas here)"
    call("cuCtxPopCurrent", ctypes.byref(ctypes.c_void_p()))


def part_parity(args, out: Path) -> dict:
    """device/arch_returns.py on this arch and on the CPU at once, then compared."""
    import importlib.util

    spec = importlib.util.spec_from_file_location("arch_returns", ROOT / "device" / "arch_returns.py")
    ar = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(ar)
    base = [sys.executable, str(ROOT / "device" / "arch_returns.py"), "--robots", str(args.parity_robots),
            "--steps", str(args.parity_steps), "--tasks", *args.parity_tasks]
    arch = os.environ.get("SGR_ARCH", "cpu")
    runs = [("arch", arch, []), ("cpu", "cpu", [])]
    lanes = max(args.lanes)
    if arch != "cpu" and lanes > 1:
        runs.append(("lanes", arch, ["--lanes", str(lanes)]))
    procs = {}
    for name, a, extra in runs:
        env = {**os.environ, "SGR_ARCH": a}
        procs[name] = subprocess.Popen([*base, *extra, "--out", str(out / f"parity_{name}.json")], env=env,
                                       stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
    rec: dict = {"part": "parity", "tasks": args.parity_tasks, "robots": args.parity_robots,
                 "steps": args.parity_steps}
    for name, p in procs.items():
        try:
            o, _ = p.communicate(timeout=max(1.0, args.limit - 5))
        except subprocess.TimeoutExpired:
            p.kill()
            o, _ = p.communicate()
        rec[f"{name}_rc"] = p.returncode
        rec[f"{name}_log"] = (o or "")[-2000:]
    try:
        a, b = (json.loads((out / f"parity_{n}.json").read_text()) for n in ("cpu", "arch"))
    except (OSError, ValueError) as e:
        rec["lines"], rec["failures"] = [], [f"no parity record: {e}"]
    else:
        tol = 1e-3 if os.environ.get("SGR_PRECISION") == "f32" else 1e-6
        rec["lines"], rec["failures"] = ar.compare(a, b, tol)
        rec["bits_identical"] = all(a["tasks"][t]["returns"] == b["tasks"][t]["returns"]
                                    and a["tasks"][t]["final_x"] == b["tasks"][t]["final_x"]
                                    for t in a["tasks"] if t in b["tasks"])
        rec["tol"] = tol
        if "lanes" in procs:  # the lanes kernel against the CPU as well
            try:
                c = json.loads((out / "parity_lanes.json").read_text())
            except (OSError, ValueError) as e:
                rec["lanes_lines"], rec["lanes_failures"] = [], [f"no lanes parity record: {e}"]
            else:
                rec["lanes"] = lanes
                rec["lanes_lines"], rec["lanes_failures"] = ar.compare(a, c, tol)
    _write(out / "part_parity.json", rec)
    return rec


PARTS = {"throughput": part_throughput, "kernels": part_kernels, "parity": part_parity}


# ------------------------------------------------------------------------------------------------ driver
def summary(probe: dict) -> str:
    """The tables of probe.json as text."""
    lines = [f"gpu_probe: {probe['arch']} {probe['precision']}, {probe['wall_s']:.0f} s, "
             f"commit {probe['commit']}; {probe.get('device', '?')}"]
    for name, p in probe["parts"].items():
        if not name.startswith("throughput"):
            continue
        us = p.get("sample_us_per_robot", float("nan"))
        lines.append(f"\n{name}: {p.get('status')}; sampling {us:.1f} us/robot")
        lines.append(f"{'B':>7} {'block':>7} {'lanes':>5} {'build us/rb':>11} {'first s':>8} "
                     f"{'physics rs/s':>13} {'env rs/s':>11} {'env/phys':>8}")
        for r in p.get("rows", []):
            if "skipped" in r:
                lines.append(f"{r['B']:>7} {r['block']!s:>7} {r['lanes']:>5}   skipped: {r['skipped']}")
                continue
            ph, en = r.get("physics_robot_steps_per_s"), r.get("env_robot_steps_per_s")
            lines.append(f"{r['B']:>7} {r['block']!s:>7} {r['lanes']:>5} {r['build_us_per_robot']:>11.1f} "
                         f"{r.get('first_step_s', 0):>8.2f} {ph or 0:>13,.0f} "
                         f"{(f'{en:,.0f}' if en else '-'):>11} {(f'{en / ph:.2f}' if en and ph else '-'):>8}")
        for s in p.get("skipped", []):
            lines.append(f"  skipped {s}")
    k = probe["parts"].get("kernels", {})
    if k:
        lines.append(f"\nkernels: {k.get('status')}")
    if not k:
        pass
    elif isinstance(k.get("kernels"), str):
        lines.append(f"  {k['kernels']}")
    else:
        d = k.get("device", {})
        if d:
            lines.append(f"  {d['name']} (cc {d['cc']}): {d['sms']} SMs, {d['max_threads_per_sm']} threads "
                         f"and {d['regs_per_sm']} registers per SM, L2 {d['l2_bytes'] / 2**20:.0f} MiB")
        shown = [x for x in k.get("kernels", []) if "range_for" in x["entry"]] or k.get("kernels", [])
        for x in shown:  # the worlds' loop (the serial task beside it only stores the loop bound)
            occ = ", ".join(f"block {b}: {o['blocks_per_sm']} blocks/{o['warps_per_sm']} warps per SM "
                            f"({100 * o['occupancy']:.0f} %)" for b, o in x["occupancy"].items())
            lines.append(f"  {x['module']} (block {x.get('compiled_for_block')}) {x['entry']}: "
                         f"{x['registers']} registers, {x['local_bytes']:,} local bytes/thread, "
                         f"{x['shared_bytes']} shared; {occ}")
            for ln in x.get("ptxas_info", []):
                lines.append(f"    {ln.strip()}")
        for e in k.get("errors", []):
            lines.append(f"  error: {e}")
    q = probe["parts"].get("parity", {})
    if not q:
        return "\n".join(lines) + "\n"
    if str(q.get("status", "")).startswith("skipped"):
        return "\n".join([*lines, f"\nparity: {q['status']}"]) + "\n"
    lines.append(f"\nparity ({probe['arch']} against cpu, {q.get('robots')} robots x {q.get('steps')} steps, "
                 f"tol {q.get('tol')}): {q.get('status')}")
    lines += [f"  {ln}" for ln in q.get("lines", [])]
    if "bits_identical" in q:
        lines.append(f"  bits: {'identical' if q['bits_identical'] else 'not identical'}")
    lines += [f"  FAILED: {f}" for f in q.get("failures", [])]
    if "lanes_lines" in q:
        lines.append(f"  the lanes kernel ({q.get('lanes')} lanes) against cpu:")
        lines += [f"    {ln}" for ln in q["lanes_lines"]]
        lines += [f"    FAILED: {f}" for f in q.get("lanes_failures", [])]
    return "\n".join(lines) + "\n"


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", required=True, help="folder for probe.json, summary.txt and the parts' files")
    ap.add_argument("--precision", choices=["f64", "f32"],
                    help="real type (default $SGR_PRECISION, else f64)")
    ap.add_argument("--quick", action="store_true",
                    help="the CPU rehearsal: B = 64, 128, short timings, one parity task")
    ap.add_argument("--sizes", type=int, nargs="+", help=f"batch sizes (default {SIZES})")
    ap.add_argument("--blocks", type=int, nargs="+", default=BLOCKS, help="GPU worlds per thread block")
    ap.add_argument("--lanes", type=int, nargs="+", default=LANES,
                    help=f"lanes per world (default {LANES}; 1: today's kernel, > 1: the lanes kernel)")
    ap.add_argument("--shapes", nargs="+", default=SHAPES, choices=SHAPES)
    ap.add_argument("--parts", nargs="+", default=["throughput", "kernels", "parity"], choices=list(PARTS))
    ap.add_argument("--limit", action="append", default=[], metavar="PART=S",
                    help=f"a part's time limit in seconds (defaults {LIMITS})")
    ap.add_argument("--budget", type=float, help=f"seconds for all parts together (default {BUDGET}; "
                    "--quick: a third)")
    ap.add_argument("--part", help=argparse.SUPPRESS)
    ap.add_argument("--part-limit", type=float, dest="part_limit", help=argparse.SUPPRESS)
    args = ap.parse_args()
    out = Path(args.out).resolve()
    out.mkdir(parents=True, exist_ok=True)
    if args.precision:
        os.environ["SGR_PRECISION"] = args.precision
    args.sizes = args.sizes or ([64, 128] if args.quick else SIZES)
    args.min_steps = 1 if args.quick else 2
    args.step_seconds = 0.2 if args.quick else STEP_SECONDS
    args.parity_tasks = PARITY_TASKS[:1] if args.quick else PARITY_TASKS
    args.parity_robots = 4 if args.quick else 16
    args.parity_steps = 20 if args.quick else 100
    if args.part:  # one part, in this process
        args.limit = args.part_limit
        PARTS[args.part.split("_")[0]](args, out)
        return 0

    limits = {k: v / (3 if args.quick else 1) for k, v in LIMITS.items()}
    for item in args.limit:
        k, _, v = item.partition("=")
        limits[k] = float(v)
    arch = os.environ.get("SGR_ARCH", "cpu")
    commit = subprocess.run(["git", "rev-parse", "--short", "HEAD"], capture_output=True, text=True,
                            cwd=ROOT).stdout.strip() or "?"
    names = [f"throughput_{s}" for s in args.shapes] if "throughput" in args.parts else []
    names += [p for p in ("kernels", "parity") if p in args.parts]
    t_start = time.perf_counter()
    probe: dict = {"arch": arch, "precision": os.environ.get("SGR_PRECISION", "f64"), "commit": commit,
                   "budget_s": args.budget or BUDGET / (3 if args.quick else 1),
                   "args": {k: v for k, v in vars(args).items() if k not in ("part", "limit", "part_limit")},
                   "limits": limits, "parts": {}}
    budget = args.budget or BUDGET / (3 if args.quick else 1)
    for name in names:
        limit = min(limits[name], budget - (time.perf_counter() - t_start) - 12)
        if limit < 5:
            probe["parts"][name] = {"status": "skipped: the probe's budget is spent", "s": 0.0}
            print(f"gpu_probe: {name}: skipped, the probe's {budget:.0f} s are spent", flush=True)
            continue
        cmd = [sys.executable, str(Path(__file__).resolve()), "--out", str(out), "--part", name,
               "--part-limit", str(limit), "--blocks", *map(str, args.blocks),
               "--lanes", *map(str, args.lanes), "--sizes", *map(str, args.sizes),
               *(["--quick"] if args.quick else [])]
        t0 = time.perf_counter()
        with open(out / f"part_{name}.log", "w") as log:
            try:
                rc = subprocess.run(cmd, stdout=log, stderr=subprocess.STDOUT, timeout=limit + 10,
                                    cwd=ROOT).returncode
                status = "ok" if rc == 0 else f"failed (exit {rc}; see part_{name}.log)"
            except subprocess.TimeoutExpired:
                status = f"ran out of its {limit:.0f} s (partial)"
        f = out / f"part_{name}.json"
        rec = json.loads(f.read_text()) if f.exists() else {}
        if status == "ok" and name.startswith("throughput") and not rec.get("done"):
            status = "stopped at its time limit (partial)"
        if rec.get("skipped") or any("skipped" in r for r in rec.get("rows", [])):
            status += "; some figures skipped"
        rec.update(status=status, s=round(time.perf_counter() - t0, 1))
        probe["parts"][name] = rec
        probe.setdefault("device", rec.get("device"))
        print(f"gpu_probe: {name}: {status} ({rec['s']} s)", flush=True)
    probe["wall_s"] = time.perf_counter() - t_start
    _write(out / "probe.json", probe)
    text = summary(probe)
    (out / "summary.txt").write_text(text)
    print(text, end="")
    return 0


if __name__ == "__main__":
    sys.exit(main())
