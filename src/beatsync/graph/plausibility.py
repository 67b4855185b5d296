"""Physical plausibility of a composed dance: its speeds against its library's.

A dance whose intervals are squeezed into short music beats moves faster than any
real motion of its library. Compared: the **root speed** [position unit / s] and the
**joint rotation speed** [deg / s] (angle of each joint's local rotation change between
frames, pooled over joints; NaN without rotations), each by its 50th, 95th and 99th
percentiles. The reference is the *largest* clip 99th percentile of the library; a
result above it by more than :data:`TOLERANCE` (25 %) gets a
:class:`~beatsync.errors.BeatsyncWarning`.

Notebook: ``notebooks/paper_b_tab02_quality_proxies.ipynb``.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np

from ..quaternions import quat_from_euler, quat_multiply

__all__ = [
    "PERCENTILES",
    "TOLERANCE",
    "motion_speeds",
    "speed_profile",
    "library_profile",
    "plausibility",
]

#: Percentiles reported for every speed.
PERCENTILES = (50, 95, 99)
#: A result may exceed the library's largest clip 99th percentile by this factor.
TOLERANCE = 1.25


def motion_speeds(motion: Any) -> dict[str, np.ndarray]:
    """Root speed [unit / s] ``(n - 1,)`` and joint rotation speeds [deg / s] ``(n - 1, J)``."""
    pos = np.asarray(motion.positions(), dtype=np.float64)
    root = np.linalg.norm(np.diff(pos[:, 0, :], axis=0), axis=1) * motion.fps
    triples = motion.rotation_triples() if getattr(motion, "skeleton", None) else []
    n = motion.n_frames
    rot = np.empty((max(0, n - 1), len(triples)))
    by_order: dict[str, list[int]] = {}
    for i, (_joint, _idx, order) in enumerate(triples):
        by_order.setdefault(order, []).append(i)
    for order, members in by_order.items():  # one conversion per Euler order
        cols = [list(triples[i][1]) for i in members]
        ang = np.stack([motion.values[:, c] for c in cols], axis=1)  # (n, J, 3)
        q = quat_from_euler(ang.reshape(-1, 3), order).reshape(n, len(members), 4)
        conj = q[:-1] * np.array([-1.0, -1.0, -1.0, 1.0])  # inverse of a unit quaternion
        rel = quat_multiply(conj, q[1:])  # frame-to-frame rotation
        # its angle, as Rotation.magnitude computes it (precise for small angles)
        step = 2.0 * np.arctan2(np.linalg.norm(rel[..., :3], axis=-1), np.abs(rel[..., 3]))
        rot[:, members] = np.degrees(step) * motion.fps
    return {"root_speed": root, "rotation_speed": rot}


def speed_profile(motion: Any) -> dict[str, float]:
    """Percentiles of :func:`motion_speeds` (``root_speed_p99``, ``rotation_speed_p50``...)."""
    sp = motion_speeds(motion)
    out = {}
    for name, arr in sp.items():
        vals = arr.ravel()
        for q in PERCENTILES:
            out[f"{name}_p{q}"] = float(np.percentile(vals, q)) if vals.size else float("nan")
    return out


def library_profile(clips: Sequence[Any]) -> dict[str, Any]:
    """Per-clip speed profiles and the reference (largest clip 99th percentiles)."""
    per_clip = [{"clip": c.name, **speed_profile(c)} for c in clips]
    ref = {}
    for key in ("root_speed_p99", "rotation_speed_p99"):
        vals = np.array([p[key] for p in per_clip], dtype=np.float64)
        ref[key] = float(np.nanmax(vals)) if np.isfinite(vals).any() else float("nan")
    return {"clips": per_clip, "reference": ref}


def plausibility(
    motion: Any,
    library: dict[str, Any],
    scales: Any,
    bound: tuple[float, float] | None,
) -> tuple[dict[str, Any], list[str]]:
    """Speeds of a result against its library (:func:`library_profile`), and the time-scales.

    Returns the report (the result's percentiles, the library reference, the ratios
    ``root_speed_ratio`` and ``rotation_speed_ratio``, ``scale_min`` ... ``scale_max`` and
    ``scale_outside_bound``) and the warnings for ratios above :data:`TOLERANCE`.
    """
    prof = speed_profile(motion)
    ref = library["reference"]
    rep: dict[str, Any] = dict(prof)
    notes = []
    labels = {"root_speed": "root speed", "rotation_speed": "joint rotation speed"}
    for key, label in labels.items():
        r = ref[f"{key}_p99"]
        rep[f"library_{key}_p99"] = r
        ratio = prof[f"{key}_p99"] / r if r and np.isfinite(r) else float("nan")
        rep[f"{key}_ratio"] = ratio
        if np.isfinite(ratio) and ratio > TOLERANCE:
            notes.append(
                f"the dance moves faster than its library: 99th-percentile {label} "
                f"{prof[f'{key}_p99']:.3g} is {ratio:.2f}x the fastest clip's {r:.3g} "
                f"(more than {TOLERANCE:g}x); tighten the time-scale bound or use a library "
                "danced nearer the song's tempo"
            )
    s = np.asarray(scales, dtype=np.float64)
    s = s[np.isfinite(s)]
    for name, q in (("min", 0), ("p5", 5), ("p50", 50), ("p95", 95), ("max", 100)):
        rep[f"scale_{name}"] = float(np.percentile(s, q)) if s.size else float("nan")
    if bound is not None and s.size:
        out = (s < bound[0] * (1 - 1e-9)) | (s > bound[1] * (1 + 1e-9))
        rep["scale_outside_bound"] = int(out.sum())
    else:
        rep["scale_outside_bound"] = None
    return rep, notes
