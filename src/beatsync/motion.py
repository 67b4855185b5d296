"""The :class:`Motion` value and forward kinematics.

Data contract
-------------
- ``Motion.values`` is ``(n_frames, n_channels)`` float64, time first, sampled at
  ``fps > 0`` [Hz]. Frame ``i`` is at time ``i / fps`` [s].
- Channels are named ``"<joint>_<dof>"`` (``"rShin_Xrotation"``, ``"hip_Xposition"``)
  for skeletal data, ``"<marker>_x"`` for marker positions, ``"<name>_angle"`` for
  derived joint angles. Rotation channels are degrees, as in BVH; positions are in
  the file's units (the bundled CMU salsa files are in metres, marker data is
  converted to metres on reading).
- A :class:`Skeleton` (from BVH) gives forward kinematics; marker data and plain
  tables have ``skeleton=None``.
- A *position-only* motion (``skeleton=None``, channels ``"<joint>_x/_y/_z"`` in
  joint order; :attr:`Motion.is_positional`) holds world joint positions directly:
  :meth:`Motion.positions` reshapes them (no forward kinematics) and
  :attr:`Motion.bones` gives joint-index pairs, given or inferred from constant joint
  distances (:func:`infer_bones`). Canonical frame of joint positions read by
  :mod:`beatsync.io.positions`: **metres, z up** (right-handed), the frame of the
  MoCap Toolbox and most C3D files, and the one ``render`` assumes for skeleton-less
  motion; files in centimetres or y up are converted on reading and back on writing.
  :attr:`Motion.position_info` (a :class:`PositionInfo`) keeps what is needed to
  write the motion back in its input's layout.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace
from typing import Any

import numpy as np

from .errors import ParameterError
from .joints import bone_lengths, check_bones, fill_joint_gaps, infer_bones
from .quaternions import quat_from_euler, quat_multiply, quat_rotate
from .units import check_finite, check_fps

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
    """One joint (or end site) of a BVH hierarchy.

    Attributes
    ----------
    name : str
    parent : int
        Index of the parent joint in :attr:`Skeleton.joints`; -1 for the root.
    offset : np.ndarray [shape=(3,)]
        Offset from the parent, in the file's length units.
    channels : tuple of str
        BVH channel names in file order (``()`` for end sites).
    is_end_site : bool
    """

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
    """What a position-only motion needs beyond its values: bones and its file's layout.

    Parameters
    ----------
    bones : np.ndarray [shape=(n_bones, 2)], int, optional
        Joint-index pairs; ``None``: inferred from the data (:func:`infer_bones`).
    layout : str
        Layout of the file it came from: ``"json"`` (Dance-with-Melody ``skeletons`` +
        ``center``), ``"npy"``, ``"npz"``, ``"c3d"``, or ``"array"`` (made in memory).
    units : {"m", "cm", "mm"}
        Length unit of that file (the motion itself is in metres).
    up : {"y", "z"}
        Vertical axis of that file (the motion itself is z up).
    units_source, up_source : {"given", "detected", "file"}
        Whether the unit / axis was given by the caller, detected from the body's
        size and shape, or read from the file's own parameters.
    center : np.ndarray [shape=(n_frames, 3)] [m], optional
        The JSON layout's per-frame root track, in the canonical frame; joint
        positions of the motion are absolute (file ``skeletons`` + ``center``).
    key : str, optional
        Array name in an ``.npz`` file.
    """

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
            f"({self.up_source}); "
            f"read as {CANONICAL_UNITS}, {CANONICAL_UP} up"
        )


@dataclass(frozen=True, eq=False)
class Motion:
    """Multi-channel motion sampled at a constant frame rate.

    Parameters
    ----------
    values : np.ndarray [shape=(n_frames, n_channels)]
        Rotations in degrees; positions in the file's units.
    fps : float > 0 [Hz]
    channels : tuple of str [len = n_channels]
    skeleton : Skeleton or None
    name : str
    position_info : PositionInfo or None
        Bones and file layout of a position-only motion (see :attr:`is_positional`).
    """

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
                    "<joint>_x/_y/_z); this motion has other channels"
                )
            if info.bones is not None:
                object.__setattr__(
                    self,
                    "position_info",
                    replace(info, bones=check_bones(info.bones, self.values.shape[1] // 3)),
                )

    # -- position-only motion ---------------------------------------------
    @property
    def is_positional(self) -> bool:
        """True for position-only motion: no skeleton, channels ``<joint>_x/_y/_z`` triples.

        MoCap Toolbox markers and joint positions read by :mod:`beatsync.io.positions`
        are position-only; BVH motion and angle tables are not.
        """
        if "positional" not in self._cache:
            ch = self.channels
            ok = self.skeleton is None and len(ch) >= 3 and len(ch) % 3 == 0
            if ok:
                for i in range(0, len(ch), 3):
                    stems = {c.rpartition("_")[0] for c in ch[i : i + 3]}
                    axes = tuple(c.rpartition("_")[2] for c in ch[i : i + 3])
                    if len(stems) != 1 or axes != ("x", "y", "z") or "" in stems:
                        ok = False
                        break
            self._cache["positional"] = ok
        return self._cache["positional"]

    @property
    def bones(self) -> np.ndarray:
        """Joint-index pairs ``(n_bones, 2)`` into axis 1 of :meth:`positions`.

        BVH: ``(joint, parent)`` from the skeleton. Position-only motion: the given
        bones, else inferred from constant joint distances (:func:`infer_bones`).
        """
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

    # -- basic properties -------------------------------------------------
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

    # -- derived motions ---------------------------------------------------
    def with_values(self, values: np.ndarray, fps: float | None = None) -> Motion:
        """Same channels and skeleton, new values (and optionally a new frame rate)."""
        return Motion(
            values=values,
            fps=self.fps if fps is None else fps,
            channels=self.channels,
            skeleton=self.skeleton,
            name=self.name,
            position_info=self.position_info,
        )

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

    # -- rotations and kinematics -----------------------------------------
    def rotation_triples(self) -> list[tuple[str, tuple[int, int, int], str]]:
        """Each joint with three rotation channels: ``(joint, channel indices, order)``.

        ``order`` is the intrinsic Euler order as listed in the file, e.g. ``"ZXY"``
        for ``Zrotation Xrotation Yrotation`` (R = Rz @ Rx @ Ry).
        """
        if "triples" in self._cache:
            return self._cache["triples"]
        out: list[tuple[str, tuple[int, int, int], str]] = []
        by_joint: dict[str, list[tuple[int, str]]] = {}
        order_seen: list[str] = []
        for i, ch in enumerate(self.channels):
            joint, _, dof = ch.rpartition("_")
            if dof in _ROT_DOFS:
                if joint not in by_joint:
                    by_joint[joint] = []
                    order_seen.append(joint)
                by_joint[joint].append((i, dof[0]))
        for joint in order_seen:
            items = by_joint[joint]
            if len(items) == 3:
                idx = tuple(i for i, _ in items)
                order = "".join(a for _, a in items)
                out.append((joint, idx, order))  # type: ignore[arg-type]
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
        """World positions of every joint and end site by forward kinematics.

        Position-only motion: the values reshaped (a view), no kinematics.

        Returns
        -------
        positions : np.ndarray [shape=(n_frames, n_joints, 3)]
            In the file's length units (position-only motion: metres, z up); axis 1
            follows :attr:`joint_names`.
        """
        if "positions" in self._cache:
            return self._cache["positions"]
        if self.skeleton is None and self.is_positional:
            pos = self.values.reshape(self.n_frames, -1, 3)
            self._cache["positions"] = pos
            return pos
        if self.skeleton is None:
            raise ParameterError(
                f"motion {self.name!r} has no skeleton (marker data or a plain table); "
                "joint positions need a BVH file"
            )
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
            if joint.parent < 0:
                pos[:, j_idx] = trans
                glob.append(local)
                continue
            parent_rot = glob[joint.parent]
            moved = trans if parent_rot is None else quat_rotate(parent_rot, trans)
            pos[:, j_idx] = pos[:, joint.parent] + moved
            if parent_rot is None or local is None:
                glob.append(local if parent_rot is None else parent_rot)
            else:
                glob.append(quat_multiply(parent_rot, local))
        self._cache["positions"] = pos
        return pos


def _check_reach(skeleton: Skeleton, values: np.ndarray) -> None:
    """Refuse offsets or translations so large that forward kinematics would overflow.

    A joint's world position is at most the sum, along its chain, of the offsets and
    translations (rotations keep lengths; each summed as ``|x| + |y| + |z|``, which
    bounds the length); that sum, times 2 sqrt(3) so that every coordinate of a
    position and of a difference of two stays finite, must be a finite float.
    """
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
    """Fill NaN gaps in every channel by linear interpolation (edges held constant).

    Marker data often has short dropouts (e.g. MoCap Toolbox ``walk1``).

    Raises
    ------
    ParameterError
        If a channel has no finite value at all.
    """
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
    cols = []
    for n in names:
        cols.append(
            np.stack([motion.values[:, motion.channel_index(f"{n}_{a}")] for a in "xyz"], axis=1)
        )
    return np.mean(cols, axis=0)


def _angle(a: np.ndarray, b: np.ndarray, c: np.ndarray) -> np.ndarray:
    """Angle ABC [deg] at vertex b between segments b->a and b->c, per frame."""
    u = a - b
    v = c - b
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
    """Joint angles [deg] from MoCap Toolbox markers (the 28-marker demo set).

    Each angle is the interior angle at a joint between its two segments
    (180 deg = straight), e.g. the knee angle between hip centre -> knee and
    ankle -> knee. NaN gaps in markers are filled linearly first.

    Parameters
    ----------
    motion : Motion
        Marker positions with channels ``"<marker>_x/_y/_z"`` (see
        :func:`beatsync.io.read_mocap_mat`).

    Returns
    -------
    Motion
        Channels ``knee_L_angle``, ``knee_R_angle``, ``hip_*``, ``ankle_*``,
        ``elbow_*``, ``shoulder_*``, ``neck_angle`` at the same frame rate.
    """
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
    """Angles [deg] between every two bones that meet at a joint, as a motion.

    For a position-only motion without a known marker set: each joint with two or
    more bones (:attr:`Motion.bones`) gives the interior angle between each pair of
    them (180 deg = straight), e.g. hip-knee-ankle. Such angles do not change when
    the dancer travels or turns, nor with body size or units, so they suit paper A's
    segmentation (which works on joint angles) where root-relative positions would
    follow every turn of a ballroom dance. NaN gaps are filled linearly first.

    Returns
    -------
    Motion
        Channels ``"<a>-<joint>-<b>_angle"`` at the same frame rate, no skeleton.
    """
    motion = fill_gaps(motion)
    pos = motion.positions()
    names = motion.joint_names
    neighbours: dict[int, list[int]] = {}
    for a, b in motion.bones:
        neighbours.setdefault(int(a), []).append(int(b))
        neighbours.setdefault(int(b), []).append(int(a))
    triples = [
        (nb[i], v, nb[k])
        for v, nb in sorted(neighbours.items())
        for i in range(len(nb))
        for k in range(i + 1, len(nb))
    ]
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
    """The joint-angle motion that segmentation works on (paper A works on joint angles).

    BVH motion and angle tables are returned as they are; MoCap Toolbox markers are
    turned into joint angles with :func:`marker_angles`; other position-only motion
    (e.g. keypoints without marker names) into the angles between its bones with
    :func:`bone_angles` (travel- and turn-invariant, see there).
    """
    if not is_marker_motion(motion):
        return motion
    if motion.is_positional and not has_marker_set(motion):
        return bone_angles(motion)
    return marker_angles(motion)
