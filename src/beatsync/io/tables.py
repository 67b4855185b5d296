"""Other motion files: MoCap Toolbox ``.mat`` markers, CSV/NPY angle tables, ``.npz`` archives."""

from __future__ import annotations

import os
from pathlib import Path
from typing import Any

import numpy as np

from ..errors import ParameterError
from ..motion import Motion
from ..validation import as_float, as_float_array, check_finite, check_fps
from ._files import atomic_write, check_input_file, write_csv


def need_fps(fps: Any, source: str, hint: str = "") -> float:
    """``fps`` [Hz], required for a file that stores no frame rate."""
    if fps is None:
        raise ParameterError(f"{source} stores no frame rate: give it with fps= (--fps){hint}")
    return check_fps(fps)


def read_mocap_mat(path: str | os.PathLike[str], variable: str | None = None) -> Motion:
    """Read markers of a MoCap Toolbox ``.mat`` struct (``variable``, e.g. ``"dance2"``; may
    be left out if there is one) in metres (stored: mm), z up, rate ``freq``, gaps kept."""
    import scipy.io

    p = check_input_file(path, "MAT")
    try:
        mat = scipy.io.loadmat(p, squeeze_me=True, struct_as_record=False)
    except Exception as exc:  # scipy raises several types for bad files
        raise ParameterError(f"cannot read {str(p)!r} as a MATLAB .mat file: {exc}") from None
    structs = {k: v for k, v in mat.items() if hasattr(v, "data") and hasattr(v, "markerName")}
    # marker data: three columns per named marker (a struct of other data has the fields too)
    cands = [
        k
        for k, v in structs.items()
        if np.ndim(v.data) == 2 and np.shape(v.data)[1] == 3 * np.size(v.markerName) > 0
    ]
    if not cands:
        found = [k for k in mat if not k.startswith("__")]
        raise ParameterError(
            f"{str(p)!r} holds no MoCap Toolbox marker recording (a struct with fields "
            f"'data', 'markerName' and 'freq'); its variables are {found}"
        )
    if variable is None:
        if len(cands) != 1:
            raise ParameterError(
                f"{str(p)!r} holds several marker recordings {cands}; choose one with "
                "variable= (--variable on the command line)"
            )
        variable = cands[0]
    if variable not in cands:
        what = "is not marker data" if variable in structs else "is not in it"
        raise ParameterError(
            f"{str(p)!r} has no marker recording {variable!r} ({what}); choose from {cands}"
        )
    s = mat[variable]
    where = f"{str(p)!r} recording {variable!r}"
    if not hasattr(s, "freq"):
        raise ParameterError(
            f"{where} has no 'freq' field (the frame rate); is it a MoCap Toolbox struct? "
            "Give the frame rate with fps= (--fps)"
        )
    rate = check_fps(_scalar(s.freq), name=f"{where} freq")
    data = as_float_array(s.data, name=f"{where} data")
    names = [str(n) for n in np.atleast_1d(s.markerName)]
    if data.shape[0] < 2:
        raise ParameterError(f"{where} has {data.shape[0]} frame(s); need at least 2")
    channels = tuple(f"{m}_{a}" for m in names for a in "xyz")
    return Motion(data / 1000.0, rate, channels, None, variable)


def _scalar(value: object) -> object:
    """A MATLAB scalar as loaded by scipy (a 0-d or 1-element array) as a plain value."""
    arr = np.asarray(value)
    return arr.reshape(()).item() if arr.size == 1 and arr.dtype.kind in "iuf" else value


def read_table(path: str | os.PathLike[str], *, fps: float | None) -> Motion:
    """Read a joint-angle table at ``fps`` [Hz]: ``.csv`` with a header row, or ``.npy``
    ``(n, c)`` (channels ``"ch0"``, ``"ch1"``, ...)."""
    p = check_input_file(path, "table")
    rate = need_fps(fps, f"{str(p)!r} (a plain table)")
    if p.suffix.lower() == ".npy":
        values = _read_npy(p)
        names = tuple(f"ch{i}" for i in range(values.shape[1]))
    else:
        import pandas as pd

        _check_csv_rows(p)
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


