"""The :class:`Motion` value and forward kinematics.

Data contract
-------------
- ``Motion.values`` is ``(n_frames, n_channels)`` float64 at ``fps > 0`` [Hz]; frame
  ``i`` is at ``i / fps`` [s].
- Channels are ``"<joint>_<dof>"`` (``"rShin_Xrotation"``) for BVH, ``"<marker>_x"``
  for positions, ``"<name>_angle"`` for joint angles. Rotations are degrees;
  positions in the file's units (markers and joint positions: metres).
- A :class:`Skeleton` (from BVH) gives forward kinematics; other motion has
  ``skeleton=None``.
- A *position-only* motion (:attr:`Motion.is_positional`: no skeleton, channels
  ``"<joint>_x/_y/_z"``) holds world joint positions in the canonical frame,
  **metres, z up** (right-handed; files in cm or y up are converted on reading and
  back on writing); :attr:`Motion.bones` are given or inferred (:func:`infer_bones`),
  and :attr:`Motion.position_info` keeps the input's layout for writing it back.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace
from itertools import combinations
from typing import Any

import numpy as np

from .errors import ParameterError
from .joints import bone_lengths, check_bones, fill_joint_gaps, infer_bones
from .quaternions import quat_from_euler, quat_multiply, quat_rotate
from .validation import check_finite, check_fps

__all__ = [
    "Joint",
    "Skeleton",
    "Motion",
    "PositionInfo",
    "CANONICAL_UNITS",
    "CANONICAL_UP",
    "infer_bones",
    "bone_lengths",
    "bone_angles",
    "fill_joint_gaps",
    "marker_angles",
    "fill_gaps",
    "check_bones",
    "has_marker_set",
    "is_marker_motion",
    "segmentation_view",
]

_ROT_DOFS = ("Xrotation", "Yrotation", "Zrotation")
#: Length unit of joint positions of a position-only motion read from a file.
CANONICAL_UNITS = "m"
#: Vertical axis of joint positions of a position-only motion read from a file.
CANONICAL_UP = "z"
#: Supported length units and their size in metres.
UNIT_METRES = {"m": 1.0, "cm": 0.01, "mm": 0.001}
_POS_DOFS = ("Xposition", "Yposition", "Zposition")


@dataclass(frozen=True, eq=False)
class Joint:
    """One joint (or end site) of a BVH hierarchy: ``parent`` index (-1: root), ``offset``
    from it [file units], BVH channel names in file order."""

    name: str
    parent: int
    offset: np.ndarray
    channels: tuple[str, ...] = ()
    is_end_site: bool = False

    def __eq__(self, other: object) -> bool:
        if not isinstance(other, Joint):
            return NotImplemented
        return (
            self.name == other.name
            and self.parent == other.parent
            and self.channels == other.channels
            and self.is_end_site == other.is_end_site
            and np.array_equal(self.offset, other.offset)
        )

    def __hash__(self) -> int:
        return hash((self.name, self.parent, self.channels, self.is_end_site))


@dataclass(frozen=True)
class Skeleton:
    """A BVH hierarchy: joints in file (depth-first) order, parents before children."""

    joints: tuple[Joint, ...]

    @property
    def joint_names(self) -> list[str]:
        """Names of all joints including end sites (axis 1 of :meth:`Motion.positions`)."""
        return [j.name for j in self.joints]

    def index(self, name: str) -> int:
        for i, j in enumerate(self.joints):
            if j.name == name:
                return i
        raise ParameterError(f"joint {name!r} is not in the skeleton; known: {self.joint_names}")

    def channel_names(self) -> tuple[str, ...]:
        """Motion channel names ``"<joint>_<dof>"`` in BVH frame-line order."""
        return tuple(f"{j.name}_{c}" for j in self.joints for c in j.channels)

    def same_structure(self, other: Skeleton) -> bool:
        """True if both have the same joints, parents and channels (offsets may differ)."""
        return len(self.joints) == len(other.joints) and all(
            a.name == b.name and a.parent == b.parent and a.channels == b.channels
            for a, b in zip(self.joints, other.joints, strict=True)
        )


@dataclass(frozen=True, eq=False)
class PositionInfo:
    """What a position-only motion needs beyond its values: bones (``None``: inferred) and
    its file's layout (``"json"``, ``"npy"``, ``"npz"``, ``"c3d"``; ``"array"``: made in
    memory), ``units`` and ``up`` (each ``"given"``, ``"detected"`` or from the ``"file"``),
    the JSON root track ``center`` [m] and the ``.npz`` array ``key``."""

    bones: np.ndarray | None = None
    layout: str = "array"
    units: str = CANONICAL_UNITS
    up: str = CANONICAL_UP
    units_source: str = "given"
    up_source: str = "given"
    center: np.ndarray | None = None
    key: str | None = None

    def describe(self) -> str:
        """One line stating units and vertical axis and whether they were detected."""
        return (
            f"{self.layout} file in {self.units} ({self.units_source}), {self.up} up "
            f"({self.up_source}); read as {CANONICAL_UNITS}, {CANONICAL_UP} up"
        )


@dataclass(frozen=True, eq=False)
class Motion:
    """Multi-channel motion sampled at a constant frame rate (see the module's contract)."""

    values: np.ndarray
    fps: float
    channels: tuple[str, ...]
    skeleton: Skeleton | None = None
    name: str = ""
    position_info: PositionInfo | None = None
    _cache: dict[str, Any] = field(default_factory=dict, repr=False, compare=False)

    def __post_init__(self) -> None:
        values = np.asarray(self.values, dtype=np.float64)
        if values.ndim != 2:
            raise ParameterError(
                f"motion values must be 2-D (n_frames, n_channels), got shape {values.shape}"
            )
        object.__setattr__(self, "values", values)
        object.__setattr__(self, "fps", check_fps(self.fps))
        object.__setattr__(self, "channels", tuple(self.channels))
        if len(self.channels) != values.shape[1]:
            raise ParameterError(
                f"motion has {values.shape[1]} value columns but {len(self.channels)} channel "
                "names; is the array transposed (it must be time first: frames x channels)?"
            )
        if self.skeleton is not None:
            if self.skeleton.channel_names() != self.channels:
                raise ParameterError("channel names do not match the skeleton's channels")
            _check_reach(self.skeleton, values)
        info = self.position_info
        if info is not None:
            if not self.is_positional:
                raise ParameterError(
                    "position_info is only for position-only motion (no skeleton, channels "
                    f"<joint>_x/_y/_z); this one has channels {list(self.channels[:6])}"
                )
            if info.bones is not None:
                object.__setattr__(
                    self,
                    "position_info",
                    replace(info, bones=check_bones(info.bones, self.values.shape[1] // 3)),
                )

    @property
    def is_positional(self) -> bool:
        """True for position-only motion: no skeleton, channels ``<joint>_x/_y/_z`` triples
        (the axis letters in either case)."""
        if "positional" not in self._cache:
            parts = [c.rpartition("_") for c in self.channels]
            stems = [p[0] for p in parts[::3]]
            self._cache["positional"] = (
                self.skeleton is None
                and len(parts) % 3 == 0
                and "" not in stems
                and len(parts) >= 3
                and [(p[0], p[2].lower()) for p in parts] == [(s, a) for s in stems for a in "xyz"]
            )
        return self._cache["positional"]

    @property
    def bones(self) -> np.ndarray:
        """Joint-index pairs ``(n_bones, 2)``: BVH ``(joint, parent)``, else given or inferred."""
        if self.skeleton is not None:
            return np.array(
                [(i, j.parent) for i, j in enumerate(self.skeleton.joints) if j.parent >= 0],
                dtype=np.int64,
            ).reshape(-1, 2)
        if not self.is_positional:
            raise ParameterError(
                f"motion {self.name!r} has neither a skeleton nor joint positions "
                "(channels <joint>_x/_y/_z): it has no bones"
            )
        info = self.position_info
        if info is not None and info.bones is not None:
            return info.bones
        if "bones" not in self._cache:
            self._cache["bones"] = infer_bones(self.positions())
        return self._cache["bones"]

    @property
    def n_frames(self) -> int:
        return int(self.values.shape[0])

    @property
    def n_channels(self) -> int:
        return int(self.values.shape[1])

    @property
    def duration(self) -> float:
        """Duration [s] = n_frames / fps (each frame covers 1/fps)."""
        return self.n_frames / self.fps

    @property
    def times(self) -> np.ndarray:
        """Time [s] of every frame, ``arange(n_frames) / fps``."""
        return np.arange(self.n_frames, dtype=np.float64) / self.fps

    @property
    def joint_names(self) -> list[str]:
        """Joint names along axis 1 of :meth:`positions` (BVH joints or position triples)."""
        if self.skeleton is None and self.is_positional:
            return [c.rpartition("_")[0] for c in self.channels[::3]]
        if self.skeleton is None:
            raise ParameterError(
                f"motion {self.name!r} has no skeleton (marker data or a plain table); "
                "joint positions need a BVH file"
            )
        return self.skeleton.joint_names

    def channel_index(self, name: str) -> int:
        try:
            return self.channels.index(name)
        except ValueError:
            raise ParameterError(
                f"channel {name!r} not found; channels look like {list(self.channels[:6])}..."
            ) from None

    def with_values(self, values: np.ndarray, fps: float | None = None) -> Motion:
        """Same channels and skeleton, new values (and optionally a new frame rate)."""
        return replace(self, values=values, fps=self.fps if fps is None else fps, _cache={})

    def select(self, names: list[str] | tuple[str, ...]) -> Motion:
        """A motion with only the named channels (no skeleton)."""
        idx = [self.channel_index(n) for n in names]
        return Motion(self.values[:, idx], self.fps, tuple(names), None, self.name)

    def slice_frames(self, start: int, stop: int) -> Motion:
        """Frames ``start:stop`` (frame indices), keeping skeleton and rate."""
        if not (0 <= start < stop <= self.n_frames):
            raise ParameterError(
                f"frame slice {start}:{stop} is outside 0:{self.n_frames} "
                "(frame indices, not seconds)"
            )
        out = self.with_values(self.values[start:stop])
        info = self.position_info
        if info is not None and info.center is not None and len(info.center) == self.n_frames:
            info = replace(info, center=info.center[start:stop])
            out = replace(out, position_info=info, _cache={})
        return out

    def rename(self, name: str) -> Motion:
        return replace(self, name=name, _cache={})

    def rotation_triples(self) -> list[tuple[str, tuple[int, int, int], str]]:
        """``(joint, channel indices, order)`` of each joint with three rotation channels.

        ``order`` is the intrinsic Euler order of the file: ``"ZXY"`` is R = Rz @ Rx @ Ry.
        """
        if "triples" in self._cache:
            return self._cache["triples"]
        by_joint: dict[str, list[tuple[int, str]]] = {}  # in order of first appearance
        for i, ch in enumerate(self.channels):
            joint, _, dof = ch.rpartition("_")
            if dof in _ROT_DOFS:
                by_joint.setdefault(joint, []).append((i, dof[0]))
        out = [
            (joint, tuple(i for i, _ in items), "".join(a for _, a in items))
            for joint, items in by_joint.items()
            if len(items) == 3
        ]
        self._cache["triples"] = out
        return out

    def partial_rotation_columns(self) -> list[int]:
        """Columns of rotation channels of joints with only one or two rotation channels."""
        in_triples = {i for _, idx, _ in self.rotation_triples() for i in idx}
        return [
            i
            for i, ch in enumerate(self.channels)
            if ch.rpartition("_")[2] in _ROT_DOFS and i not in in_triples
        ]

    def positions(self) -> np.ndarray:
        """World positions ``(n_frames, n_joints, 3)`` [file units] along :attr:`joint_names`.

        Forward kinematics for BVH; position-only motion: the values reshaped (a view).
        """
        if "positions" in self._cache:
            return self._cache["positions"]
        if self.skeleton is None:  # joint_names refuses a plain table
            pos = self.values.reshape(self.n_frames, len(self.joint_names), 3)
            self._cache["positions"] = pos
            return pos
        n = self.n_frames
        joints = self.skeleton.joints
        pos = np.zeros((n, len(joints), 3))
        glob: list[np.ndarray | None] = []  # world rotation per joint (None: identity)
        col = 0
        for j_idx, joint in enumerate(joints):
            trans = np.broadcast_to(joint.offset, (n, 3)).copy()
            rot_axes: list[str] = []
            rot_cols: list[int] = []
            for c in joint.channels:
                if c in _POS_DOFS:
                    trans[:, "XYZ".index(c[0])] += self.values[:, col]
                elif c in _ROT_DOFS:
                    rot_axes.append(c[0])
                    rot_cols.append(col)
                col += 1
            local = (
                quat_from_euler(self.values[:, rot_cols], "".join(rot_axes)) if rot_axes else None
            )
            parent_rot = glob[joint.parent] if joint.parent >= 0 else None
            moved = trans if parent_rot is None else quat_rotate(parent_rot, trans)
            pos[:, j_idx] = moved if joint.parent < 0 else pos[:, joint.parent] + moved
            if parent_rot is None or local is None:
                glob.append(local if parent_rot is None else parent_rot)
            else:
                glob.append(quat_multiply(parent_rot, local))
        self._cache["positions"] = pos
        return pos


def _check_reach(skeleton: Skeleton, values: np.ndarray) -> None:
    """Refuse offsets or translations so large that forward kinematics would overflow: a
    world position is at most the chain's sum of ``|x| + |y| + |z|`` of offsets and
    translations (rotations keep lengths), which times 2 sqrt(3) must stay finite."""
    joints = skeleton.joints
    with np.errstate(over="ignore"):  # an overflow is inf: refused below
        sizes = np.abs([j.offset for j in joints]).sum(axis=1).tolist()
    biggest = int(np.argmax(sizes))
    largest = (sizes[biggest], f"OFFSET of joint {joints[biggest].name!r}")
    col = 0
    for i, joint in enumerate(joints):
        for k, c in enumerate(joint.channels):
            if c in _POS_DOFS:
                big = float(np.fmax.reduce(np.abs(values[:, col + k]), initial=0.0))
                if big > largest[0]:
                    largest = (big, f"channel {joint.name}_{c} value {big:g}")
                sizes[i] += big
        col += len(joint.channels)
        if joint.parent >= 0:
            sizes[i] += sizes[joint.parent]  # parents come first: now the chain's sum
    if not math.isfinite(2 * math.sqrt(3) * max(sizes, default=0.0)):
        what = largest[1]
        if what.startswith("OFFSET"):
            what += f" ({' '.join(map(str, joints[biggest].offset))})"
        raise ParameterError(
            f"{what} is too large: forward kinematics would overflow float64 (joint "
            "positions beyond 1e308); a corrupt number or a wrong unit?"
        )


def fill_gaps(motion: Motion) -> Motion:
    """Fill NaN gaps in every channel by linear interpolation (edges held constant)."""
    values = motion.values.copy()
    t = np.arange(motion.n_frames)
    for c in range(values.shape[1]):
        bad = ~np.isfinite(values[:, c])
        if bad.all():
            raise ParameterError(f"channel {motion.channels[c]!r} has no finite value at all")
        if bad.any():
            values[bad, c] = np.interp(t[bad], t[~bad], values[~bad, c])
    return motion.with_values(values)


def _marker(motion: Motion, names: tuple[str, ...]) -> np.ndarray:
    idx = [[motion.channel_index(f"{n}_{a}") for a in "xyz"] for n in names]
    return motion.values[:, idx].mean(axis=1)


def _angle(a: np.ndarray, b: np.ndarray, c: np.ndarray) -> np.ndarray:
    """Angle ABC [deg] at vertex b between segments b->a and b->c, per frame."""
    u, v = a - b, c - b
    cosang = np.sum(u * v, axis=1) / (np.linalg.norm(u, axis=1) * np.linalg.norm(v, axis=1))
    return np.degrees(np.arccos(np.clip(cosang, -1.0, 1.0)))


# Marker groups of the MoCap Toolbox demo data (28 markers).
_MCT_POINTS = {
    "head": ("Head_FL", "Head_FR", "Head_BL", "Head_BR"),
    "neck": ("Shoulder_L", "Shoulder_R"),
    "pelvis": ("Hip_FL", "Hip_FR", "Hip_BL", "Hip_BR"),
    "hip_L": ("Hip_FL", "Hip_BL"),
    "hip_R": ("Hip_FR", "Hip_BR"),
    "shoulder_L": ("Shoulder_L",),
    "shoulder_R": ("Shoulder_R",),
    "elbow_L": ("Elbow_L",),
    "elbow_R": ("Elbow_R",),
    "wrist_L": ("Radius_L", "Ulna_L"),
    "wrist_R": ("Radius_R", "Ulna_R"),
    "knee_L": ("Knee_L",),
    "knee_R": ("Knee_R",),
    "ankle_L": ("Ankle_L",),
    "ankle_R": ("Ankle_R",),
    "toe_L": ("BigToe_L",),
    "toe_R": ("BigToe_R",),
}

# angle name -> (a, vertex, c)
_MCT_ANGLES = {
    "knee_L_angle": ("hip_L", "knee_L", "ankle_L"),
    "knee_R_angle": ("hip_R", "knee_R", "ankle_R"),
    "hip_L_angle": ("shoulder_L", "hip_L", "knee_L"),
    "hip_R_angle": ("shoulder_R", "hip_R", "knee_R"),
    "ankle_L_angle": ("knee_L", "ankle_L", "toe_L"),
    "ankle_R_angle": ("knee_R", "ankle_R", "toe_R"),
    "elbow_L_angle": ("shoulder_L", "elbow_L", "wrist_L"),
    "elbow_R_angle": ("shoulder_R", "elbow_R", "wrist_R"),
    "shoulder_L_angle": ("hip_L", "shoulder_L", "elbow_L"),
    "shoulder_R_angle": ("hip_R", "shoulder_R", "elbow_R"),
    "neck_angle": ("pelvis", "neck", "head"),
}


def marker_angles(motion: Motion) -> Motion:
    """Interior joint angles [deg] (180 = straight; :data:`_MCT_ANGLES`) from the MoCap
    Toolbox 28-marker set, marker gaps filled linearly first."""
    motion = fill_gaps(motion)
    try:
        points = {k: _marker(motion, v) for k, v in _MCT_POINTS.items()}
    except ParameterError as exc:
        raise ParameterError(
            f"marker_angles needs the MoCap Toolbox 28-marker set (Knee_L, Ankle_L, ...): {exc}"
        ) from None
    names = tuple(_MCT_ANGLES)
    values = np.stack(
        [_angle(points[a], points[b], points[c]) for a, b, c in _MCT_ANGLES.values()], axis=1
    )
    check_finite(values, name="marker angles")
    return Motion(values, motion.fps, names, None, motion.name)


def bone_angles(motion: Motion) -> Motion:
    """Interior angles [deg] between every two bones that meet at a joint (channels
    ``"<a>-<joint>-<b>_angle"``, gaps filled linearly first): unchanged by travel, turns,
    body size and units, they suit paper A's segmentation of joint positions."""
    motion = fill_gaps(motion)
    pos = motion.positions()
    names = motion.joint_names
    neighbours: dict[int, list[int]] = {}
    for a, b in motion.bones:
        neighbours.setdefault(int(a), []).append(int(b))
        neighbours.setdefault(int(b), []).append(int(a))
    triples = [(a, v, b) for v, nb in sorted(neighbours.items()) for a, b in combinations(nb, 2)]
    if not triples:
        raise ParameterError(
            f"motion {motion.name!r} has {len(names)} joint(s) and no two bones meet at a "
            "joint: joint angles need at least 3 joints in a chain"
        )
    with np.errstate(invalid="ignore", divide="ignore"):
        values = np.stack([_angle(pos[:, a], pos[:, v], pos[:, b]) for a, v, b in triples], 1)
    values = np.where(np.isfinite(values), values, 180.0)  # coincident joints: straight
    channels = tuple(f"{names[a]}-{names[v]}-{names[b]}_angle" for a, v, b in triples)
    return Motion(values, motion.fps, channels, None, motion.name)


def has_marker_set(motion: Motion) -> bool:
    """True if the motion has the MoCap Toolbox 28-marker names :func:`marker_angles` needs."""
    have = set(motion.channels)
    return all(f"{m}_x" in have for ms in _MCT_POINTS.values() for m in ms)


def is_marker_motion(motion: Motion) -> bool:
    """True for marker positions (channels ``"<marker>_x/_y/_z"``, no skeleton)."""
    return motion.skeleton is None and all(
        c.rsplit("_", 1)[-1] in ("x", "y", "z") for c in motion.channels
    )


def segmentation_view(motion: Motion) -> Motion:
    """The joint-angle motion that segmentation works on (paper A works on joint angles):
    BVH and tables as they are, markers through :func:`marker_angles`, other joint
    positions through :func:`bone_angles`."""
    if not is_marker_motion(motion):
        return motion
    if motion.is_positional and not has_marker_set(motion):
        return bone_angles(motion)
    return marker_angles(motion)
