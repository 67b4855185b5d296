"""Channel choice for the segmentation: which joint angles, constant ones dropped, z-scored.

Only :func:`select_channels` validates its input (it is called at the public entry);
the array helpers trust theirs. :func:`standardise` returns channels first,
``(n_channels, n_frames)``, the layout of the rest of the package.
"""

from __future__ import annotations

import re
from collections.abc import Sequence

import numpy as np

from ..errors import ParameterError, warn

__all__ = [
    "CONSTANT_REL_STD",
    "select_channels",
    "nonconstant_channels",
    "standardise",
    "unwrap_rotations",
]

CONSTANT_REL_STD = 1e-3
"""A channel with std <= this times the largest selected std is excluded as constant."""


# Joint-name keywords (lower case, side prefixes removed) of the main limb and spine
# joints of CMU, iClone CC_Base and Mixamo-like rigs (see select_channels).
_LIMB_SPINE = (
    "abdomen", "chest", "neck", "spine", "waist", "pelvis",
    "shldr", "shoulder", "upperarm", "arm", "forearm", "elbow",
    "thigh", "upleg", "leg", "shin", "calf", "knee", "foot", "ankle",
)  # fmt: skip
# Never default: twist/helper bones, extremities, face, and the root/hip (its rotation
# is the body's global orientation, not a joint angle).
_EXCLUDE = ("twist", "share", "toe", "hand", "finger", "thumb", "index", "mid", "ring",
            "pinky", "eye", "jaw", "head", "collar", "clavicle", "breast", "rib",
            "buttock", "root", "end")  # fmt: skip
_ROOT_NAMES = ("hip", "hips", "cc_base_hip", "rl_boneroot", "root")


def _joint_key(joint: str) -> str:
    """Joint key: ``"rShin"`` -> ``"shin"``, ``"CC_Base_L_Calf"`` -> ``"calf"``."""
    key = re.sub(r"^(CC_Base_|mixamorig:?|RL_)", "", joint, flags=re.IGNORECASE)
    key = re.sub(r"^([LR]_|[lr](?=[A-Z])|Left_?|Right_?)", "", key, flags=0)
    key = re.sub(r"^(left_?|right_?)", "", key, flags=re.IGNORECASE)
    return re.sub(r"\d+$", "", key.lower().replace("_", ""))


def _is_default_channel(name: str) -> bool:
    if name.endswith("_angle"):
        return True
    joint, sep, dof = name.rpartition("_")
    if not sep or not dof.lower().endswith("rotation"):
        return False
    if joint.lower() in _ROOT_NAMES:
        return False
    key = _joint_key(joint)
    if any(x in key for x in _EXCLUDE):
        return False
    return any(key == k or key.endswith(k) for k in _LIMB_SPINE)


def select_channels(
    names: Sequence[str], channels: str | Sequence[str] = "default"
) -> tuple[str, ...]:
    """Choose the channels the segmentation uses: ``"default"``, ``"all"`` or exactly the names.

    ``"default"``: rotation channels of the main limb and spine joints (CMU: abdomen chest
    neck rShldr rForeArm rThigh rShin rFoot and their left twins; iClone: ``CC_Base_Waist``,
    ``Spine01``, ``*_Upperarm``, ``*_Forearm``, ``*_Thigh``, ``*_Calf``, ``*_Foot``; never
    twist bones, hands, toes, face or the root), and every ``*_angle`` channel; if none
    matches, all channels with a :class:`BeatsyncWarning`.

    >>> select_channels(["hip_Xposition", "hip_Zrotation", "rShin_Xrotation", "rHand_Xrotation"])
    ('rShin_Xrotation',)
    """
    names = tuple(str(n) for n in names)
    if isinstance(channels, str):
        if channels == "all":
            return names
        if channels != "default":
            if channels in names:
                return (channels,)
            raise ParameterError(
                f"channels={channels!r}: use 'default', 'all' or a list of channel names "
                f"(e.g. {list(names[:3])})"
            )
        chosen = tuple(n for n in names if _is_default_channel(n))
        if not chosen:
            warn(
                "no limb/spine rotation or *_angle channel found among "
                f"{list(names[:4])}...; using all channels",
                stacklevel=3,
            )
            return names
        return chosen
    chosen = tuple(str(c) for c in channels)
    missing = [c for c in chosen if c not in names]
    if missing:
        raise ParameterError(
            f"channel(s) {missing[:5]} not found; channels look like {list(names[:4])}"
        )
    if not chosen:
        raise ParameterError("channels is an empty list; give at least one channel name")
    return chosen


def nonconstant_channels(values: np.ndarray) -> np.ndarray:
    """Boolean mask of channels kept by the documented near-constant rule."""
    std = values.std(axis=0)
    return (std > CONSTANT_REL_STD * std.max(initial=0.0)) & (std > 1e-9)


def standardise(values: np.ndarray) -> np.ndarray:
    """Per-channel z-score, returned channel-first ``(C, n)`` (r is invariant to it)."""
    x = values - values.mean(axis=0)
    x = x / x.std(axis=0)
    return np.ascontiguousarray(x.T)


def unwrap_rotations(values: np.ndarray, names: Sequence[str]) -> np.ndarray:
    """Unwrap rotation channels [deg] across the +-180 wrap (analysis only)."""
    rot = [i for i, nm in enumerate(names) if nm.lower().endswith("rotation")]
    out = values.copy()
    out[:, rot] = np.unwrap(values[:, rot], axis=0, period=360.0)
    return out
