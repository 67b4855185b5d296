"""Files in general: atomic writes, output-folder checks, JSON/CSV writers, checksums."""

from __future__ import annotations

import contextlib
import json
import os
import tempfile
from collections.abc import Iterator
from pathlib import Path
from typing import IO, Any

import numpy as np

from ..errors import ParameterError


def check_input_file(path: str | os.PathLike[str], what: str) -> Path:
    """Return ``path`` as a Path after checking it is an existing, non-empty file.

    ``what`` names the kind of file in messages (``"BVH"``, ``"audio"``).
    """
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


def to_jsonable(obj: Any, *, float_digits: int | None = None) -> Any:
    """Convert numpy scalars/arrays and paths inside ``obj`` to plain JSON types.

    Non-finite floats become ``None`` (``null``): strict JSON has no NaN.
    ``float_digits`` rounds every float to that many significant digits (see
    :func:`write_json`); ``None`` keeps floats exact.
    """
    if float_digits is not None:
        float_digits = _check_digits(float_digits)
    return _jsonable(obj, float_digits)


def _check_digits(digits: Any) -> int:
    if isinstance(digits, bool) or not isinstance(digits, (int, np.integer)):
        raise ParameterError(f"float_digits={digits!r} must be a whole number of digits, 1-17")
    if not 1 <= int(digits) <= 17:
        raise ParameterError(
            f"float_digits={digits!r} must be in 1-17 significant digits (a float64 has 17)"
        )
    return int(digits)


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
    """Write ``obj`` as indented JSON (numpy values converted) (atomic).

    Parameters
    ----------
    path : path-like
    obj : dict, list, numbers, strings, numpy arrays and scalars, paths
        NaN and infinite floats are written as ``null``.
    float_digits : int in 1-17, optional
        Round every float to this many significant digits before writing, so a
        committed file does not change in its last digits when the same numbers are
        computed through another BLAS or CPU path (10 digits keep every value to a
        relative 5e-11 and hide float64 rounding noise). ``None`` (default) writes each
        float exactly (shortest round-trip decimal).

    Examples
    --------
    >>> import tempfile, pathlib
    >>> p = pathlib.Path(tempfile.mkdtemp()) / "a.json"
    >>> _ = write_json(p, {"r": 0.1 + 0.2}, float_digits=10)
    >>> import json
    >>> json.loads(p.read_text())
    {'r': 0.3}
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
    """The JSON objects of a JSON-lines file, one per line ([] if it does not exist).

    A line that is not a complete JSON object (the torn last line of a run that was
    killed while appending) is skipped.
    """
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
    """Append objects to a JSON-lines file, one per line, in one write, and flush it to
    disk (``fsync``).

    So a crash loses at most the lines being written; a torn last line left by an
    earlier crash is ended first, so that it stays a line of its own.
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
    import hashlib

    p = check_input_file(path, "input")
    h = hashlib.sha256()
    with open(p, "rb") as fh:
        for chunk in iter(lambda: fh.read(1 << 20), b""):
            h.update(chunk)
    return h.hexdigest()


# The former private name, still imported by io.positions; new code uses check_input_file.
_existing_file = check_input_file
