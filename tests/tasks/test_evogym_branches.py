"""Every reward and termination branch of every task (tasks/suite/, and the goal and instability
rules of tasks/env.py) is reached by recorded evogym 2.0.0 data on both sides of its threshold:
some recorded step lies just past it and some just short of it (within EPS, a tenth of a voxel, or
EPS_ANGLE for orientations), in evogym's own numbers (tests/data/evogym32: the returns files and
`state_cases.npz`). The replays of that data (test_evogym32.py, test_evogym_states.py) then compare
our rewards, observations and termination steps on both sides of every threshold, so a threshold,
factor or sign changed in any branch fails there. docs/VALIDATION.md lists the branches and cases.

Not reachable from evogym states (listed in docs/VALIDATION.md, checked below where data show it):
Pusher-v0/-v1's "package COM below y = 0" (evogym's ground plane throws a package put 0.005 into it
above y = 0.4 within one step).
"""

from __future__ import annotations

import json
import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pytest

EPS = 0.01  # world units: a tenth of a voxel
EPS_ANGLE = 0.1  # radians: a falling robot turns up to ~0.05 per step near the thresholds
DATA = Path(__file__).parents[1] / "data" / "evogym32"
LO, HI = math.pi / 2, 3 * math.pi / 2  # upside_down's default interval
UP_LO, UP_HI = math.pi / 2 - math.pi / 12, 3 * math.pi / 2 + math.pi / 12  # UpStepper-v0's


def _episodes(source: str) -> list[dict]:
    """Recorded episodes: "returns:<task>" (its 24 robots) or the name of a state case. Each has the
    states after every step (row t = after step t): robot `com`, `ort`, tracked object `other`."""
    if source.startswith("returns:"):
        z = np.load(DATA / f"returns_{source[8:]}.npz", allow_pickle=False)
        out = []
        for i in range(len(z["seed"])):
            n = int(z["steps_run"][i]) + 1
            ep = {"com": z["com"][i, 1:n], "ort": z["ort"][i, 1:n],
                  "unstable": int(z["unstable_step"][i])}
            if "other_com" in z.files:
                ep["other"] = z["other_com"][i, 1:n]
            out.append(ep)
        return out
    z = np.load(DATA / "state_cases.npz", allow_pickle=False)
    (case,) = [c for c in json.loads(str(z["cases"])) if c["name"] == source]
    pre = source + "/"
    ep = {"com": z[pre + "com"][1:], "ort": z[pre + "ort"][1:], "unstable": case["unstable_step"]}
    if pre + "other_com" in z.files:
        ep["other"] = z[pre + "other_com"][1:]
    return [ep]


def robot_x(ep):
    return ep["com"][:, 0]


def robot_y(ep):
    return ep["com"][:, 1]


def other_y(ep):
    return ep["other"][:, 1]


def ort(ep):
    return ep["ort"]


def package_x_between(lo: float, hi: float):
    """The package's x while its COM y is in [lo, hi) (Carrier-v1: the x line decides there)."""
    def value(ep):
        y = ep["other"][:, 1]
        return np.where((y >= lo) & (y < hi), ep["other"][:, 0], np.nan)
    return value


def package_y_where_x(right_of_2: bool):
    """The package's y while its x is right of 2.0 (line 0.4) or not (line 0.6), Carrier-v1."""
    def value(ep):
        x = ep["other"][:, 0]
        return np.where((x > 2.0) == right_of_2, ep["other"][:, 1], np.nan)
    return value


@dataclass(frozen=True)
class Branch:
    task: str
    what: str  # the branch, as docs/VALIDATION.md names it
    sources: tuple[str, ...]
    value: object  # episode -> value after every step (NaN where the branch does not apply)
    threshold: float
    past_above: bool  # the branch is taken when value > threshold (else when value < threshold)
    eps: float = EPS


def goal(task: str, short: str, x: float) -> Branch:
    return Branch(task, f"goal: COM x > {x} (+bonus, end)", (f"{short}_past_goal",
                  f"{short}_short_of_goal"), robot_x, x, True)


def upside(task: str, sources_lo: tuple, sources_hi: tuple, lo=LO, hi=HI) -> list[Branch]:
    return [Branch(task, "fell over: orientation > lo (-3, end)", sources_lo, ort, lo, True,
                   EPS_ANGLE),
            Branch(task, "fell over: orientation < hi (-3, end)", sources_hi, ort, hi, False,
                   EPS_ANGLE)]


