"""Rewards, terminations and helpers several evogym tasks share."""

from __future__ import annotations

import math

import numpy as np

from tasks.spec import Measure

PENALTY = -3.0  # evogym's penalty for an episode ended by falling over or falling off


def dx(before: Measure, after: Measure) -> np.ndarray:
    """Rightward progress of the robot's COM."""
    return (after.com - before.com)[:, 0]


def dy(before: Measure, after: Measure) -> np.ndarray:
    """Upward progress of the robot's COM (the climbers' reward)."""
    return (after.com - before.com)[:, 1]


def reached_height(y: float, bonus: float = 1.0):
    """Termination: +bonus and the episode ends once the robot's COM is above height y (world
    units), e.g. the top of a climber's pipe. Pass y as evogym writes it (e.g. 65 * 0.1) to get
    its double bit for bit."""
    def termination(before: Measure, after: Measure):
        return np.full(len(after.com), bonus), after.com[:, 1] > y
    return termination


def upside_down(lo: float = math.pi / 2, hi: float = 3 * math.pi / 2):
    """Termination: -3 and the episode ends while the robot's orientation is in (lo, hi)."""
    def termination(before: Measure, after: Measure):
        o = after.orientation
        return np.full(len(o), PENALTY), (o > lo) & (o < hi)
    return termination


def fell_below(y: float):
    """Termination: -3 and the episode ends once the robot's COM is below height y (world units)."""
    def termination(before: Measure, after: Measure):
        return np.full(len(after.com), PENALTY), after.com[:, 1] < y
    return termination


def both(*terms):
    """Several terminations: each that fires adds its reward; the episode ends if any fires."""
    def termination(before: Measure, after: Measure):
        extra = np.zeros(len(after.com))
        done = np.zeros(len(after.com), dtype=bool)
        for term in terms:
            e, d = term(before, after)
            extra = np.where(d, extra + e, extra)
            done |= d
        return extra, done
    return termination
