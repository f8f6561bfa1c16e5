"""Replay evogym reference data through our tasks and measure the disagreement.

Two folder formats are understood (see the READMEs of shared/reference): trace folders
(`index.json` + one `.npz` per case + `chaos_floor.json`) and returns folders (`<task>.npz` with
40 random robots each + `summary.json`). All cases of one task run as one batch.
"""

from __future__ import annotations

import hashlib
import json
import zipfile
from pathlib import Path

import numpy as np
from scipy.stats import spearmanr

from tasks.env import BatchEnv
from tsim import backend
from tsim.errors import SgrError
from tsim.files import CONFIG_CAP, read_bytes, read_head, read_text

# a data set's files are read through links (git-annex keeps them so), but only regular files, of at
# most this many bytes: a FIFO or a device named index.json would be read forever
DATA_CAP = 4096 << 20


def _json(path: Path):
    try:
        return json.loads(read_text(path, CONFIG_CAP, follow=True))
    except (json.JSONDecodeError, UnicodeDecodeError) as exc:
        raise SgrError(f"{path}: not valid JSON ({exc})") from None


def _npz(path: Path):
    read_head(path, 0, follow=True)  # SgrError unless a regular file (is_zipfile would read a FIFO)
    if not zipfile.is_zipfile(path):
        raise SgrError(f"{path}: not a .npz file")
    try:
        return np.load(path, allow_pickle=False)
    except (ValueError, EOFError, OSError, zipfile.BadZipFile) as exc:
        raise SgrError(f"{path}: unreadable .npz file ({exc})") from None


TRACES_FORMAT = 1  # index.json's format_version of a trace set (references/'s evogym recorder)
EVOGYM32_FORMAT = 2  # ... and of tests/data/evogym32's


def _index(folder: Path, version: int) -> dict:
    """`folder`'s index.json, checked to be of the format this sgr reads: a set recorded in a
    format we do not know would be compared field by field as if we did."""
    path = folder / "index.json"
    index = _json(path)
    if not isinstance(index, dict):
        raise SgrError(f"{path}: not a reference index (a JSON object)")
    if index.get("format_version") != version:
        raise SgrError(f"{path}: format_version {index.get('format_version')!r}; this sgr reads {version}")
    shapes = ({"cases": list} if version == TRACES_FORMAT else {"all_tasks": list, "tasks": dict})
    for key, kind in shapes.items():
        if not isinstance(index.get(key), kind):
            raise SgrError(f"{path}: key {key!r} must be a {kind.__name__}, got {str(index.get(key))[:40]}")
    return index


def _case(folder: Path, case: object, index: Path):
    """A trace case's .npz, checked against what index.json says of it: its file inside `folder`,
    the same bytes (sha256) and the same task (a swapped or edited file would be validated as the
    case it is not)."""
    if not isinstance(case, dict) or not isinstance(case.get("file"), str) or "task" not in case:
        raise SgrError(f"{index}: a case must be an object with 'file' and 'task', got {str(case)[:80]!r}")
    path = _recorded_file(folder, case, index)
    z = _npz(path)
    if "task" in z.files and str(z["task"]) != case["task"]:
        raise SgrError(f"{path}: holds task {str(z['task'])!r}, {index} says {case['task']!r}")
    return z


def _recorded_file(folder: Path, entry: dict, index: Path) -> Path:
    """The file an index entry ({"file": name, "sha256": ...}) names: inside `folder`, there, and
    with the bytes recorded when the entry has a sha256."""
    name = str(entry.get("file"))
    if Path(name).name != name or name in ("", ".", ".."):  # the name, not where a link points
        raise SgrError(f"{index}: file {entry.get('file')!r} is not a file of {folder}")
    path = folder / name
    if not path.is_file():
        raise SgrError(f"{path}: not found (named by {index})")
    if "sha256" in entry and hashlib.sha256(read_bytes(path, DATA_CAP, follow=True)).hexdigest() != \
            entry["sha256"]:
        raise SgrError(f"{path}: its sha256 is not the one {index} records: not the file recorded")
    return path