BRANCHES = [
    goal("Walker-v0", "walker", 9.9),
    goal("BridgeWalker-v0", "bridge", 6.0),
    goal("CaveCrawler-v0", "cave", 6.9),
    Branch("Flipper-v0", "end: COM x < 0.1", ("flipper_past_left_end", "flipper_short_of_left_end"),
           robot_x, 0.1, False),
    goal("UpStepper-v0", "upstepper", 6.9),
    *upside("UpStepper-v0", ("upstepper_tips_left",), ("upstepper_tips_right",), UP_LO, UP_HI),
    goal("DownStepper-v0", "downstepper", 7.4),
    *upside("DownStepper-v0", ("downstepper_tips_left",), ("downstepper_tips_right",)),
    goal("ObstacleTraverser-v0", "obstacle_v0", 7.9),
    *upside("ObstacleTraverser-v0", ("obstacle_v0_tips_left",), ("obstacle_v0_tips_right",)),
    goal("ObstacleTraverser-v1", "obstacle_v1", 5.9),
    *upside("Hurdler-v0", ("returns:Hurdler-v0",), ("hurdler_tips_right",)),
    Branch("GapJumper-v0", "fell off: COM y < 0.4 (-3, end)", ("gap_jumper_falls_off",), robot_y,
           0.4, False),
    Branch("PlatformJumper-v0", "fell off: COM y < 0.4 (-3, end)", ("platform_jumper_falls_off",),
           robot_y, 0.4, False),
    *upside("PlatformJumper-v0", ("platform_jumper_tips_left",), ("platform_jumper_tips_right",)),
    goal("Traverser-v0", "traverser", 5.9),
    Branch("Lifter-v0", "robot COM y < 0.3: +20 x its dy", ("lifter_robot_falls_low",), robot_y,
           0.3, False),
    goal("Carrier-v0", "carrier", 9.9),
    Branch("Carrier-v0", "package y < 0.3: +10 x its dy", ("returns:Carrier-v0",), other_y, 0.3,
           False),
    Branch("Carrier-v1", "package x > 2.0: line 0.4 instead of 0.6",
           ("carrier_v1_package_right_of_2", "carrier_v1_package_left_of_2"),
           package_x_between(0.4, 0.6), 2.0, True),
    Branch("Carrier-v1", "package x > 2.0 and y < 0.4: +10 x its dy",
           ("carrier_v1_package_falls_low",), package_y_where_x(True), 0.4, False),
    Branch("Carrier-v1", "package x <= 2.0 and y < 0.6: +10 x its dy",
           ("returns:Carrier-v1", "carrier_v1_package_left_of_2"), package_y_where_x(False), 0.6,
           False),
    goal("Pusher-v0", "pusher", 9.9),
    goal("Pusher-v1", "pusher_v1", 6.9),
    Branch("BeamToppler-v0", "beam COM x < 0.2 (+1, end)",
           ("beam_toppler_beam_past_left", "beam_toppler_beam_short_of_left"),
           lambda ep: ep["other"][:, 0], 0.2, False),
    Branch("BeamSlider-v0", "beam COM x < 0.2 (+1, end)",
           ("beam_slider_beam_past_left", "beam_slider_beam_short_of_left"),
           lambda ep: ep["other"][:, 0], 0.2, False),
    Branch("Thrower-v0", "robot COM x < 0: its dx penalty's sign flips",
           ("thrower_left_of_zero", "thrower_right_of_zero"), robot_x, 0.0, False),
    Branch("Catcher-v0", "package y < 0.5: +10 x its dy", ("catcher_package_falls_low",), other_y,
           0.5, False),
    Branch("Climber-v0", "top: COM y > 8.6 (+1, end)",
           ("climber_v0_past_top", "climber_v0_short_of_top"), robot_y, 8.6, True),
    Branch("Climber-v1", "top: COM y > 6.5 (+1, end)",
           ("climber_past_top", "climber_short_of_top"), robot_y, 6.5, True),
]


def margins(b: Branch) -> tuple[float, float]:
    """Over every recorded step of the branch's sources: the smallest distance past the threshold
    and the smallest distance short of it (inf when that side is never reached)."""
    past = short = math.inf
    for source in b.sources:
        for ep in _episodes(source):
            v = np.asarray(b.value(ep), dtype=float)
            v = v[~np.isnan(v)]
            d = v - b.threshold if b.past_above else b.threshold - v
            if (d > 0).any():
                past = min(past, float(d[d > 0].min()))
            if (d <= 0).any():
                short = min(short, float(-d[d <= 0].max()))
    return past, short


@pytest.mark.parametrize("b", BRANCHES, ids=[f"{b.task}: {b.what}" for b in BRANCHES])
def test_branch_reached_just_past_and_just_short_by_evogym_data(b):
    past, short = margins(b)
    assert past <= b.eps and short <= b.eps, (past, short)


def test_instability_reached_and_not():
    """tasks/env.py's -3 for an unstable step: evogym's Lifter-v0 robot 4 and Carrier-v1 robot 8
    go unstable (replayed, per robot, by test_evogym32.py), their other robots do not."""
    for task, robot in (("Lifter-v0", 4), ("Carrier-v1", 8)):
        steps = [ep["unstable"] for ep in _episodes(f"returns:{task}")]
        assert steps[robot] >= 0 and sum(s >= 0 for s in steps) == 1


