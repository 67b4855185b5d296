"""Joint-position motion files: Dance-with-Melody JSON, ``.npy``/``.npz`` arrays, C3D.

Readers return a position-only :class:`~beatsync.motion.Motion` in the canonical frame
(metres, z up) whose :class:`~beatsync.motion.PositionInfo` records the file's layout,
units and vertical axis, which the writers restore. ``.json`` (Dance-with-Melody):
``{"length": N, "center": [N][3], "skeletons": [N][J][3]}``, joints relative to the
root track ``center``, no rate (the bundled dancers: 25 fps, cm, y up); ``.npy``: one
``(n_frames, n_joints, 3)`` array (AIST++ ``keypoints3d``); ``.npz``: such an array
under a key, with an optional scalar ``fps``; ``.c3d``: marker points (a negative
residual is a gap) with the file's rate, labels and ``POINT:UNITS``.

Units (``"m"``, ``"cm"``, ``"mm"``) and vertical axis (``"y"``, ``"z"``) are given or
detected: up is whichever of y and z the body extends along most (median over
frames), the unit the one that makes that extent 0.25-3 m. Gaps up to ``max_gap`` [s]
are filled (:func:`beatsync.joints.fill_joint_gaps`), longer ones refused.
"""

from __future__ import annotations

import json
import os
import warnings
from pathlib import Path
from typing import Any

import numpy as np

from ..errors import ParameterError
from ..motion import (
    UNIT_METRES,
    Motion,
    PositionInfo,
    fill_joint_gaps,
)
from ..validation import check_choice, check_fps, check_positive
from ._files import atomic_write, check_input_file, check_motion_output
from .tables import need_fps, read_npz

POSITION_SUFFIXES = (".json", ".npy", ".npz", ".c3d")
#: Plausible body height range [m] for detecting units.
_HEIGHT_M = (0.25, 3.0)
#: Preferred key of an AIST++-style archive.
_KEYPOINT_KEYS = ("keypoints3d", "keypoints3d_optim", "positions", "joints")


def _options(up: Any, units: Any, bones: Any, max_gap: Any) -> dict[str, Any]:
    """The readers' common options, checked (``up``/``units`` ``None``: detect)."""
    for name, value, choices in (("up", up, ("y", "z")), ("units", units, UNIT_METRES)):
        if value is not None:
            check_choice(value, choices, name=name)
    max_gap = check_positive(max_gap, name="max_gap", unit="s", allow_zero=True)
    return {"up": up, "units": units, "bones": bones, "max_gap": max_gap}


def _extents(pos: np.ndarray) -> np.ndarray:
    """Median over frames of the body's extent along x, y and z (file units)."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)  # all-NaN frames
        ext = np.nanmax(pos, axis=1) - np.nanmin(pos, axis=1)
        return np.nanmedian(ext, axis=0)


def detect_up(positions: Any) -> str:
    """The vertical axis (``"y"`` or ``"z"``): the longer body extent, by more than 15 %."""
    ext = _extents(np.asarray(positions, dtype=np.float64))
    ey, ez = float(ext[1]), float(ext[2])
    if ey > 1.15 * ez:
        return "y"
    if ez > 1.15 * ey:
        return "z"
    raise ParameterError(
        f"cannot tell the vertical axis: the body extends {ey:.3g} along y and {ez:.3g} "
        "along z (file units); give it with up='y' or up='z' (--up)"
    )


def detect_units(positions: Any, up: str) -> str:
    """The length unit (``"m"``, ``"cm"``, ``"mm"``) that makes the body 0.25-3 m tall."""
    h = float(_extents(np.asarray(positions, dtype=np.float64))["xyz".index(up)])
    for unit, scale in UNIT_METRES.items():
        if _HEIGHT_M[0] <= h * scale <= _HEIGHT_M[1]:
            return unit
    raise ParameterError(
        f"cannot tell the length unit: the body is {h:.3g} file units tall, which is not "
        "a human size (0.25-3 m) in metres, centimetres or millimetres; give it with "
        "units='m', 'cm' or 'mm' (--units)"
    )


def to_canonical(positions: Any, *, units: str, up: str) -> np.ndarray:
    """File positions -> metres, z up (right-handed: y up ``(x, y, z)`` -> ``(x, -z, y)``)."""
    p = np.asarray(positions, dtype=np.float64) * UNIT_METRES[units]
    if up == "y":
        p = np.stack([p[..., 0], -p[..., 2], p[..., 1]], axis=-1)
    return p


def from_canonical(positions: Any, *, units: str, up: str) -> np.ndarray:
    """Metres, z up -> the file's units and vertical axis (inverse of :func:`to_canonical`)."""
    p = np.asarray(positions, dtype=np.float64)
    if up == "y":
        p = np.stack([p[..., 0], p[..., 2], -p[..., 1]], axis=-1)
    return p / UNIT_METRES[units]