def _evogym32_files(folder: Path, index: dict, task: str) -> None:
    """SgrError unless the files `evogym32_returns` and `evogym32_traces` replay for `task` are the
    ones index.json records, byte for byte."""
    path = folder / "index.json"
    facts = index["tasks"].get(task)
    entries = [facts.get("returns_file"), *(facts.get("traces") or [])] if isinstance(facts, dict) else []
    recorded = {e["file"]: e for e in entries if isinstance(e, dict) and isinstance(e.get("file"), str)}
    for f in [folder / f"returns_{task}.npz", *sorted(folder.glob(f"trace_{task}_*.npz"))]:
        if f.name not in recorded:
            raise SgrError(f"{f}: not recorded in {path} (task {task!r})")
        _recorded_file(folder, recorded[f.name], path)


def validate_traces(folder: Path) -> dict:
    """Replay every trace case of `folder` with evogym's recorded actions, one batch per task: per
    case COM (world units), step-0 observation and return errors; per task the median COM errors
    and, with chaos_floor.json, evogym's own spread under tiny perturbations (chaos_median); and
    per case the largest observation error over the first 50 steps, the orientation entries apart
    (`obs_err_max50`, `obs_err_orientation_max50`)."""
    index = _index(folder, TRACES_FORMAT)
    chaos_file = folder / "chaos_floor.json"
    chaos = _json(chaos_file) if chaos_file.exists() else None
    by_task: dict[str, list] = {}
    for case in index["cases"]:  # every file checked before anything is simulated
        z = _case(folder, case, folder / "index.json")
        by_task.setdefault(case["task"], []).append((case, z))
    cases_out, tasks_out = [], {}
    for task, pairs in by_task.items():
        cases, data = [c for c, _ in pairs], [z for _, z in pairs]
        steps = int(data[0]["steps"])
        bodies = [z["body"] for z in data]
        env = BatchEnv(task, bodies, episode_steps=steps, passive_ok=True)
        obs0 = [env.robot_obs(w) for w in range(env.n_worlds)]
        com = np.zeros((len(data), steps + 1, 2))
        ret = np.zeros(len(data))
        com[:, 0] = env.sim.robot_com()
        obs50 = [[o] for o in obs0]
        for t in range(steps):
            _, r, _, _, _ = env.step([z["actions"][t] for z in data])
            ret += r
            com[:, t + 1] = env.sim.robot_com()
            if t < 50:
                for w in range(env.n_worlds):
                    obs50[w].append(env.robot_obs(w))
        errs_final, errs_50 = [], []
        for k, (c, z) in enumerate(zip(cases, data, strict=False)):
            err = np.linalg.norm(com[k] - z["com"], axis=1)
            row = {"file": c["file"], "task": task, "com_err_final": float(err[-1]),
                   "com_err_max50": float(err[:51].max()),
                   "obs_dim": int(len(obs0[k])), "obs_dim_evogym": int(z["obs"].shape[1]),
                   "obs_err_step0": (float(np.abs(obs0[k] - z["obs"][0]).max())
                                     if len(obs0[k]) == z["obs"].shape[1] else float("inf")),
                   "return_err": float(abs(ret[k] - z["reward"].sum()))}
            o = np.array(obs50[k])
            if o.shape == z["obs"][:len(o)].shape:
                d = np.abs(o - z["obs"][:len(o)])
                oc = _orientation_columns(env, k)
                keep = np.ones(d.shape[1], bool)
                keep[oc] = False
                row["obs_err_max50"] = float(d[:, keep].max())
                row["obs_err_orientation_max50"] = float(d[:, oc].max()) if len(oc) else 0.0
            else:
                row["obs_err_max50"] = row["obs_err_orientation_max50"] = float("inf")
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
    files = [(f, z) for f in sorted(folder.glob("*.npz")) if "returns" in (z := _npz(f)).files]
    for f, z in files:  # <task>.npz: a file named for one task holding another's robots is refused first
        if str(z["task"]) != f.stem:
            raise SgrError(f"{f}: holds task {str(z['task'])!r}, its name says {f.stem!r}")
    for f, z in files:
        task = f.stem
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
        raise SgrError(f"not a folder: {folder}")
    out: dict = {"cases": [], "tasks": {}}
    if any(folder.glob("returns_*.npz")):  # tests/data/evogym32
        out["tasks"] = validate_evogym32(folder)
        return out
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
        raise SgrError(f"{folder} holds neither reference traces (index.json) nor returns (<task>.npz)")
    return out


