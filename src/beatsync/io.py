"""Reading and writing files: the only module of beatsync that touches the disk.

Data contract
-------------
- Motion files become a :class:`~beatsync.motion.Motion` (values ``(n_frames,
  n_channels)``, ``fps`` [Hz], channel names, skeleton for BVH).
- Audio becomes mono float32 ``y`` with its sample rate ``sr`` [Hz].
- Beat annotation files hold one time in seconds per line (first column); extra
  columns (e.g. beat-in-bar) are ignored.
- Every write is atomic: data goes to a temporary file in the destination folder,
  which is renamed over the destination only when complete. Nothing is written when
  an error is raised.
"""

from __future__ import annotations

import contextlib
import json
import os
import tempfile
import warnings
from collections.abc import Iterator
from pathlib import Path
from typing import IO, Any

import numpy as np

from .errors import ParameterError
from .motion import Joint, Motion, Skeleton
from .units import check_finite, check_fps, check_times

__all__ = [
    "atomic_write",
    "check_output_folder",
    "read_motion",
    "read_bvh",
    "write_bvh",
    "read_mocap_mat",
    "read_table",
    "write_table",
    "read_audio",
    "write_audio",
    "read_beats",
    "write_beats",
    "write_json",
    "write_csv",
    "sha256_file",
    "read_npz",
    "write_npz",
    "AUDIO_SUFFIXES",
    "MOTION_SUFFIXES",
]

MOTION_SUFFIXES = (".bvh", ".mat", ".csv", ".npy")
AUDIO_SUFFIXES = (".wav", ".flac", ".ogg", ".mp3", ".aiff", ".aif", ".m4a")


def _existing_file(path: str | os.PathLike[str], what: str) -> Path:
    p = Path(path)
    if not p.exists():
        raise ParameterError(f"{what} file {str(p)!r} does not exist")
    if not p.is_file():
        raise ParameterError(f"{what} path {str(p)!r} is not a file")
    if p.stat().st_size == 0:
        raise ParameterError(f"{what} file {str(p)!r} is empty")
    return p


def _new_file_mode(dest: Path) -> int:
    """Permissions for a written file: the existing file's, else 0o666 less the umask."""
    if dest.exists():
        return dest.stat().st_mode & 0o777
    umask = os.umask(0)
    os.umask(umask)
    return 0o666 & ~umask


def check_output_folder(path: str | os.PathLike[str]) -> Path:
    """Refuse an output path whose folder is missing or not writable; return its folder."""
    parent = Path(path).resolve().parent
    if not parent.is_dir():
        raise ParameterError(f"output folder {str(parent)!r} does not exist; create it first")
    if not os.access(parent, os.W_OK):
        raise ParameterError(f"output folder {str(parent)!r} is not writable")
    return parent


@contextlib.contextmanager
def atomic_write(path: str | os.PathLike[str], mode: str = "w") -> Iterator[IO[Any]]:
    """Open a temporary file next to ``path``; rename it to ``path`` on success.

    On any exception the temporary file is removed and ``path`` is untouched.
    """
    dest = Path(path)
    parent = check_output_folder(dest)
    fd, tmp = tempfile.mkstemp(prefix=f".{dest.name}.", suffix=".tmp", dir=parent)
    try:
        with os.fdopen(fd, mode) as fh:
            yield fh
            fh.flush()
            os.fsync(fh.fileno())
        os.chmod(tmp, _new_file_mode(dest))
        os.replace(tmp, dest)
    except BaseException:
        with contextlib.suppress(FileNotFoundError):
            os.unlink(tmp)
        raise


# --------------------------------------------------------------------------- BVH


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
    p = _existing_file(path, "BVH")
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


# --------------------------------------------------------------- other motion


def read_mocap_mat(path: str | os.PathLike[str], variable: str | None = None) -> Motion:
    """Read marker data from a MoCap Toolbox ``.mat`` file (MATLAB v5 struct).

    Parameters
    ----------
    path : path-like
    variable : str
        Name of the struct, e.g. ``"dance2"``; may be omitted if the file has only one.

    Returns
    -------
    Motion
        Marker positions in metres (the toolbox stores mm), channels
        ``"<marker>_x"``, ``"_y"``, ``"_z"`` (z up), ``fps`` from the struct's
        ``freq``, no skeleton. NaN gaps are kept (see :func:`beatsync.motion.fill_gaps`).
    """
    import scipy.io

    p = _existing_file(path, "MAT")
    try:
        mat = scipy.io.loadmat(p, squeeze_me=True, struct_as_record=False)
    except Exception as exc:  # scipy raises several types for bad files
        raise ParameterError(f"cannot read {str(p)!r} as a MATLAB .mat file: {exc}") from None
    cands = [
        k
        for k, v in mat.items()
        if not k.startswith("__") and hasattr(v, "data") and hasattr(v, "markerName")
    ]
    if variable is None:
        if len(cands) != 1:
            raise ParameterError(
                f"{str(p)!r} holds several marker recordings {cands}; choose one with "
                "variable= (--variable on the command line)"
            )
        variable = cands[0]
    if variable not in cands:
        raise ParameterError(
            f"{str(p)!r} has no marker recording {variable!r}; choose from {cands}"
        )
    s = mat[variable]
    data = np.asarray(s.data, dtype=np.float64)
    names = [str(n) for n in np.atleast_1d(s.markerName)]
    if data.ndim != 2 or data.shape[1] != 3 * len(names):
        raise ParameterError(
            f"{variable!r} data has shape {data.shape}, expected (frames, 3 x {len(names)} markers)"
        )
    channels = tuple(f"{m}_{a}" for m in names for a in "xyz")
    return Motion(data / 1000.0, float(s.freq), channels, None, variable)


