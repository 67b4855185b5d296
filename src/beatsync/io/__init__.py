"""Reading and writing files: the only package of beatsync that touches the disk.

Modules: ``_files`` (atomic writes, JSON/CSV, checksums), ``bvh``, ``tables``
(``.mat`` markers, angle tables, ``.npz``), ``positions`` (joint positions), ``audio``
(audio and beat files). :func:`read_motion` and :func:`write_motion` choose by suffix.
Motion files become a :class:`~beatsync.motion.Motion`; audio mono float32 ``y`` at
``sr`` [Hz]; beat files hold one time [s] per line (first column). Every write is
atomic: a temporary file in the destination folder is renamed over the destination
only when complete, so nothing is written when an error is raised.
"""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np

from ..errors import ParameterError
from ..joints import fill_joint_gaps
from ..motion import Motion
from ..validation import check_positive
from ._files import (
    append_jsonl,
    atomic_write,
    check_input_file,
    check_motion_output,
    check_output_folder,
    read_jsonl,
    sha256_file,
    to_jsonable,
    write_csv,
    write_json,
    write_jsonl,
)
from .audio import (
    SOUNDFILE_SUFFIXES,
    read_audio,
    read_beats,
    resample_audio,
    write_audio,
    write_beats,
)
from .bvh import read_bvh, write_bvh
from .positions import (
    read_c3d,
    read_positions_array,
    read_positions_json,
    write_c3d,
    write_positions_array,
    write_positions_json,
)
from .tables import (
    check_npy_header,
    read_mocap_mat,
    read_npz,
    read_table,
    write_npz,
    write_table,
)

__all__ = [
    "atomic_write",
    "check_input_file",
    "check_npy_header",
    "check_output_folder",
    "read_motion",
    "write_motion",
    "read_positions_json",
    "write_positions_json",
    "read_positions_array",
    "write_positions_array",
    "read_c3d",
    "write_c3d",
    "read_bvh",
    "write_bvh",
    "read_mocap_mat",
    "read_table",
    "write_table",
    "read_audio",
    "write_audio",
    "resample_audio",
    "SOUNDFILE_SUFFIXES",
    "read_beats",
    "write_beats",
    "write_json",
    "read_jsonl",
    "write_jsonl",
    "append_jsonl",
    "to_jsonable",
    "write_csv",
    "check_motion_output",
    "sha256_file",
    "read_npz",
    "write_npz",
    "AUDIO_SUFFIXES",
    "MOTION_SUFFIXES",
    "MOTION_OUTPUT_SUFFIXES",
]

MOTION_SUFFIXES = (".bvh", ".mat", ".csv", ".npy", ".npz", ".json", ".c3d")
AUDIO_SUFFIXES = (".wav", ".flac", ".ogg", ".mp3", ".aiff", ".aif", ".m4a")
#: Suffixes :func:`write_motion` writes.
MOTION_OUTPUT_SUFFIXES = (".bvh", ".csv", ".npy", ".npz", ".json", ".c3d")


def read_motion(
    path: str | os.PathLike[str],
    *,
    fps: float | None = None,
    variable: str | None = None,
    up: str | None = None,
    units: str | None = None,
    max_gap: float = 0.25,
) -> Motion:
    """Read any supported motion file, chosen by its suffix: ``.bvh`` (``fps`` overrides the
    header), ``.mat`` markers (``variable``: the recording), ``.csv``/2-D ``.npy`` tables
    (``fps`` required), joint positions (:mod:`beatsync.io.positions`; ``variable``: an
    ``.npz`` array; ``up``, ``units``). Gaps up to ``max_gap`` [s] are filled."""
    p = Path(path)
    suffix = p.suffix.lower()
    # an .npz renamed, strings, records...: refused before any load
    shape = check_npy_header(p)[0] if suffix == ".npy" else ()
    positional = suffix in (".json", ".npz", ".c3d") or (len(shape) == 3 and shape[-1] == 3)
    if not positional and (up is not None or units is not None):
        given = ", ".join(f"{k}={v!r}" for k, v in (("up", up), ("units", units)) if v)
        raise ParameterError(
            f"{given} apply to joint-position files (.json, .c3d, .npz or .npy arrays of "
            f"shape (frames, joints, 3)); {str(p)!r} is not one: leave them out"
        )
    opts = {"up": up, "units": units, "max_gap": max_gap}
    if suffix == ".bvh":
        return read_bvh(p, fps=fps)
    if suffix == ".mat":
        m = read_mocap_mat(p, variable)
        if fps is not None:
            m = m.with_values(m.values, fps=fps)
        if not np.isfinite(m.values).all():  # marker dropouts: filled like joint positions
            gap = check_positive(max_gap, name="max_gap", unit="s", allow_zero=True)
            pos = fill_joint_gaps(m.positions(), m.fps, max_gap=gap, joint_names=m.joint_names)
            m = m.with_values(pos.reshape(m.n_frames, -1))
        return m
    if suffix == ".json":
        return read_positions_json(p, fps=fps, **opts)
    if suffix == ".c3d":
        return read_c3d(p, fps=fps, **opts)
    if positional:
        return read_positions_array(p, fps=fps, key=variable, **opts)
    if suffix in (".csv", ".npy"):
        return read_table(p, fps=fps)
    hint = ""
    if suffix in SOUNDFILE_SUFFIXES:
        hint = " (this is audio: are the arguments swapped? the motion comes first, then the music)"
    raise ParameterError(
        f"unsupported motion file {str(p)!r}: expected one of {', '.join(MOTION_SUFFIXES)}{hint}"
    )


def write_motion(path: str | os.PathLike[str], motion: Motion) -> Path:
    """Write a motion in the format its suffix names, matching :func:`read_motion` (atomic).

    Joint positions go back in their input's layout, units and vertical axis; ``.csv``
    (and ``.npy`` for other motion) write the values as a table.
    """
    p = Path(path)
    suffix = p.suffix.lower()
    if suffix == ".bvh":
        return write_bvh(p, motion)
    if suffix == ".csv":
        return write_table(p, motion)
    if suffix == ".json":
        return write_positions_json(p, motion)
    if suffix == ".c3d":
        return write_c3d(p, motion)
    if suffix in (".npy", ".npz") and motion.is_positional:
        return write_positions_array(p, motion)
    if suffix == ".npy":
        with atomic_write(p, mode="wb") as fh:
            np.save(fh, motion.values)
        return p
    raise ParameterError(
        f"cannot write motion as {str(p)!r}: choose a suffix from "
        f"{', '.join(MOTION_OUTPUT_SUFFIXES)} (.npz only for joint positions)"
    )