def check_npy_header(path: str | os.PathLike[str]) -> tuple[tuple[int, ...], np.dtype]:
    """Shape and dtype of a ``.npy`` file from its header alone; refuses non-numeric dtypes."""
    p = check_input_file(path, ".npy")
    with open(p, "rb") as fh:
        magic = fh.read(6)
        if magic[:2] == b"PK":
            raise ParameterError(
                f"{str(p)!r} is an .npz archive (a zip of arrays), not a .npy array: rename "
                "it .npz, or save one array with numpy.save"
            )
        if magic != b"\x93NUMPY":
            raise ParameterError(f"{str(p)!r} is not a .npy file (no NumPy header)")
        fh.seek(0)
        try:
            fmt = np.lib.format
            v1 = fmt.read_magic(fh) == (1, 0)
            shape, _, dtype = (fmt.read_array_header_1_0 if v1 else fmt.read_array_header_2_0)(fh)
        except Exception as exc:  # numpy raises several types for broken headers
            raise ParameterError(f"{str(p)!r} has a broken .npy header: {exc}") from None
    if dtype.hasobject:
        raise ParameterError(
            f"{str(p)!r} holds Python objects (a pickled array), which are never loaded; "
            "save a numeric array"
        )
    if dtype.names is not None or dtype.kind not in "iuf":
        # describe the dtype in the words of as_float_array; nothing of the file is read
        as_float_array(np.empty(0, dtype=dtype), name=f"{str(p)!r}")
    return tuple(shape), dtype


def _read_npy(p: Path) -> np.ndarray:
    """A ``.npy`` file holding one numeric ``(frames, channels)`` array, else a clear error."""
    check_npy_header(p)
    try:
        values = np.load(p, allow_pickle=False)
    except Exception as exc:  # truncated data, unsupported versions
        raise ParameterError(f"cannot read {str(p)!r} as a .npy array: {exc}") from None
    if values.ndim != 2:
        raise ParameterError(
            f"{str(p)!r} holds an array of shape {values.shape}; need 2-D (frames, channels) "
            "angles, or 3-D (frames, joints, 3) joint positions"
        )
    return values.astype(np.float64, copy=False)


def _is_number(text: str) -> bool:
    try:
        as_float(text, name="header", allow_nonfinite=True, text=True)
    except ParameterError:
        return False
    return True


def write_table(path: str | os.PathLike[str], motion: Motion) -> Path:
    """Write motion values as CSV with a header row of channel names (atomic)."""
    import pandas as pd

    return write_csv(path, pd.DataFrame(motion.values, columns=list(motion.channels)))


def _check_csv_rows(p: Path) -> None:
    """Refuse a row with another number of fields than the header (pandas fills NaN)."""
    import csv

    try:
        with open(p, newline="", encoding="utf-8-sig") as fh:
            reader = csv.reader(fh)
            header = next(reader, [])
            for row in reader:
                if row and len(row) != len(header):
                    raise ParameterError(
                        f"{str(p)!r} line {reader.line_num}: {len(row)} fields, but the header "
                        f"row names {len(header)} channels"
                    )
    except (UnicodeDecodeError, csv.Error) as exc:
        raise ParameterError(f"cannot read {str(p)!r} as a UTF-8 CSV table: {exc}") from None


def read_npz(path: str | os.PathLike[str]) -> dict[str, np.ndarray]:
    """Read every array of an ``.npz`` file (no pickles)."""
    p = check_input_file(path, "npz")
    with open(p, "rb") as fh:
        magic = fh.read(6)
    if magic == b"\x93NUMPY":
        raise ParameterError(
            f"{str(p)!r} is a single .npy array, not an .npz archive: rename it .npy"
        )
    if magic[:2] != b"PK":
        raise ParameterError(f"{str(p)!r} is not an .npz archive (not a zip file)")
    try:
        with np.load(p, allow_pickle=False) as data:
            return {k: data[k] for k in data.files}
    except Exception as exc:  # zipfile and numpy raise several types for broken archives
        raise ParameterError(f"cannot read {str(p)!r} as an .npz archive: {exc}") from None


def write_npz(path: str | os.PathLike[str], arrays: dict[str, np.ndarray]) -> Path:
    """Write named arrays as an uncompressed ``.npz`` file (atomic)."""
    with atomic_write(path, mode="wb") as fh:
        np.savez(fh, **arrays)
    return Path(path)
