"""Other motion files: MoCap Toolbox ``.mat`` markers, CSV/NPY angle tables, ``.npz`` archives."""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np

from ..errors import ParameterError
from ..motion import Motion
from ..units import check_finite, check_fps
from ._files import _existing_file, atomic_write, write_csv


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