def read_table(
    path: str | os.PathLike[str], *, fps: float | None, channels: list[str] | None = None
) -> Motion:
    """Read a plain joint-angle table: ``.csv`` with a header row, or ``.npy`` ``(n, c)``.

    Parameters
    ----------
    fps : float > 0 [Hz]
        Required: tables carry no frame rate.
    channels : list of str, optional
        Names for ``.npy`` columns (default ``"ch0"``, ``"ch1"``, ...).
    """
    p = _existing_file(path, "table")
    if fps is None:
        raise ParameterError(
            f"{str(p)!r} is a plain table without a frame rate: give it with fps= (--fps)"
        )
    rate = check_fps(fps)
    if p.suffix.lower() == ".npy":
        try:
            values = np.load(p, allow_pickle=False)
        except Exception as exc:
            raise ParameterError(f"cannot read {str(p)!r} as a .npy array: {exc}") from None
        if values.ndim != 2:
            raise ParameterError(f"{str(p)!r} holds shape {values.shape}; need (frames, channels)")
        names = tuple(channels) if channels else tuple(f"ch{i}" for i in range(values.shape[1]))
    else:
        import pandas as pd

        try:
            df = pd.read_csv(p)
        except Exception as exc:
            raise ParameterError(
                f"cannot read {str(p)!r} as CSV with a header row: {exc}"
            ) from None
        non_num = [c for c in df.columns if not np.issubdtype(df[c].dtype, np.number)]
        if non_num:
            raise ParameterError(
                f"{str(p)!r} has non-numeric columns {non_num[:5]}; the first row must be "
                "channel names and every other row numbers"
            )
        names = tuple(str(c) for c in df.columns)
        if all(_is_number(c) for c in names):
            raise ParameterError(
                f"the first row of {str(p)!r} is numbers, not channel names: add a header "
                "row (e.g. knee_L,knee_R,...) or save the array as .npy"
            )
        values = df.to_numpy(dtype=np.float64)
    values = check_finite(values, name=f"{p.name} values")
    if values.shape[0] < 2:
        raise ParameterError(f"{str(p)!r} has {values.shape[0]} frame(s); need at least 2")
    return Motion(values, rate, names, None, p.stem)


def _is_number(text: str) -> bool:
    try:
        float(text)
    except ValueError:
        return False
    return True


def write_table(path: str | os.PathLike[str], motion: Motion) -> Path:
    """Write motion values as CSV with a header row of channel names (atomic)."""
    import pandas as pd

    return write_csv(path, pd.DataFrame(motion.values, columns=list(motion.channels)))


def read_motion(
    path: str | os.PathLike[str], *, fps: float | None = None, variable: str | None = None
) -> Motion:
    """Read any supported motion file, chosen by its suffix.

    ``.bvh`` (``fps`` overrides the header), ``.mat`` (MoCap Toolbox markers;
    ``variable`` names the recording), ``.csv``/``.npy`` (``fps`` required).
    """
    p = Path(path)
    suffix = p.suffix.lower()
    if suffix == ".bvh":
        return read_bvh(p, fps=fps)
    if suffix == ".mat":
        m = read_mocap_mat(p, variable)
        if fps is not None:
            m = m.with_values(m.values, fps=fps)
        return m
    if suffix in (".csv", ".npy"):
        return read_table(p, fps=fps)
    raise ParameterError(
        f"unsupported motion file {str(p)!r}: expected one of {', '.join(MOTION_SUFFIXES)}"
    )


# ----------------------------------------------------------------------- audio


