"""Measures of a body matrix: how symmetric, how irregular, what it is made of and how big.

A body is an (H, W) grid of evogym material codes (0 empty, 1 rigid, 2 soft, 3 horizontal and
4 vertical actuator). Every measure is read inside the body's bounding box (the rows and columns
holding a voxel), so a body drawn off-centre in its grid measures as the same body centred. Reports
show them beside a champion's picture; quality diversity uses them as descriptors. A population's
body diversity is `evolve.search.body_distance.mean_pairwise_body_distance`.
"""

from __future__ import annotations

import zlib

import numpy as np

MATERIALS = {1: "rigid", 2: "soft", 3: "h_actuator", 4: "v_actuator"}
# every key `measures` returns, in the order reports show them
NAMES = ("width", "height", "voxels", "fill", "rigid", "soft", "h_actuator", "v_actuator", "actuator",
         "symmetry_lr", "symmetry_tb", "irregularity", "boundaries")


def bounding_box(body: np.ndarray) -> np.ndarray:
    """The smallest sub-grid holding every voxel of `body` (ValueError for an empty body)."""
    body = np.asarray(body)
    rows, cols = np.nonzero(body)
    if rows.size == 0:
        raise ValueError("an empty body has no bounding box")
    return body[rows.min():rows.max() + 1, cols.min():cols.max() + 1]


def _agreement(a: np.ndarray, b: np.ndarray) -> float:
    """Share of the cells filled in `a` or in `b` where both hold the same material."""
    filled = (a != 0) | (b != 0)
    return float(np.count_nonzero((a == b) & filled) / np.count_nonzero(filled))


def symmetry_lr(body: np.ndarray) -> float:
    """Left-right symmetry in [0, 1]: the bounding box's agreement with its mirror image about the
    vertical axis (1: a mirror-symmetric body). Mirroring keeps a horizontal actuator horizontal."""
    box = bounding_box(body)
    return _agreement(box, box[:, ::-1])


def symmetry_tb(body: np.ndarray) -> float:
    """Top-bottom symmetry in [0, 1]: agreement with the mirror image about the horizontal axis."""
    box = bounding_box(body)
    return _agreement(box, box[::-1, :])


def _compressed(grid: np.ndarray) -> int:
    return len(zlib.compress(np.ascontiguousarray(grid, dtype=np.uint8).tobytes(), 9))


def irregularity(body: np.ndarray) -> int:
    """How much description the body needs: the zlib (level 9) size in bytes of its bounding box's
    material grid, less that of a uniform grid of the same shape (0: one material throughout;
    larger for bodies with less repetition)."""
    box = bounding_box(body)
    return _compressed(box) - _compressed(np.zeros_like(box))


def boundaries(body: np.ndarray) -> float:
    """Share in [0, 1] of the bounding box's neighbouring cell pairs (side by side or one above the
    other) holding different materials, empty included: 0 for a uniform block, higher for a body
    made of small patches."""
    box = bounding_box(body)
    pairs = box[:, 1:].size + box[1:, :].size
    if pairs == 0:
        return 0.0
    differ = np.count_nonzero(box[:, 1:] != box[:, :-1]) + np.count_nonzero(box[1:, :] != box[:-1, :])
    return float(differ / pairs)


def measures(body: np.ndarray) -> dict[str, float]:
    """Every measure of `body`, by the names in NAMES: width and height of its bounding box, its
    voxel count, `fill` (voxels / bounding-box cells), each material's share of the voxels,
    `actuator` (both actuator kinds), both symmetries, irregularity and boundaries."""
    body = np.asarray(body)
    box = bounding_box(body)
    voxels = int(np.count_nonzero(box))
    out: dict[str, float] = {"width": int(box.shape[1]), "height": int(box.shape[0]), "voxels": voxels,
                             "fill": voxels / box.size}
    for code, name in MATERIALS.items():
        out[name] = int(np.count_nonzero(box == code)) / voxels
    out["actuator"] = out["h_actuator"] + out["v_actuator"]
    out["symmetry_lr"] = symmetry_lr(box)
    out["symmetry_tb"] = symmetry_tb(box)
    out["irregularity"] = irregularity(box)
    out["boundaries"] = boundaries(box)
    return {name: out[name] for name in NAMES}


def describe(m: dict[str, float]) -> str:
    """A body's `measures` in a few words, e.g. "5x5, symmetry lr 1.00 tb 0.40, irregularity 9,
    actuators 48 %"; the size is its bounding box's rows x columns, as `--shape` writes a shape."""
    return (f"{m['height']}x{m['width']}, symmetry lr {m['symmetry_lr']:.2f} tb {m['symmetry_tb']:.2f}, "
            f"irregularity {m['irregularity']}, actuators {100 * m['actuator']:.0f} %")


def material_shares(m: dict[str, float]) -> str | None:
    """The materials' shares of a body's voxels in percent, rigid / soft / h / v (MATERIALS'
    order), e.g. "10 / 42 / 24 / 24 %"; None where `m` lacks one (a row measured before)."""
    if not all(name in m for name in MATERIALS.values()):
        return None
    return " / ".join(f"{100 * m[name]:.0f}" for name in MATERIALS.values()) + " %"
