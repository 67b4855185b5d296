"""Files in general: atomic writes, output-folder checks, JSON/CSV writers, checksums."""

from __future__ import annotations

import contextlib
import hashlib
import json
import os
import tempfile
from collections.abc import Iterator
from pathlib import Path
from typing import IO, Any

import numpy as np

from ..errors import ParameterError


def check_input_file(path: str | os.PathLike[str], what: str) -> Path:
    """``path`` as a Path, checked to be an existing, non-empty file (``what``: its kind)."""
    p = Path(path)
    if not p.exists():
        raise ParameterError(f"{what} file {str(p)!r} does not exist")
    if not p.is_file():
        raise ParameterError(f"{what} path {str(p)!r} is not a file")
    if p.stat().st_size == 0:
        raise ParameterError(f"{what} file {str(p)!r} is empty")
    return p


def check_motion_output(
    motion: Any, suffix: str, path: str | os.PathLike[str], *, as_positions: bool = False
) -> None:
    """Refuse to write ``motion`` to ``path`` as ``suffix`` when that format cannot hold
    it: BVH stores the rotations of a skeleton; .json, .npz and .c3d (and any suffix
    ``as_positions``) joint positions."""
    if suffix == ".bvh" and motion.skeleton is None:
        what, alt = "a table without a skeleton", ".csv (write_table)"
        if motion.is_positional:
            what = "joint positions without joint rotations"
            alt = ".json, .npy or .c3d (positions, in the input's layout) or .csv"
        raise ParameterError(
            f"cannot write {str(path)!r} as BVH: motion {motion.name!r} is {what}, and BVH "
            f"stores rotations of a skeleton; write {alt}"
        )
    if (as_positions or suffix in (".json", ".npz", ".c3d")) and not motion.is_positional:
        raise ParameterError(
            f"cannot write {str(path)!r}: motion {motion.name!r} is not joint positions "
            f"(channels <joint>_x/_y/_z), so it cannot be written as {suffix} joint "
            "positions; write .bvh (rotation data with a skeleton) or a .csv table"
        )


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


def to_jsonable(obj: Any, *, float_digits: int | None = None) -> Any:
    """Numpy values and paths inside ``obj`` as plain JSON types; NaN/inf become ``None``.

    ``float_digits`` rounds every float to that many significant digits (1-17).
    """
    d = float_digits
    if d is not None and (
        isinstance(d, bool) or not isinstance(d, (int, np.integer)) or not 1 <= d <= 17
    ):
        raise ParameterError(
            f"float_digits={d!r} must be a whole number of significant digits, 1-17 (a "
            "float64 has 17)"
        )
    return _jsonable(obj, None if d is None else int(d))


def _jsonable(obj: Any, digits: int | None) -> Any:
    if isinstance(obj, dict):
        return {str(k): _jsonable(v, digits) for k, v in obj.items()}
    if isinstance(obj, (list, tuple)):
        return [_jsonable(v, digits) for v in obj]
    if isinstance(obj, np.ndarray):
        return _jsonable(obj.tolist(), digits)
    if isinstance(obj, (bool, np.bool_)):
        return bool(obj)
    if isinstance(obj, np.integer):
        return int(obj)
    if isinstance(obj, (float, np.floating)):
        value = float(obj)
        if not np.isfinite(value):
            return None  # JSON has no NaN/Infinity
        return float(f"{value:.{digits}g}") if digits is not None else value
    if isinstance(obj, Path):
        return str(obj)
    return obj


def write_json(path: str | os.PathLike[str], obj: Any, *, float_digits: int | None = None) -> Path:
    """Write :func:`to_jsonable` of ``obj`` as indented JSON (atomic).

    ``float_digits`` rounds floats so that a committed file's last digits do not change
    when another BLAS or CPU computes the same numbers (10 digits: a relative 5e-11).
    """
    data = to_jsonable(obj, float_digits=float_digits)
    with atomic_write(path) as fh:
        json.dump(data, fh, indent=2, allow_nan=False)
        fh.write("\n")
    return Path(path)


def write_csv(path: str | os.PathLike[str], frame: Any, *, float_format: str | None = None) -> Path:
    """Write a pandas DataFrame as CSV without its index (atomic).

    ``float_format`` (a printf format such as ``"%.6g"``) fixes the precision of floats.
    """
    with atomic_write(path) as fh:
        frame.to_csv(fh, index=False, float_format=float_format)
    return Path(path)


def read_jsonl(path: str | os.PathLike[str]) -> list[dict[str, Any]]:
    """The JSON objects of a JSON-lines file ([] if none); a torn line (a killed run) is skipped."""
    p = Path(path)
    if not p.is_file():
        return []
    rows = []
    with open(p, encoding="utf-8", errors="replace") as fh:
        for line in fh:
            try:
                row = json.loads(line)
            except ValueError:
                continue
            if isinstance(row, dict):
                rows.append(row)
    return rows


def _jsonl_line(row: dict[str, Any]) -> str:
    return json.dumps(to_jsonable(row), allow_nan=False) + "\n"


def write_jsonl(path: str | os.PathLike[str], rows: Any) -> Path:
    """Write ``rows`` (dicts) as a JSON-lines file, one object per line (atomic)."""
    with atomic_write(path) as fh:
        for row in rows:
            fh.write(_jsonl_line(row))
    return Path(path)


def append_jsonl(path: str | os.PathLike[str], *rows: dict[str, Any]) -> Path:
    """Append objects to a JSON-lines file in one write, flushed to disk (``fsync``).

    A crash loses at most the lines being written; a torn last line is ended first.
    """
    p = Path(path)
    line = "".join(_jsonl_line(row) for row in rows)
    torn = False
    if p.is_file() and p.stat().st_size > 0:
        with open(p, "rb") as fh:
            fh.seek(-1, os.SEEK_END)
            torn = fh.read(1) != b"\n"
    with open(p, "a", encoding="utf-8") as fh:
        fh.write(("\n" if torn else "") + line)
        fh.flush()
        os.fsync(fh.fileno())
    return p


def sha256_file(path: str | os.PathLike[str]) -> str:
    """SHA-256 hex digest of a file's bytes."""
    with open(check_input_file(path, "input"), "rb") as fh:
        return hashlib.file_digest(fh, "sha256").hexdigest()
