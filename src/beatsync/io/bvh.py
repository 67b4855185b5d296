"""BVH motion files: read (with a frame-rate override) and write (exact round trip)."""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np

from ..errors import ParameterError
from ..motion import Joint, Motion, Skeleton
from ..units import check_finite, check_fps
from ._files import atomic_write, check_input_file


def _parse_hierarchy(tokens: list[str], path: Path) -> tuple[Skeleton, int]:
    joints: list[Joint] = []
    i = 0
    stack: list[int] = []
    pending_parent = -1

    def err(msg: str) -> ParameterError:
        return ParameterError(f"malformed BVH {str(path)!r}: {msg}")

    if not tokens or tokens[0].upper() != "HIERARCHY":
        raise err("it does not start with HIERARCHY (is it a BVH file?)")
    i = 1
    n = len(tokens)
    while i < n:
        tok = tokens[i]
        up = tok.upper()
        if up in ("ROOT", "JOINT"):
            if i + 2 >= n:
                raise err("file ends inside a joint definition (truncated?)")
            name = tokens[i + 1]
            if tokens[i + 2] != "{":
                raise err(f"expected '{{' after {tok} {name}")
            parent = stack[-1] if stack else -1
            if up == "ROOT" and stack:
                raise err("ROOT inside another joint")
            joints.append(Joint(name, parent, np.zeros(3)))
            stack.append(len(joints) - 1)
            i += 3
        elif up == "END":
            if i + 2 >= n or tokens[i + 1].upper() != "SITE" or tokens[i + 2] != "{":
                raise err("malformed End Site")
            parent = stack[-1] if stack else -1
            pname = joints[parent].name if parent >= 0 else "root"
            joints.append(Joint(f"{pname}_end", parent, np.zeros(3), (), True))
            stack.append(len(joints) - 1)
            i += 3
        elif up == "OFFSET":
            if not stack:
                raise err("OFFSET outside a joint")
            try:
                off = np.array([float(t) for t in tokens[i + 1 : i + 4]])
            except ValueError:
                raise err(f"bad OFFSET values {tokens[i + 1 : i + 4]}") from None
            if off.shape != (3,):
                raise err("OFFSET needs three numbers (truncated?)")
            j = joints[stack[-1]]
            joints[stack[-1]] = Joint(j.name, j.parent, off, j.channels, j.is_end_site)
            i += 4
        elif up == "CHANNELS":
            if not stack:
                raise err("CHANNELS outside a joint")
            try:
                k = int(tokens[i + 1])
            except (ValueError, IndexError):
                raise err("CHANNELS needs a count") from None
            chans = tuple(tokens[i + 2 : i + 2 + k])
            valid = {"Xposition", "Yposition", "Zposition", "Xrotation", "Yrotation", "Zrotation"}
            if len(chans) != k or not set(chans) <= valid:
                raise err(f"bad CHANNELS list {chans}")
            j = joints[stack[-1]]
            joints[stack[-1]] = Joint(j.name, j.parent, j.offset, chans, j.is_end_site)
            i += 2 + k
        elif tok == "}":
            if not stack:
                raise err("unbalanced '}'")
            stack.pop()
            i += 1
        elif up == "MOTION":
            if stack:
                raise err("MOTION section starts before the hierarchy is closed (truncated?)")
            pending_parent = i + 1
            break
        else:
            raise err(f"unexpected token {tok!r}")
    if pending_parent < 0:
        raise err("no MOTION section (file truncated?)")
    if not joints:
        raise err("no joints in the hierarchy")
    names = [j.name for j in joints]
    if len(set(names)) != len(names):
        dup = sorted({x for x in names if names.count(x) > 1})
        raise err(f"duplicate joint names {dup}")
    return Skeleton(tuple(joints)), pending_parent