def _frame_of(pos: np.ndarray, units: str | None, up: str | None) -> tuple[str, str]:
    up = detect_up(pos) if up is None else up
    units = detect_units(pos, up) if units is None else units
    h = float(_extents(pos)["xyz".index(up)]) * UNIT_METRES[units]
    if not 0.05 <= h <= 10.0:
        raise ParameterError(
            f"with units={units!r} the body is {h:.3g} m tall: the unit looks wrong "
            f"(detected: {detect_units(pos, up) if h > 0 else '?'})"
        )
    return units, up


def _names(n_joints: int, names: Any = None) -> tuple[str, ...]:
    if names is None:
        return tuple(f"j{i}" for i in range(n_joints))
    out: list[str] = []
    for i, n in enumerate(names):
        clean = "_".join(str(n).split()) or f"j{i}"
        out.append(f"{clean}_{i}" if clean in out else clean)
    return tuple(out)


def _build(
    pos: np.ndarray,
    fps: float,
    name: str,
    source: str,
    layout: str,
    *,
    units: str | None,
    up: str | None,
    bones: Any,
    max_gap: float,
    file_frame: tuple[str | None, str | None] = (None, None),
    joint_names: Any = None,
    center: np.ndarray | None = None,
    key: str | None = None,
) -> Motion:
    """Check file positions ``(n, J, 3)``, fill gaps, convert, and make the Motion.

    ``file_frame``: the units and vertical axis the file states, used unless given.
    """
    if pos.ndim != 3 or pos.shape[2] != 3:
        raise ParameterError(
            f"{source} holds an array of shape {pos.shape}; joint positions must be "
            "(n_frames, n_joints, 3)"
        )
    n, n_j = pos.shape[0], pos.shape[1]
    if n_j < 2:
        raise ParameterError(
            f"{source} has {n_j} joint(s); a position-only motion needs at least 2 joints "
            "(is the array transposed? it must be frames x joints x 3)"
        )
    if n < 2:
        raise ParameterError(f"{source} has {n} frame(s); need at least 2")
    names = _names(n_j, joint_names)
    if center is not None:
        center = fill_joint_gaps(center[:, None], fps, max_gap=max_gap, joint_names=["center"])
        pos, center = pos + center, center[:, 0]
    pos = fill_joint_gaps(pos, fps, max_gap=max_gap, joint_names=names)
    units_source = "given" if units else "file" if file_frame[0] else "detected"
    up_source = "given" if up else "file" if file_frame[1] else "detected"
    units, up = _frame_of(pos, units or file_frame[0], up or file_frame[1])
    center = None if center is None else to_canonical(center, units=units, up=up)
    info = PositionInfo(bones, layout, units, up, units_source, up_source, center, key)
    values = to_canonical(pos, units=units, up=up).reshape(n, 3 * n_j)
    channels = tuple(f"{j}_{a}" for j in names for a in "xyz")
    return Motion(values, fps, channels, None, name, position_info=info)


