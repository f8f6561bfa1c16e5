"""Byte-reproducible .npz files and the strided steps of the reference data's large state arrays.

Shared by the evogym recorders (references/evogym_reference.py, run in evogym's Python 3.10 venv) and
references/thin_reference.py; numpy only, so it imports in either environment.
"""

from __future__ import annotations

import hashlib
import io
import zipfile

import numpy as np


def state_steps(last: int, stride: int, first: int = 5) -> np.ndarray:
    """The steps at which a reference file keeps its large state arrays (every point, every
    observation): 0..first, every stride-th and the last. A physics change shows at every step, so
    these catch it as the full arrays did, at a fraction of the size; COM, orientation and rewards
    stay per step."""
    keep = set(range(min(first, last) + 1)) | set(range(0, last + 1, stride)) | {last}
    return np.array(sorted(keep), dtype=np.int64)


def save_npz(path: str, arrays: dict) -> str:
    """np.savez_compressed, but byte-reproducible (fixed timestamps, the dict's key order); returns
    the sha256 of the file."""
    buf = io.BytesIO()
    with zipfile.ZipFile(buf, "w", compression=zipfile.ZIP_DEFLATED, compresslevel=9) as zf:
        for key, value in arrays.items():
            arr = np.asanyarray(value)
            if arr.dtype == object:
                raise TypeError(f"{key}: object arrays are not allowed")
            data = io.BytesIO()
            np.lib.format.write_array(data, arr, allow_pickle=False)
            info = zipfile.ZipInfo(key + ".npy", date_time=(1980, 1, 1, 0, 0, 0))
            info.compress_type = zipfile.ZIP_DEFLATED
            info.external_attr = 0o644 << 16
            zf.writestr(info, data.getvalue(), compresslevel=9)
    raw = buf.getvalue()
    with open(path, "wb") as f:
        f.write(raw)
    return hashlib.sha256(raw).hexdigest()