def read_bvh(path: str | os.PathLike[str], *, fps: float | None = None) -> Motion:
    """Read a BVH file.

    Parameters
    ----------
    path : path-like
    fps : float > 0 [Hz], optional
        Override the frame rate declared by ``Frame Time`` (the CMU salsa BVH files
        declare 120 fps but are 60 fps).

    Returns
    -------
    Motion
        Channels ``"<joint>_<dof>"`` in file order, rotations in degrees.

    Raises
    ------
    ParameterError
        Missing, truncated or malformed file; frame lines with the wrong number of
        values; a frame count that does not match; NaN/inf values; a bad frame time.
    """
    p = check_input_file(path, "BVH")
    try:
        text = p.read_text()
    except (UnicodeDecodeError, OSError) as exc:
        raise ParameterError(f"cannot read BVH {str(p)!r} as text: {exc}") from None
    head, sep, motion_part = text.partition("MOTION")
    if not sep:
        raise ParameterError(f"malformed BVH {str(p)!r}: no MOTION section (file truncated?)")
    skeleton, _ = _parse_hierarchy(head.split() + ["MOTION"], p)
    lines = motion_part.strip("\n").splitlines()
    header: dict[str, str] = {}
    k = 0
    while k < len(lines) and len(header) < 2:
        line = lines[k].strip()
        k += 1
        if not line:
            continue
        key, colon, val = line.partition(":")
        if not colon:
            raise ParameterError(f"malformed BVH {str(p)!r}: expected 'Frames:' and 'Frame Time:'")
        header[key.strip().lower()] = val.strip()
    try:
        n_declared = int(header["frames"])
        frame_time = float(header["frame time"])
    except (KeyError, ValueError):
        raise ParameterError(
            f"malformed BVH {str(p)!r}: missing or bad 'Frames:'/'Frame Time:' header"
        ) from None
    n_ch = len(skeleton.channel_names())
    rows = [ln for ln in lines[k:] if ln.strip()]
    if len(rows) != n_declared:
        raise ParameterError(
            f"BVH {str(p)!r} declares {n_declared} frames but has {len(rows)} frame lines "
            "(file truncated or edited?)"
        )
    if n_declared == 0:
        raise ParameterError(f"BVH {str(p)!r} has no frames")
    try:
        flat = np.array(" ".join(rows).split(), dtype=np.float64)
    except ValueError:
        raise ParameterError(f"BVH {str(p)!r} has non-numeric values in its frame lines") from None
    if flat.size != n_declared * n_ch:
        counts = [len(r.split()) for r in rows]
        bad = next(i for i, c in enumerate(counts) if c != n_ch)
        raise ParameterError(
            f"BVH {str(p)!r}: frame line {bad + 1} has {counts[bad]} values but the hierarchy "
            f"defines {n_ch} channels"
        )
    values = flat.reshape(n_declared, n_ch)
    check_finite(values, name=f"BVH {p.name} values")
    if fps is None:
        if not np.isfinite(frame_time) or frame_time <= 0:
            raise ParameterError(
                f"BVH {str(p)!r} has Frame Time {frame_time!r}; give the frame rate with fps="
            )
        rate = 1.0 / frame_time
    else:
        rate = check_fps(fps)
    return Motion(values, rate, skeleton.channel_names(), skeleton, p.stem)


def _fmt(x: float) -> str:
    return repr(float(x))


def write_bvh(path: str | os.PathLike[str], motion: Motion) -> Path:
    """Write ``motion`` as BVH with its skeleton; atomic.

    Values are written with the shortest decimal that round-trips exactly, so
    ``read_bvh(write_bvh(p, m))`` gives identical values and frame rate.
    """
    if motion.skeleton is None:
        raise ParameterError(
            f"motion {motion.name!r} has no skeleton (marker data or a plain table) and "
            "cannot be written as BVH; write it as CSV (write_table) instead"
        )
    check_finite(motion.values, name="motion values")
    joints = motion.skeleton.joints
    children: dict[int, list[int]] = {i: [] for i in range(-1, len(joints))}
    for i, j in enumerate(joints):
        children[j.parent].append(i)
    out: list[str] = ["HIERARCHY"]

    def emit(i: int, depth: int) -> None:
        j = joints[i]
        ind = "\t" * depth
        if j.is_end_site:
            out.append(f"{ind}End Site")
        else:
            out.append(f"{ind}{'ROOT' if j.parent < 0 else 'JOINT'} {j.name}")
        out.append(f"{ind}{{")
        out.append(f"{ind}\tOFFSET {' '.join(_fmt(v) for v in j.offset)}")
        if not j.is_end_site:
            out.append(f"{ind}\tCHANNELS {len(j.channels)} {' '.join(j.channels)}")
        for c in children[i]:
            emit(c, depth + 1)
        out.append(f"{ind}}}")

    for r in children[-1]:
        emit(r, 0)
    out.append("MOTION")
    out.append(f"Frames: {motion.n_frames}")
    out.append(f"Frame Time: {_fmt(1.0 / motion.fps)}")
    body = "\n".join(" ".join(map(repr, row)) for row in motion.values.tolist())
    with atomic_write(path) as fh:
        fh.write("\n".join(out) + "\n" + body + "\n")
    return Path(path)