def read_audio(path: str | os.PathLike[str], *, sr: int | None = None) -> tuple[np.ndarray, int]:
    """Read an audio file as mono float32.

    Parameters
    ----------
    path : path-like
        WAV, FLAC, OGG, MP3, ... (libsndfile; other formats through librosa/audioread).
    sr : int > 0 [Hz], optional
        Resample to this rate; default keeps the file's rate.

    Returns
    -------
    y : np.ndarray [shape=(n,)], float32
    sr : int [Hz]

    Raises
    ------
    ParameterError
        Missing, empty or unreadable file; no samples; NaN/inf samples.
    """
    import soundfile as sf

    p = _existing_file(path, "audio")
    if sr is not None and (not np.isfinite(sr) or sr <= 0):
        raise ParameterError(f"sr={sr!r} must be a sample rate > 0 [Hz]")
    try:
        data, file_sr = sf.read(p, dtype="float32", always_2d=True)
        y = data.mean(axis=1)
    except Exception:
        try:
            import librosa

            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                y, file_sr = librosa.load(p, sr=None, mono=True)
        except Exception as exc:
            raise ParameterError(
                f"cannot read {str(p)!r} as audio ({type(exc).__name__}); "
                "is it a WAV/FLAC/OGG/MP3 file?"
            ) from None
    y = np.asarray(y, dtype=np.float32)
    if y.size == 0:
        raise ParameterError(f"audio file {str(p)!r} has no samples")
    if not np.all(np.isfinite(y)):
        raise ParameterError(f"audio file {str(p)!r} contains NaN or infinite samples")
    file_sr = int(file_sr)
    if sr is not None and int(sr) != file_sr:
        import librosa

        y = librosa.resample(y, orig_sr=file_sr, target_sr=int(sr)).astype(np.float32)
        file_sr = int(sr)
    return y, file_sr


def write_audio(path: str | os.PathLike[str], y: np.ndarray, sr: int) -> Path:
    """Write mono or ``(n, channels)`` audio; format from the suffix (atomic)."""
    import soundfile as sf

    dest = Path(path)
    y = check_finite(y, name="audio samples").astype(np.float32)
    if sr is None or sr <= 0:
        raise ParameterError(f"sr={sr!r} must be a sample rate > 0 [Hz]")
    fmt = dest.suffix.lstrip(".").upper() or "WAV"
    if fmt not in sf.available_formats():
        raise ParameterError(f"cannot write audio as {dest.suffix!r}; use .wav or .flac")
    with atomic_write(dest, "wb") as fh:
        sf.write(fh, y, int(sr), format=fmt)
    return dest


# ----------------------------------------------------------------------- beats


def read_beats(path: str | os.PathLike[str]) -> np.ndarray:
    """Read beat (or any event) times in seconds from the first column of a text file.

    Blank lines and lines starting with ``#`` are skipped; other columns are ignored.

    Raises
    ------
    ParameterError
        Unreadable file, non-numeric values, or times that are not increasing seconds.
    """
    p = _existing_file(path, "beat annotation")
    times = []
    try:
        text = p.read_text()
    except (UnicodeDecodeError, OSError) as exc:
        raise ParameterError(f"cannot read {str(p)!r} as a text file of times: {exc}") from None
    for n, line in enumerate(text.splitlines(), 1):
        s = line.strip()
        if not s or s.startswith("#"):
            continue
        first = s.replace(",", " ").split()[0]
        try:
            times.append(float(first))
        except ValueError:
            raise ParameterError(
                f"{str(p)!r} line {n}: {first!r} is not a time in seconds"
            ) from None
    return check_times(np.array(times), name=f"beat times in {p.name}", allow_empty=False)


def write_beats(path: str | os.PathLike[str], times: np.ndarray) -> Path:
    """Write event times [s], one per line with 6 decimals (atomic)."""
    t = check_times(times, name="beat times")
    with atomic_write(path) as fh:
        fh.write("".join(f"{x:.6f}\n" for x in t))
    return Path(path)


def write_json(path: str | os.PathLike[str], obj: Any) -> Path:
    """Write ``obj`` as indented JSON (numpy values converted) (atomic)."""
    from .commands._common import to_jsonable

    with atomic_write(path) as fh:
        json.dump(to_jsonable(obj), fh, indent=2, allow_nan=False)
        fh.write("\n")
    return Path(path)


def write_csv(path: str | os.PathLike[str], frame: Any) -> Path:
    """Write a pandas DataFrame as CSV without its index (atomic)."""
    with atomic_write(path) as fh:
        frame.to_csv(fh, index=False)
    return Path(path)


# ------------------------------------------------------------------ binaries


def sha256_file(path: str | os.PathLike[str]) -> str:
    """SHA-256 hex digest of a file's bytes."""
    import hashlib

    p = _existing_file(path, "input")
    h = hashlib.sha256()
    with open(p, "rb") as fh:
        for chunk in iter(lambda: fh.read(1 << 20), b""):
            h.update(chunk)
    return h.hexdigest()


def read_npz(path: str | os.PathLike[str]) -> dict[str, np.ndarray]:
    """Read every array of an ``.npz`` file (no pickles)."""
    p = _existing_file(path, "npz")
    try:
        with np.load(p, allow_pickle=False) as data:
            return {k: data[k] for k in data.files}
    except (OSError, ValueError) as exc:
        raise ParameterError(f"cannot read {str(p)!r} as an .npz archive: {exc}") from None


def write_npz(path: str | os.PathLike[str], arrays: dict[str, np.ndarray]) -> Path:
    """Write named arrays as an uncompressed ``.npz`` file (atomic)."""
    with atomic_write(path, mode="wb") as fh:
        np.savez(fh, **arrays)
    return Path(path)