def validate_evogym32(folder: str | Path, tasks: list[str] | None = None) -> dict:
    """Per task of tests/data/evogym32 that the registry knows (or `tasks`): the returns and
    traces summaries of `evogym32_returns` and `evogym32_traces`; in f32, `chaos_check`'s figures."""
    from tasks.specs import TASKS

    folder = Path(folder)
    index = _index(folder, EVOGYM32_FORMAT)
    out = {}
    tasks = tasks or [t for t in index["all_tasks"] if t in TASKS]
    for task in tasks:  # every file replayed is checked against index.json before any replay
        _evogym32_files(folder, index, task)
    for task in tasks:
        r = evogym32_returns(folder, task)
        if not backend.real().bits:  # no bits to match: evogym's chaos floor is the measure
            c = chaos_row(r, _npz(folder / f"returns_{task}.npz"))
            out[task] = {k: c[k] for k in ("com_err_median", "chaos_floor", "com_ratio", "com_ok",
                                           "spearman", "spearman_evogym_rerun", "rank_ok")}
            continue
        t = evogym32_traces(folder, task)
        out[task] = {"median_abs_diff": r["median_abs_diff"], "max_abs_diff": r["max_abs_diff"],
                     "term_agree": f"{r['term_agree']}/{r['n_cases']}",
                     "n_terminated": int((r["term_step_evogym"] >= 0).sum()),
                     "obs_len_ok": r["obs_len_ok"],
                     "obs_err_reset": max(r["obs_err"], r["obs_err_orientation"]),
                     "com_err_max_returns": r["com_err_max"], "com_err_max_traces": t["com_err_max"],
                     "trace_obs_err_max": max(c["obs_err_max"] for c in t["cases"])}
    return out


# ---------------------------------------------------------------------- evogym32 (all 32 tasks)
ORIENTATION_BLOCKS = ("orientation",)  # block names containing this hold an orientation


def _orientation_columns(env: BatchEnv, w: int) -> np.ndarray:
    """Observation columns of robot w that hold an orientation (evogym's reset value of an
    undeformed body is a rounding artefact, see docs/VALIDATION.md)."""
    cols, col = [], 0
    for b in env.spec.observation:
        width = 2 * int(env.n_points[w]) if b.width < 0 else b.width
        if any(k in b.name for k in ORIENTATION_BLOCKS):
            cols += range(col, col + width)
        col += width
    return np.array(cols, dtype=int)


def _obs_errors(env: BatchEnv, ref: np.ndarray, dims: np.ndarray) -> tuple[list, list, list]:
    same_len, err, err_ort = [], [], []
    for w in range(env.n_worlds):
        o = env.robot_obs(w)
        r = ref[w, :int(dims[w])]
        same_len.append(len(o) == len(r))
        if len(o) != len(r):
            err.append(float("inf"))
            err_ort.append(float("inf"))
            continue
        d = np.abs(o - r)
        keep = np.ones(len(d), bool)
        oc = _orientation_columns(env, w)
        keep[oc] = False
        err.append(float(d[keep].max()))
        err_ort.append(float(d[oc].max()) if len(oc) else 0.0)
    return same_len, err, err_ort


