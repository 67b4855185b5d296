"""Reading and writing files: the only package of beatsync that touches the disk.

Modules: ``_files`` (atomic writes, JSON/CSV, checksums), ``bvh``, ``tables``
(``.mat`` markers, CSV/NPY angle tables, ``.npz``), ``audio`` (audio and beat files).

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

import os
from pathlib import Path

from ..errors import ParameterError
from ..motion import Motion
from ._files import (
    atomic_write,
    check_input_file,
    check_output_folder,
    sha256_file,
    to_jsonable,
    write_csv,
    write_json,
)
from .audio import read_audio, read_beats, write_audio, write_beats
from .bvh import read_bvh, write_bvh
from .tables import read_mocap_mat, read_npz, read_table, write_npz, write_table

__all__ = [
    "atomic_write",
    "check_input_file",
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
    "to_jsonable",
    "write_csv",
    "sha256_file",
    "read_npz",
    "write_npz",
    "AUDIO_SUFFIXES",
    "MOTION_SUFFIXES",
]

MOTION_SUFFIXES = (".bvh", ".mat", ".csv", ".npy")
AUDIO_SUFFIXES = (".wav", ".flac", ".ogg", ".mp3", ".aiff", ".aif", ".m4a")


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