def read_positions_json(
    path: str | os.PathLike[str],
    *,
    fps: float | None,
    up: str | None = None,
    units: str | None = None,
    bones: Any = None,
    max_gap: float = 0.25,
) -> Motion:
    """Read the Dance-with-Melody JSON layout at ``fps`` [Hz] (the file has none); ``up``,
    ``units`` detected and ``bones`` inferred unless given; joints ``j0``, ``j1``, ..."""
    p = check_input_file(path, "JSON motion")
    opts = _options(up, units, bones, max_gap)
    rate = need_fps(
        fps, f"{str(p)!r} (JSON joint positions)", "; the Dance-with-Melody dataset is 25 fps"
    )
    try:
        with open(p, encoding="utf-8") as fh:
            doc = json.load(fh)
    except (OSError, UnicodeDecodeError, json.JSONDecodeError) as exc:
        raise ParameterError(f"cannot read {str(p)!r} as JSON: {exc}") from None
    expected = (
        "expected the Dance-with-Melody layout: an object with 'skeletons' "
        "[frames][joints][3] (joint positions) and 'center' [frames][3] (root track), "
        "optionally 'length'"
    )
    if not isinstance(doc, dict) or "skeletons" not in doc:
        got = f"keys {sorted(doc)[:8]}" if isinstance(doc, dict) else type(doc).__name__
        raise ParameterError(f"{str(p)!r} is a JSON of another layout ({got}); {expected}")
    skel = _ragged_check(doc["skeletons"], "skeletons", p, 3)
    center = None
    if doc.get("center") is not None:
        center = _ragged_check(doc["center"], "center", p, 2)
        if center.shape[1:] != (3,) or center.shape[0] != skel.shape[0]:
            raise ParameterError(
                f"{str(p)!r}: 'center' has shape {center.shape} but 'skeletons' has "
                f"{skel.shape[0]} frames; {expected}"
            )
    length = doc.get("length")
    if length is not None and length != skel.shape[0]:
        raise ParameterError(
            f"{str(p)!r} says length={length!r} but 'skeletons' has {skel.shape[0]} frames "
            "(truncated or edited file?)"
        )
    name = p.parent.name if p.stem == "skeletons" else p.stem
    return _build(skel, rate, name, repr(str(p)), "json", center=center, **opts)


def _ragged_check(data: Any, what: str, p: Path, ndim: int) -> np.ndarray:
    """A nested list as a float array (``null`` -> NaN), refusing ragged nesting."""
    if not isinstance(data, list) or not data:
        raise ParameterError(f"{str(p)!r}: {what!r} must be a non-empty list of frames")
    try:
        arr = np.array(data, dtype=np.float64)  # null -> NaN
    except (TypeError, ValueError):
        arr = None
    if arr is not None and arr.ndim == ndim and arr.shape[-1] == 3:
        return arr
    layout = "[frames][joints][3]" if ndim == 3 else "[frames][3]"
    n0 = len(data[0]) if isinstance(data[0], list) else None
    for i, frame in enumerate(data):
        if not isinstance(frame, list):
            break
        if ndim == 3 and len(frame) != n0:
            raise ParameterError(
                f"{str(p)!r}: {what!r} is ragged: frame {i} has {len(frame)} joints, frame 0 "
                f"has {n0}; every frame needs the same joints ({layout})"
            )
        points = frame if ndim == 3 else [frame]
        for j, point in enumerate(points):
            if not isinstance(point, list) or len(point) != 3:
                size = len(point) if isinstance(point, list) else "not a list of"
                where = f"frame {i} joint {j}" if ndim == 3 else f"frame {i}"
                raise ParameterError(
                    f"{str(p)!r}: {what!r} is ragged: {where} has {size} coordinates; "
                    f"need 3 (x, y, z) per point ({layout})"
                )
    raise ParameterError(f"{str(p)!r}: {what!r} must be numbers nested as {layout}")