def evogym32_returns(folder: str | Path, task: str) -> dict:
    """Replay `returns_<task>.npz` of tests/data/evogym32 (24 robots, 100 steps, one batch)."""
    z = _npz(Path(folder) / f"returns_{task}.npz")
    bodies, n_act, steps = list(z["body"]), z["n_act"], int(z["steps"])
    seeds = [int(s) for s in z["reset_seed"]] if "reset_seed" in z.files else None
    env = BatchEnv(task, bodies, episode_steps=steps, passive_ok=True, seeds=seeds)
    same_len, obs_err, obs_err_ort = _obs_errors(env, z["obs0"], z["obs_dim"])
    B = len(bodies)
    rewards = np.full((B, steps), np.nan)
    term_step = np.full(B, -1)
    com = np.full((B, steps + 1, 2), np.nan)
    com[:, 0] = env.sim.robot_com()
    acts = z["actions"]
    for t in range(steps):
        live = ~env.terminated
        _, r, term, _, _ = env.step([acts[i, t, :n_act[i]] for i in range(B)])
        rewards[live, t] = r[live]
        com[live, t + 1] = env.sim.robot_com()[live]
        term_step[live & term] = t
        if term.all():
            break
    ret = np.nansum(rewards, axis=1)
    d = np.abs(ret - z["returns"])
    run = z["steps_run"]
    com_err = [float(np.nanmax(np.linalg.norm(com[i, :run[i] + 1] - z["com"][i, :run[i] + 1], axis=1)))
               for i in range(B)]
    com_err_final = [float(np.linalg.norm(com[i, run[i]] - z["com"][i, run[i]])) for i in range(B)]
    return {"task": task, "n_cases": B, "returns": ret, "returns_evogym": z["returns"],
            "abs_diff": d, "median_abs_diff": float(np.median(d)), "max_abs_diff": float(d.max()),
            "term_step": term_step, "term_step_evogym": z["term_step"],
            "term_agree": int((term_step == z["term_step"]).sum()),
            "obs_len_ok": all(same_len), "obs_err": float(max(obs_err)),
            "obs_err_orientation": float(max(obs_err_ort)), "com_err": np.array(com_err),
            "com_err_max": float(max(com_err)),
            "com_err_median": float(np.median(com_err)), "com_err_final": np.array(com_err_final)}


def state_steps(z) -> np.ndarray:
    """The steps whose points (`pos`, `robot_vel`) a trace file keeps: its `state_steps` (format 2:
    0..5, every 10th and the last), else every step (format 1)."""
    if "state_steps" in z.files:
        return z["state_steps"]
    return np.arange(int(z["steps_run"]) + 1)


def evogym32_traces(folder: str | Path, task: str) -> dict:
    """Replay the 3 `trace_<task>_*.npz` cases of tests/data/evogym32 (50 steps, one batch): robot
    COM, reward and observation errors at every step."""
    files = sorted(Path(folder).glob(f"trace_{task}_*.npz"))
    data = [_npz(f) for f in files]
    steps = int(data[0]["steps"])
    seeds = [int(z["reset_seed"]) for z in data] if "reset_seed" in data[0].files else None
    env = BatchEnv(task, [z["body"] for z in data], episode_steps=steps, passive_ok=True,
                   seeds=seeds)
    B = len(data)
    obs = [[env.robot_obs(w)] for w in range(B)]
    com = [[env.sim.robot_com()[w].copy()] for w in range(B)]
    rew = [[] for _ in range(B)]
    for t in range(steps):
        live = ~env.terminated
        acts = [z["actions"][min(t, len(z["actions"]) - 1)] for z in data]
        _, r, _, _, _ = env.step(acts)
        for w in np.nonzero(live)[0]:
            obs[w].append(env.robot_obs(w))
            com[w].append(env.sim.robot_com()[w].copy())
            rew[w].append(r[w])
    cases = []
    for w, (f, z) in enumerate(zip(files, data, strict=True)):
        n = int(z["steps_run"]) + 1
        c = np.array(com[w][:n])
        o, ro = np.array(obs[w][:n]), z["obs"][:n]
        oc = _orientation_columns(env, w)
        keep = np.ones(ro.shape[1], bool)
        keep[oc] = False
        same = o.shape == ro.shape
        cases.append({"file": f.name, "steps_run": n - 1, "steps_run_ours": len(com[w]) - 1,
                      "com_err_max": float(np.linalg.norm(c - z["com"][:len(c)], axis=1).max()),
                      "obs_err_max": float(np.abs(o - ro)[:, keep].max()) if same else float("inf"),
                      "obs_err_step0": float(np.abs(o[0] - ro[0])[keep].max()) if same else float("inf"),
                      "obs_err_orientation": (float(np.abs(o - ro)[:, oc].max()) if same and len(oc)
                                              else 0.0),
                      "reward_err_max": float(np.abs(np.array(rew[w][:n - 1]) - z["reward"][:n - 1]).max())})
    return {"task": task, "cases": cases, "com_err_max": max(c["com_err_max"] for c in cases)}


