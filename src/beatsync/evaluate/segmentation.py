"""Scores of a temporal segmentation against reference period boundaries (mir_eval style:
1-D increasing frame indices, ``reference`` the ground truth; no segmentation runs here).
"""

from __future__ import annotations

from typing import Any

import numpy as np

from ..validation import nearest

__all__ = ["boundary_errors"]


def boundary_errors(estimated: Any, reference: Any, *, remove_offset: bool = False) -> dict:
    """Boundary error [frames] of estimated against reference boundary frames.

    Each reference boundary inside the estimated span is matched to the nearest estimated
    one; ``remove_offset`` subtracts the median signed error first (for baselines whose
    boundaries sit at another phase of the cycle).
    """
    est = np.asarray(estimated, dtype=np.float64)
    ref = np.asarray(reference, dtype=np.float64)
    if est.size == 0 or ref.size == 0:
        return {"mean": np.nan, "max": np.nan, "n_matched": 0, "count_error": est.size - ref.size,
                "offset": 0.0}  # fmt: skip
    signed = nearest(ref, est) - ref
    if remove_offset:
        offset = float(np.median(signed))
        return boundary_errors(est - offset, ref) | {"offset": offset}
    inside = (ref >= est[0] - 0.5) & (ref <= est[-1] + 0.5)
    err = np.abs(signed[inside]) if inside.any() else np.abs(signed)
    return {
        "mean": float(err.mean()),
        "max": float(err.max()),
        "n_matched": int(err.size),
        "count_error": int(est.size - ref.size),
        "offset": 0.0,
    }
