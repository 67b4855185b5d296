"""Keeping bone lengths when position-only motion is resampled.

Joint positions are resampled linearly (no rotations to slerp), which shortens a turning
limb between frames (by ``1 - cos(theta / 2)`` for a turn of ``theta`` per source frame)
and more at a blended loop join. So each bone is then set back to its source length,
interpolated like the positions, keeping its direction: walking a spanning tree of the
bone graph outwards, each child joint goes to its parent's corrected position plus the
bone's direction times that length.

Data contract: positions ``(n_frames, n_joints, 3)``; bones ``(n_bones, 2)`` joint
index pairs; source times in seconds of the source motion's timeline.
"""

from __future__ import annotations

from collections import deque

import numpy as np

__all__ = ["bone_tree", "interp_frames", "restore_bone_lengths"]


def interp_frames(values: np.ndarray, fps: float, t: np.ndarray) -> np.ndarray:
    """``values`` (frames first, at ``fps``) at times ``t`` [s], linear between frames."""
    f = np.clip(np.asarray(t) * fps, 0.0, values.shape[0] - 1)
    i0 = np.floor(f).astype(np.int64)
    i1 = np.minimum(i0 + 1, values.shape[0] - 1)
    w = (f - i0).reshape(-1, *[1] * (values.ndim - 1))
    return (1.0 - w) * values[i0] + w * values[i1]


def bone_tree(bones: np.ndarray, n_joints: int) -> list[tuple[int, int]]:
    """``(parent, child)`` pairs of a spanning forest of the bone graph, parents first.

    Each component is rooted at its joint with the most bones (the pelvis or the
    spine in a body), so corrections spread outwards along the shortest chains.
    """
    adj: list[list[int]] = [[] for _ in range(n_joints)]
    for a, b in np.asarray(bones, dtype=np.int64).reshape(-1, 2):
        adj[int(a)].append(int(b))
        adj[int(b)].append(int(a))
    seen = np.zeros(n_joints, dtype=bool)
    order: list[tuple[int, int]] = []
    for root in sorted(range(n_joints), key=lambda j: -len(adj[j])):
        if seen[root] or not adj[root]:
            continue
        seen[root] = True
        queue = deque([root])
        while queue:
            p = queue.popleft()
            for c in adj[p]:
                if not seen[c]:
                    seen[c] = True
                    order.append((p, c))
                    queue.append(c)
    return order


def restore_bone_lengths(
    out_pos: np.ndarray,
    src_pos: np.ndarray,
    bones: np.ndarray,
    fps: float,
    src_a: np.ndarray,
    src_b: np.ndarray | None = None,
    w: np.ndarray | None = None,
) -> np.ndarray:
    """Set every bone of resampled positions ``out_pos`` ``(k, joints, 3)`` back to its
    source length (``src_pos`` at ``fps``), interpolated at the source times ``src_a``
    [s] and, where two poses were blended at a loop join, at ``src_b`` with weight ``w``.
    """
    tree = bone_tree(bones, src_pos.shape[1])
    if not tree:
        return out_pos
    par, chi = np.array(tree, dtype=np.int64).T
    lengths = np.linalg.norm(src_pos[:, chi] - src_pos[:, par], axis=-1)  # (n, n_tree)
    target = interp_frames(lengths, fps, src_a)
    if src_b is not None and w is not None and np.any(w > 0):
        target = target * (1.0 - w[:, None]) + interp_frames(lengths, fps, src_b) * w[:, None]
    fixed = out_pos.copy()
    for k, (p, c) in enumerate(tree):
        d = out_pos[:, c] - out_pos[:, p]
        norm = np.linalg.norm(d, axis=-1, keepdims=True)
        safe = norm[:, 0] > 1e-12
        fixed[safe, c] = fixed[safe, p] + d[safe] / norm[safe] * target[safe, k : k + 1]
        fixed[~safe, c] = fixed[~safe, p] + d[~safe]
    return fixed
