#!/usr/bin/env bash
# GPU readiness in one short run (not run by CI: this project's CI has no GPU).
#   bash bench/gpu_check.sh            # from the repository root, venv at .venv (README's install)
# 1. physics validation on the GPU: `sgr validate` of the recorded evogym returns and traces of
#    the paper's 4 tasks and of the returns of all 32 tasks (tests/data/evogym32: the kernel that
#    sweeps and prunes contact pairs runs for BridgeWalker, CaveCrawler, Climber-v1, Traverser);
#    every figure is printed beside the CPU's (the same command with SGR_ARCH=cpu), and the script
#    fails when a task's median return error on the GPU exceeds 1e-9 (the CPU's are <= 7e-11)
# 2. `sgr bench` on Walker-v0 at B = 1024, 8192 and 65536 on the GPU (robot-steps/s), 50 steps
# Dry run of the script itself on a CPU: SGR_ARCH_GPU=cpu SIZES=64 bash bench/gpu_check.sh
# Writes everything to ${OUT:-gpu-check}/ and prints a summary; exit 1 on a failed check.
set -euo pipefail
PY=${PY:-.venv/bin/python}
OUT=${OUT:-gpu-check}
mkdir -p "$OUT"
export SGR_ARCH=${SGR_ARCH_GPU:-cuda}
"$PY" -c "import tsim.runtime as r; r.init(); print('taichi arch:', r.ti.lang.impl.current_cfg().arch)"
for d in tests/data/returns tests/data/traces tests/data/evogym32; do
  name=$(basename "$d")
  SGR_ARCH=cpu "$PY" -m evolve.cli validate --json "$d" > "$OUT/validate_${name}_cpu.json"
  "$PY" -m evolve.cli validate --json "$d" > "$OUT/validate_${name}_gpu.json"
done
"$PY" - "$OUT" <<'PY'
import json, sys
out = sys.argv[1]
bad = []
for name in ("returns", "traces", "evogym32"):
    cpu = json.load(open(f"{out}/validate_{name}_cpu.json"))
    gpu = json.load(open(f"{out}/validate_{name}_gpu.json"))
    for task, g in gpu["tasks"].items():
        c = cpu["tasks"][task]
        keys = [k for k in g if isinstance(g[k], float) and ("err" in k or "diff" in k)]
        print(name, task, " ".join(f"{k} gpu {g[k]:.3g} cpu {c[k]:.3g}" for k in keys))
        if name != "traces" and g.get("median_abs_diff", 0.0) > 1e-9:
            bad.append(f"{task}: median |return - evogym| {g['median_abs_diff']:.3g} on the GPU")
if bad:
    print("FAILED:", "; ".join(bad))
    sys.exit(1)
print("validation on the GPU: ok")
PY
for B in ${SIZES:-1024 8192 65536}; do
  "$PY" -m evolve.cli bench --task Walker-v0 --robots "$B" --steps 50 --json | tee "$OUT/bench_$B.json"
done