def test_flipper_counts_flips_both_ways():
    """Flipper-v0's flip counter: steps that turn the robot from below pi/3 to above 5 pi/3 (one
    flip back) and from above 5 pi/3 to below pi/3 (one forward) both occur in evogym's returns
    data, as do steps that cross neither."""
    back = forward = neither = 0
    for ep in _episodes("returns:Flipper-v0"):
        o0, o1 = ep["ort"][:-1], ep["ort"][1:]
        b = (o0 < math.pi / 3) & (o1 > 5 * math.pi / 3)
        f = (o0 > 5 * math.pi / 3) & (o1 < math.pi / 3)
        back, forward, neither = back + b.sum(), forward + f.sum(), neither + (~b & ~f).sum()
    assert back > 0 and forward > 0 and neither > 0


def test_bidirectional_goal_reached_within_and_beyond_0_2():
    """BidirectionalWalker-v0: a goal counts as done when the COM is within 0.2 of it after the
    step (the next goal is then scored in the same step). Replaying evogym's recorded COMs and
    goals (the random robots and the state cases put 0.195 and 0.205 right of the first goal),
    some steps finish a goal just inside 0.2 and some leave it just outside."""
    z = np.load(DATA / "returns_BidirectionalWalker-v0.npz", allow_pickle=False)
    runs = [(z["goals_x_voxels"][i], z["com"][i, 1:int(z["steps_run"][i]) + 1, 0])
            for i in range(len(z["seed"]))]
    s = np.load(DATA / "state_cases.npz", allow_pickle=False)
    runs += [(s[f"{n}/goals_x_voxels"], s[f"{n}/com"][1:, 0])
             for n in ("bidirectional_goal_within", "bidirectional_goal_beyond")]
    inside = outside = math.inf
    for goals_vox, xs in runs:
        goals = [g * 0.1 for g in goals_vox if g >= 0]
        k = 0
        for x in xs:
            while k < len(goals):
                d = abs(goals[k] - x)
                if d < 0.2:
                    inside = min(inside, 0.2 - d)
                    k += 1
                else:
                    outside = min(outside, d - 0.2)
                    break
    assert inside <= EPS and outside <= EPS, (inside, outside)


def _goal_loop(goals_vox: np.ndarray, xs: np.ndarray) -> list[tuple[int, float]]:
    """evogym's goal loop over the COM x after every step: per step, the index of the last goal
    it evaluated and that goal's distance from the COM (a goal within 0.2 is done and the next
    one evaluated with the same COM)."""
    goals = [g * 0.1 for g in goals_vox if g >= 0]
    k, out = 0, []
    for x in xs:
        while True:
            d = abs(goals[k] - x)
            if d < 0.2 and k + 1 < len(goals):
                k += 1
                continue
            out.append((k, d))
            if d < 0.2:
                k += 1
            break
        if k == len(goals):
            break
    return out


def test_bidirectional_all_goals_done_reached_and_not():
    """BidirectionalWalker-v0's "all goals done" (+1, the end): in evogym's recorded episodes where
    the robot was moved before every step to each goal in turn (`bidirectional_all_goals_done`,
    `bidirectional_last_goal_beyond`), the last goal is evaluated with the COM just inside 0.2
    (done: evogym ended the episode there, with the +1 in that step's reward) and just outside
    (not done: evogym went on), within EPS of the line on both sides."""
    z = np.load(DATA / "state_cases.npz", allow_pickle=False)
    cases = {c["name"]: c for c in json.loads(str(z["cases"]))}
    inside = outside = math.inf
    for name in ("bidirectional_all_goals_done", "bidirectional_last_goal_beyond"):
        goals = z[f"{name}/goals_x_voxels"]
        last = int((goals >= 0).sum()) - 1
        loop = _goal_loop(goals, z[f"{name}/com"][1:, 0])
        rewards = z[f"{name}/rewards"]
        for t, (k, d) in enumerate(loop):
            if k != last:
                continue
            if d < 0.2:
                inside = min(inside, 0.2 - d)
                assert cases[name]["term_step"] == t and rewards[t] > 0.9  # progress + 1
            else:
                outside = min(outside, d - 0.2)
        if cases[name]["term_step"] < 0:
            assert len(loop) == cases[name]["steps_run"] and loop[-1][0] == last
    assert inside <= EPS and outside <= EPS, (inside, outside)


def test_pusher_package_below_zero_is_out_of_evogyms_reach():
    """Pusher's "package below y = 0" branch: a package put with its COM 0.005 into evogym's ground
    plane (left of the terrain) is above 0.4 after one step, so no evogym state reaches the branch;
    the recorded episodes (replayed by test_evogym_states.py) show it."""
    for name in ("pusher_package_in_plane", "pusher_v1_package_in_plane"):
        (ep,) = _episodes(name)
        assert (ep["other"][:, 1] > 0.4).all()
