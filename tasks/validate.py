"""Replay evogym reference data through our tasks and measure the disagreement.

Two folder formats are understood (see the READMEs of shared/reference): trace folders
(`index.json` + one `.npz` per case + `chaos_floor.json`) and returns folders (`<task>.npz` with
40 random robots each + `summary.json`). All cases of one task run as one batch.
"""

from __future__ import annotations

import json
import zipfile
from pathlib import Path

import numpy as np
from scipy.stats import spearmanr

from tasks.env import BatchEnv


def _json(path: Path):
    try:
        return json.loads(path.read_text())
    except (json.JSONDecodeError, UnicodeDecodeError) as exc:
        raise ValueError(f"{path}: not valid JSON ({exc})") from None


def _npz(path: Path):
    if not zipfile.is_zipfile(path):
        raise ValueError(f"{path}: not a .npz file")
    try:
        return np.load(path)
    except (ValueError, EOFError, OSError, zipfile.BadZipFile) as exc:
        raise ValueError(f"{path}: unreadable .npz file ({exc})") from None


def validate_traces(folder: Path) -> dict:
    """Replay every trace case of `folder` with evogym's recorded actions, one batch per task: per
    case COM (world units), step-0 observation and return errors; per task the median COM errors
    and, with chaos_floor.json, evogym's own spread under tiny perturbations (chaos_median)."""
    index = _json(folder / "index.json")
    chaos_file = folder / "chaos_floor.json"
    chaos = _json(chaos_file) if chaos_file.exists() else None
    by_task: dict[str, list] = {}
    for case in index["cases"]:
        by_task.setdefault(case["task"], []).append(case)
    cases_out, tasks_out = [], {}
    for task, cases in by_task.items():
        data = [_npz(folder / c["file"]) for c in cases]
        steps = int(data[0]["steps"])
        bodies = [z["body"] for z in data]
        env = BatchEnv(task, bodies, episode_steps=steps, passive_ok=True)
        obs0 = [env.robot_obs(w) for w in range(env.n_worlds)]
        com = np.zeros((len(data), steps + 1, 2))
        ret = np.zeros(len(data))
        com[:, 0] = env.sim.robot_com()
        for t in range(steps):
            _, r, _, _, _ = env.step([z["actions"][t] for z in data])
            ret += r
            com[:, t + 1] = env.sim.robot_com()
        errs_final, errs_50 = [], []
        for k, (c, z) in enumerate(zip(cases, data, strict=False)):
            err = np.linalg.norm(com[k] - z["com"], axis=1)
            row = {"file": c["file"], "task": task, "com_err_final": float(err[-1]),
                   "com_err_max50": float(err[:51].max()),
                   "obs_dim": int(len(obs0[k])), "obs_dim_evogym": int(z["obs"].shape[1]),
                   "obs_err_step0": (float(np.abs(obs0[k] - z["obs"][0]).max())
                                     if len(obs0[k]) == z["obs"].shape[1] else float("inf")),
                   "return_err": float(abs(ret[k] - z["reward"].sum()))}
            cases_out.append(row)
            errs_final.append(row["com_err_final"])
            errs_50.append(row["com_err_max50"])
        t_out = {"median_com_err_final": float(np.median(errs_final)),
                 "median_com_err_max50": float(np.median(errs_50))}
        if chaos is not None:
            devs = []
            for c in chaos["cases"]:
                if c["task"] != task:
                    continue
                for fam in ("perturbations", "initial_shift"):
                    for run in (c.get(fam) or {}).values():
                        devs.append(np.hypot(run["abs_dcom_x_final"], run["abs_dcom_y_final"]))
            if devs:
                t_out["chaos_median"] = float(np.median(devs))
        tasks_out[task] = t_out
    return {"cases": cases_out, "tasks": tasks_out}


def validate_returns(folder: Path) -> dict:
    """Replay the robots of each <task>.npz (files without `returns` are skipped) with their
    recorded actions: Spearman and median absolute difference of our returns against evogym's."""
    tasks_out = {}
    summary = _json(folder / "summary.json") if (folder / "summary.json").exists() else {}
    for f in sorted(folder.glob("*.npz")):
        z = _npz(f)
        if "returns" not in z.files:
            continue
        task = str(z["task"])
        n_act, steps_run = z["n_act"], z["steps_run"]
        bodies = list(z["body"])
        steps = int(z["episode_length"])
        env = BatchEnv(task, bodies, episode_steps=steps)
        ret = np.zeros(len(bodies))
        acts = z["actions"]
        for t in range(steps):
            _, r, term, trunc, _ = env.step([acts[i, t, :n_act[i]] for i in range(len(bodies))])
            ret += r
            if term.all():
                break
        ref = z["returns"]
        rho = float(spearmanr(ret, ref).statistic)
        out = {"spearman": rho, "median_abs_diff": float(np.median(np.abs(ret - ref))),
               "n_cases": len(bodies), "n_unstable": int(env.sim.unstable.sum()),
               "n_unstable_evogym": int(z["unstable"].sum()), "steps_run_evogym_max": int(steps_run.max())}
        chaos = summary.get("tasks", {}).get(task, {}).get("chaos", {})
        if chaos:
            out["spearman_evogym_vs_perturbed"] = chaos["plus"]["spearman_returns_ref_vs_perturbed"]
            out["chaos_median_abs_return_diff"] = chaos["pooled_plus_minus"]["abs_return_diff"]["median"]
        tasks_out[task] = out
    return {"tasks": tasks_out}


def validate(folder: str | Path) -> dict:
    """Validate every reference set found in `folder` (trace format, returns format, or both)."""
    folder = Path(folder)
    if not folder.is_dir():
        raise ValueError(f"not a folder: {folder}")
    out: dict = {"cases": [], "tasks": {}}
    found = False
    if (folder / "index.json").exists():
        found = True
        r = validate_traces(folder)
        out["cases"] += r["cases"]
        out["tasks"].update(r["tasks"])
    if any("returns" in _npz(f).files for f in folder.glob("*.npz")):
        found = True
        for task, vals in validate_returns(folder)["tasks"].items():
            out["tasks"].setdefault(task, {}).update(vals)
    if not found:
        raise ValueError(f"{folder} holds neither reference traces (index.json) nor returns (<task>.npz)")
    return out