def write_positions_json(path: str | os.PathLike[str], motion: Motion) -> Path:
    """Write a position-only motion in the Dance-with-Melody JSON layout (atomic), in its
    file's units and axis; ``center``: its root track, else the joints' per-frame mean."""
    info = _positional_info(motion, Path(path))
    pos = motion.positions()
    center = info.center
    if center is None or len(center) != motion.n_frames:
        center = pos.mean(axis=1)
    skel = from_canonical(pos - center[:, None, :], units=info.units, up=info.up)
    c = from_canonical(center, units=info.units, up=info.up)
    doc = {"length": motion.n_frames, "center": c.tolist(), "skeletons": skel.tolist()}
    with atomic_write(path) as fh:
        json.dump(doc, fh, allow_nan=False)
    return Path(path)


def _positional_info(motion: Motion, path: Path) -> PositionInfo:
    check_motion_output(motion, path.suffix.lower(), path, as_positions=True)
    return motion.position_info or PositionInfo()


def read_positions_array(
    path: str | os.PathLike[str],
    *,
    fps: float | None = None,
    key: str | None = None,
    up: str | None = None,
    units: str | None = None,
    bones: Any = None,
    max_gap: float = 0.25,
) -> Motion:
    """Read joint positions ``(n_frames, n_joints, 3)`` from ``.npy`` or ``.npz``.

    ``fps`` [Hz] is required unless an ``.npz`` stores one (then it must agree); ``key``
    names the ``.npz`` array; the rest as for :func:`read_positions_json`.
    """
    p = check_input_file(path, "array")
    opts = _options(up, units, bones, max_gap)
    suffix = p.suffix.lower()
    file_fps = None
    if suffix == ".npz":
        arrays = read_npz(p)
        cands = [k for k, v in arrays.items() if v.ndim == 3 and v.shape[-1] == 3]
        found = [k for k in _KEYPOINT_KEYS if k in cands] or (cands if len(cands) == 1 else [])
        if key is None and not found:
            raise ParameterError(
                f"{str(p)!r} holds {'no' if not cands else 'several'} (frames, joints, 3) "
                f"arrays {cands} among {sorted(arrays)}; name one with key= (--variable)"
            )
        key = found[0] if key is None else key
        if key not in arrays:
            raise ParameterError(f"{str(p)!r} has no array {key!r}; it holds {sorted(arrays)}")
        pos = np.asarray(arrays[key], dtype=np.float64)
        for k in ("fps", "frame_rate", "framerate"):
            if k in arrays and arrays[k].size == 1:
                file_fps = check_fps(float(arrays[k]), name=f"{k} stored in {p.name}")
    else:
        try:
            pos = np.asarray(np.load(p, allow_pickle=False), dtype=np.float64)
        except Exception as exc:
            raise ParameterError(f"cannot read {str(p)!r} as a .npy array: {exc}") from None
    rate = _file_rate(fps, file_fps, p) if file_fps is not None else need_fps(fps, repr(str(p)))
    source = repr(str(p)) + (f" array {key!r}" if key else "")
    layout = suffix.lstrip(".")
    return _build(pos, rate, p.stem, source, layout, key=key, **opts)


def _file_rate(fps: Any, file_fps: float, p: Path) -> float:
    """The file's own rate; a given ``fps`` must agree with it."""
    if fps is not None:
        given = check_fps(fps)
        if abs(given - file_fps) > 1e-6 * file_fps:
            raise ParameterError(
                f"fps={fps!r} contradicts the frame rate stored in {str(p)!r} ({file_fps:g} Hz); "
                "leave fps out (the file's rate is used) or fix the file"
            )
    return file_fps


def write_positions_array(path: str | os.PathLike[str], motion: Motion) -> Path:
    """Write a position-only motion as ``(n_frames, n_joints, 3)`` (atomic), in its file's
    units and axis; ``.npz`` adds the scalar ``fps`` (array key default ``keypoints3d``)."""
    dest = Path(path)
    info = _positional_info(motion, dest)
    arr = from_canonical(motion.positions(), units=info.units, up=info.up)
    with atomic_write(dest, mode="wb") as fh:
        if dest.suffix.lower() == ".npz":
            np.savez(fh, **{info.key or "keypoints3d": arr, "fps": np.float64(motion.fps)})
        else:
            np.save(fh, arr)
    return dest