# ---------------------------------------------------------------------- against evogym's chaos floor
CHAOS_FACTOR = 2.0  # a precision passes a task within this many times evogym's own spread


def chaos_check(folder: str | Path, tasks: list[str] | None = None,
                factor: float = CHAOS_FACTOR) -> dict:
    """Per task of tests/data/evogym32 (or `tasks`): our disagreement with evogym against evogym's
    own under +-1e-6 action changes (its chaos floor), for a precision that cannot match bits (f32).

    - COM: per case, the largest |COM(ours) - COM(evogym)| over the episode (`com_err`) and at its
      end (`com_err_final`); evogym's spread per case is the larger of its +1e-6 and -1e-6 reruns'
      largest COM deviation (`max_com_dev_p6`, `_m6`: recorded over the episode, not at its end).
      The task passes if the median over its 24 cases of ours is within `factor` x the median of
      evogym's (`chaos_floor`); `chaos_floor_pooled` is the median over all 48 reruns.
    - Ranking: Spearman's rho of our returns against evogym's, passing if its distance from 1 is
      within `factor` x that of evogym's own reruns (the lower of the + and - reruns' rho), or
      within 1e-3 (rank swaps of returns closer than the reruns' spread)."""
    from tasks.specs import TASKS

    folder = Path(folder)
    index = _index(folder, EVOGYM32_FORMAT)
    return {task: chaos_row(evogym32_returns(folder, task), _npz(folder / f"returns_{task}.npz"), factor)
            for task in tasks or [t for t in index["all_tasks"] if t in TASKS]}


def chaos_row(r: dict, z, factor: float = CHAOS_FACTOR) -> dict:
    """`chaos_check`'s figures of one task from `evogym32_returns`'s result `r` and its file `z`."""
    p6, m6 = z["max_com_dev_p6"], z["max_com_dev_m6"]
    floor = float(np.median(np.maximum(p6, m6)))
    rho = float(spearmanr(r["returns"], z["returns"]).statistic)
    rho_evogym = float(min(spearmanr(z["returns_p6"], z["returns"]).statistic,
                           spearmanr(z["returns_m6"], z["returns"]).statistic))
    com_med = float(np.median(r["com_err"]))
    return {"com_err_median": com_med, "com_err_final_median": float(np.median(r["com_err_final"])),
            "com_err_max": r["com_err_max"], "chaos_floor": floor,
            "chaos_floor_pooled": float(np.median(np.concatenate([p6, m6]))),
            "com_ratio": com_med / floor if floor > 0 else float("inf"),
            "com_ok": bool(com_med <= factor * floor),
            "spearman": rho, "spearman_evogym_rerun": rho_evogym,
            "rank_ok": bool(1 - rho <= max(factor * (1 - rho_evogym), 1e-3)),
            "median_abs_return_diff": r["median_abs_diff"],
            "term_agree": f"{r['term_agree']}/{r['n_cases']}"}
