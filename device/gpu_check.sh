#!/usr/bin/env bash
# GPU readiness in one command on a bare GPU machine (Python 3.12, no network, no taichi): not run
# by CI, whose machines have no GPU. From the repository root, with device-wheels/ beside it
# (bash device/device_wheels.sh, here, before sending the tree):
#   bash device/gpu_check.sh
# 1. installs the carried wheels offline (pip --no-index --target) and puts them and the project on
#    PYTHONPATH: nothing is built, nothing downloaded;
# 2. `sgr bench` on Walker-v0 at B = 1024, 8192 and 32768 (robot-steps/s), each under BENCH_LIMIT
#    seconds (a size that runs out is said in the summary, not failed);
# 2b. bench/gpu_probe.py (PROBE=0 skips it): throughput by B / block size / lanes at 5x5 and
#    10x10, registers, local bytes and occupancy of the step kernel, a 4-task parity table; under
#    PROBE_LIMIT (330 s) per precision in PROBE_PRECISIONS (default f64), each part under its own
#    limit; its files in $OUT/probe_<precision>/;
# 2c. bench/device_state_bench.py at B = STATE_B (8192): the state kept on the device between env
#    steps against numpy through every launch (STATE=0 skips it; ~1 min);
# 2d. with GENERATION_POPS="1024 4096": bench/generation_breakdown.py, an honest SGR generation's
#    time by part at each population (off by default; in a call of its own it is simply
#    `SGR_ARCH=cuda python bench/generation_breakdown.py --pop 1024 --generations 1 --json F`);
# 3. the GPU against evogym's recorded data that travelled (`sgr validate` of each folder under
#    tests/data that holds it), beside the CPU's figures; fails when a task's median |return -
#    evogym| exceeds 1e-9 on the GPU;
# 4. the GPU against this machine's own CPU backend on all 32 tasks, in f64 and f32 (f32 skipped
#    where SGR_PRECISION does not exist yet) (device/arch_returns.py: random 5x5 robots, open-loop
#    actions; fails when a task's median |return difference| exceeds F64_TOL=1e-6 / F32_TOL=1e-3,
#    and says whether f64's bits matched: CUDA may fuse multiply-adds, see below). It comes last:
#    on the H200 (2026-12-04) its f64 half took ~8 of a call's 9 minutes (CUDA compiles each
#    task's kernels afresh), so a call cut short still brings back 2 and 3.
#    With the probe (2b, ~5.5 min per precision) a 540 s call leaves ~3 min for 3 and 4: run
#    `PROBE=0 bash device/gpu_check.sh` in a second call for the whole comparison.
# Everything goes to $OUT (default gpu-check/) as JSON and text, with a summary at the end; exit 1
# on a failed check. Rehearsal on a CPU (what device/gpu_rehearsal.sh does):
#   SGR_ARCH_GPU=cpu SIZES=64 ROBOTS=2 STEPS=20 DATA=tests/data/returns PY=python3.12 bash device/gpu_check.sh
set -euo pipefail
cd "$(dirname "$0")/.."
PY=${PY:-python3}
OUT=${OUT:-gpu-check}
WHEELS=${WHEELS:-device-wheels}
GPU=${SGR_ARCH_GPU:-cuda}
mkdir -p "$OUT"
start=$(date +%s)
if ! "$PY" -c "import taichi, neat, gymnasium" >/dev/null 2>&1; then
  [ -d "$WHEELS" ] || { echo "gpu_check: no taichi here and no $WHEELS/ (run device/device_wheels.sh first)"; exit 1; }
  SITE=$(mktemp -d)
  "$PY" -m pip install -q --no-index --no-deps --target "$SITE" "$WHEELS"/*.whl
  export PYTHONPATH="$SITE${PYTHONPATH:+:$PYTHONPATH}"
fi
export PYTHONPATH="$PWD${PYTHONPATH:+:$PYTHONPATH}"
SGR_ARCH=$GPU "$PY" -c "import tsim.backend.runtime as r; print('taichi arch:', r.init())" | tee "$OUT/arch.txt"
"$PY" -c "import numpy, taichi; print('python', __import__('sys').version.split()[0], 'numpy', numpy.__version__, 'taichi', taichi.__version__)" | tee -a "$OUT/arch.txt"
command -v nvidia-smi >/dev/null && nvidia-smi --query-gpu=name,driver_version,memory.total --format=csv | tee -a "$OUT/arch.txt" || true

: > "$OUT/summary.txt"
fail=0
# 2. throughput. The bench builds its batch on the host (~0.6 ms per robot on a 2-vCPU VM), so B =
# 65536 spends ~40 s before its first step: it ran out of a 70 s limit on the H200 on 2026-12-04.
for B in ${SIZES:-1024 8192 32768}; do
  SGR_ARCH=$GPU timeout "${BENCH_LIMIT:-120}" "$PY" -m evolve.cli bench --task Walker-v0 --robots "$B" \
    --steps 50 --json | tee "$OUT/bench_$B.json" \
    || echo "gpu_check: bench at B = $B failed or ran out of its ${BENCH_LIMIT:-120} s" | tee -a "$OUT/summary.txt"
done
# 2b. the probe (bench/gpu_probe.py): the step kernel by batch size (8k-128k), block size and lanes,
# at 5x5 and 10x10, registers / local bytes / occupancy read from the compiled kernel, and a parity
# table on the paper's four tasks; each of its parts has its own time limit inside PROBE_LIMIT.
# PROBE=0 skips it; PROBE_PRECISIONS="f64 f32" runs it in both (~5 min each); on a CPU (the
# rehearsal) it runs its --quick sizes. Files in $OUT/probe_<precision>/ (summary.txt first).
if [ "${PROBE:-1}" != 0 ]; then
  for prec in ${PROBE_PRECISIONS:-f64}; do
    SGR_ARCH=$GPU timeout "${PROBE_LIMIT:-330}" "$PY" bench/gpu_probe.py --out "$OUT/probe_$prec" \
      --precision "$prec" $([ "$GPU" = cpu ] && echo --quick) \
      || echo "gpu_check: gpu_probe ($prec) failed or ran out of its ${PROBE_LIMIT:-330} s" \
        | tee -a "$OUT/summary.txt"
  done
fi
# 2c. the state kept on the device between env steps against the state through numpy at every
# launch (bench/device_state_bench.py, issue 48 item 2), alternating; STATE=0 skips it
if [ "${STATE:-1}" != 0 ]; then
  SGR_ARCH=$GPU timeout "${STATE_LIMIT:-120}" "$PY" bench/device_state_bench.py --robots "${STATE_B:-8192}" \
    --steps 20 --rounds 2 --record "$OUT/device_state.json" | tee "$OUT/device_state.txt" \
    || echo "gpu_check: device_state_bench failed or ran out of its ${STATE_LIMIT:-120} s" | tee -a "$OUT/summary.txt"
fi
# 2d. where an honest SGR generation's time goes on the GPU (bench/generation_breakdown.py, issue 48
# item 4), at each population in GENERATION_POPS (e.g. "1024 4096"; empty, the default, skips it:
# a generation at pop 1,024 is ~1 min on a GPU besides compiling, so give it its own call)
for pop in ${GENERATION_POPS:-}; do
  SGR_ARCH=$GPU timeout "${GENERATION_LIMIT:-400}" "$PY" bench/generation_breakdown.py --pop "$pop" \
    --generations 1 --json "$OUT/generation_$pop.json" | tee "$OUT/generation_$pop.txt" \
    || echo "gpu_check: generation_breakdown at pop $pop failed or ran out of its ${GENERATION_LIMIT:-400} s" \
      | tee -a "$OUT/summary.txt"
done
# 3. recorded evogym data that travelled
for d in ${DATA:-tests/data/returns tests/data/traces tests/data/evogym32}; do
  [ -d "$d" ] || continue
  name=$(basename "$d")
  SGR_ARCH=cpu "$PY" -m evolve.cli validate --json "$d" > "$OUT/validate_${name}_cpu.json"
  SGR_ARCH=$GPU "$PY" -m evolve.cli validate --json "$d" > "$OUT/validate_${name}_gpu.json"
done
"$PY" - "$OUT" <<'PY' | tee "$OUT/validate_summary.txt" || fail=1
import json, os, sys
out = sys.argv[1]
bad, seen = [], 0
for name in ("returns", "traces", "evogym32"):
    if not os.path.exists(f"{out}/validate_{name}_gpu.json"):
        continue
    cpu = json.load(open(f"{out}/validate_{name}_cpu.json"))
    gpu = json.load(open(f"{out}/validate_{name}_gpu.json"))
    for task, g in gpu["tasks"].items():
        seen += 1
        c = cpu["tasks"][task]
        keys = [k for k in g if isinstance(g[k], float) and ("err" in k or "diff" in k)]
        print(name, task, " ".join(f"{k} gpu {g[k]:.3g} cpu {c[k]:.3g}" for k in keys))
        if name != "traces" and g.get("median_abs_diff", 0.0) > 1e-9:
            bad.append(f"{task}: median |return - evogym| {g['median_abs_diff']:.3g} on the GPU")
if bad:
    print("FAILED:", "; ".join(bad))
    sys.exit(1)
print(f"evogym's recorded data on the GPU: ok ({seen} task records)")
PY

# 4. GPU against the CPU on every task, in each precision (SGR_PRECISION; PRECISIONS="f64 f32").
# f64 is judged statistically: Taichi 1.7's CUDA JIT (taichi/runtime/cuda/jit_cuda.cpp) keeps
# FPOpFusion::Strict with fast_math off but marks every function "unsafe-fp-math"="true", which
# lets LLVM's NVPTX backend fuse multiply-adds (fma.rn.f64), so bits need not match the CPU's
# (docs/history/VALIDATION.md, "CUDA f64"): the check fails on a task's median |return difference| above
# F64_TOL and says whether the bits matched. f32 is compared with the CPU in f32 (F32_TOL).
for prec in ${PRECISIONS:-f64 f32}; do
  if [ "$prec" = f32 ] && ! grep -rqs "SGR_PRECISION" tsim/; then
    echo "gpu_check: f32 skipped: this tree has no SGR_PRECISION option (branch precision)" | tee "$OUT/arch_compare_f32.txt"
    continue
  fi
  tol=$([ "$prec" = f32 ] && echo "${F32_TOL:-1e-3}" || echo "${F64_TOL:-1e-6}")
  SGR_PRECISION=$prec SGR_ARCH=cpu "$PY" device/arch_returns.py --robots "${ROBOTS:-16}" --steps "${STEPS:-200}" --out "$OUT/arch_cpu_$prec.json"
  SGR_PRECISION=$prec SGR_ARCH=$GPU "$PY" device/arch_returns.py --robots "${ROBOTS:-16}" --steps "${STEPS:-200}" --out "$OUT/arch_gpu_$prec.json"
  "$PY" device/arch_returns.py --tol "$tol" --compare "$OUT/arch_cpu_$prec.json" "$OUT/arch_gpu_$prec.json" | tee "$OUT/arch_compare_$prec.txt" || fail=1
done

echo "gpu_check: $(( $(date +%s) - start )) s; $([ $fail = 0 ] && echo ok || echo FAILED)" | tee -a "$OUT/summary.txt"
exit $fail