def read_c3d(
    path: str | os.PathLike[str],
    *,
    fps: float | None = None,
    up: str | None = None,
    units: str | None = None,
    bones: Any = None,
    max_gap: float = 0.25,
) -> Motion:
    """Read the marker points of a C3D file at its own rate (a given ``fps`` must agree);
    ``units``/``up`` default to ``POINT:UNITS``/``POINT:Y_SCREEN``, else are detected."""
    import c3d

    p = check_input_file(path, "C3D")
    opts = _options(up, units, bones, max_gap)
    try:
        with open(p, "rb") as fh, warnings.catch_warnings():
            warnings.simplefilter("ignore")  # "No analog data found" and the like
            reader = c3d.Reader(fh)
            n_points = int(reader.point_used)
            rate = float(reader.point_rate)
            labels = [str(s).strip() for s in reader.point_labels][:n_points] if n_points else []
            file_units = _param_str(reader, "POINT:UNITS")
            screen = _param_str(reader, "POINT:Y_SCREEN")
            declared = int(reader.frame_count)
            frames = []
            if n_points > 0:
                for _, points, _ in reader.read_frames():
                    xyz = np.array(points[:, :3], dtype=np.float64)
                    xyz[points[:, 3] < 0] = np.nan
                    frames.append(xyz)
    except Exception as exc:  # the c3d package raises several types for bad files
        raise ParameterError(f"cannot read {str(p)!r} as a C3D file: {exc}") from None
    if n_points == 0 or not frames:
        raise ParameterError(
            f"{str(p)!r} is a C3D file without marker points (only analog data?); "
            "beatsync needs 3-D points"
        )
    if len(frames) < declared:  # the c3d package stops at the end with a warning (ignored)
        raise ParameterError(
            f"C3D file {str(p)!r} is cut short: its header declares {declared} frames "
            f"but it holds {len(frames)}; an interrupted copy or download? Copy the file again"
        )
    rate = _file_rate(fps, check_fps(rate, name=f"point rate of {p.name}"), p)
    file_unit = file_units.lower() if file_units.lower() in UNIT_METRES else None
    file_up = screen[1].lower() if screen.upper() in ("+Y", "+Z") else None
    names = labels if len(labels) == n_points else None
    pos, frame = np.stack(frames), (file_unit, file_up)
    return _build(
        pos, rate, p.stem, repr(str(p)), "c3d", file_frame=frame, joint_names=names, **opts
    )


def _param_str(reader: Any, name: str) -> str:
    try:  # None (no such parameter) has no string_value either
        return str(reader.get(name).string_value).strip()
    except Exception:
        return ""


def write_c3d(path: str | os.PathLike[str], motion: Motion) -> Path:
    """Write a position-only motion as C3D float points (atomic), in its file's units and
    axis (without one: mm, z up, the usual C3D convention)."""
    import c3d

    info = _positional_info(motion, Path(path))
    units = info.units if motion.position_info is not None else "mm"
    pos = from_canonical(motion.positions(), units=units, up=info.up).astype(np.float32)
    writer = c3d.Writer(point_rate=float(motion.fps), point_units=f"{units:<4}")
    writer.set_point_labels([n[:30] for n in motion.joint_names])
    analog = np.zeros((0, 0), dtype=np.float32)
    residual = np.zeros((pos.shape[1], 2), dtype=np.float32)
    writer.add_frames([(np.hstack([frame, residual]), analog) for frame in pos])
    with atomic_write(path, mode="wb") as fh, warnings.catch_warnings():
        warnings.simplefilter("ignore")
        writer.write(fh)
    return Path(path)
