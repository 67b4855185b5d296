"""The tracks of a beat-tracking dataset: audio files paired with their annotations.

:func:`find_tracks` pairs every audio file with the annotation of the same stem
(``.beats``: one time [s] per line, an optional second column such as the beat in the
bar is ignored); :func:`read_annotation` reads one and refuses values that are not
beat times in seconds. :mod:`beatsync.study.beat_dataset` scores the pairs.
"""

from __future__ import annotations

import os
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from .. import io
from ..errors import ParameterError
from ..evaluate.beats import not_seconds_detail
from ..units import MAX_BPM

__all__ = ["Track", "TrackList", "find_tracks", "read_annotation", "ANNOTATION_SUFFIX"]

#: Suffix of beat annotation files: one time [s] per line, optionally a second column.
ANNOTATION_SUFFIX = ".beats"


@dataclass(frozen=True)
class Track:
    """One audio file and its annotation.

    Attributes
    ----------
    key : str
        The audio file's path relative to the audio folder, without suffix (POSIX).
    group : str
        Its folder relative to the audio folder (``"."`` at the top).
    audio, annotation : Path
    """

    key: str
    group: str
    audio: Path
    annotation: Path


@dataclass(frozen=True)
class TrackList:
    """Output of :func:`find_tracks`: the pairs, and the audio files left without one.

    Attributes
    ----------
    tracks : list of Track
    unmatched : list of Path
        Audio files with no annotation of their name.
    shared : dict of Path -> list of Path
        Annotations found by name only (a flat folder) that more than one audio file
        would use (``a/x.wav`` and ``b/x.wav`` for ``x.beats``), or that another audio
        file has at its own relative path: the audio files that found them by name are
        skipped, as an annotation fits one recording at most.
    duplicates : list of Path
        Audio files skipped because a file of the same path and name with another
        suffix was taken (``x.wav`` beside ``x.flac``: the first in sorted order).
    """

    tracks: list[Track]
    unmatched: list[Path] = field(default_factory=list)
    shared: dict[Path, list[Path]] = field(default_factory=dict)
    duplicates: list[Path] = field(default_factory=list)


def _folder(path: str | os.PathLike[str], what: str) -> Path:
    p = Path(path)
    if not p.exists():
        raise ParameterError(f"{what} folder {str(p)!r} does not exist")
    if not p.is_dir():
        raise ParameterError(f"{what} folder {str(p)!r} is a file, not a folder")
    return p


def find_tracks(
    audio_dir: str | os.PathLike[str], annotation_dir: str | os.PathLike[str]
) -> TrackList:
    """Pair every audio file under ``audio_dir`` with the ``.beats`` file of its stem.

    The annotation at the same relative path is preferred (``a/x.wav`` ->
    ``a/x.beats``); otherwise the only ``x.beats`` anywhere under ``annotation_dir``
    (flat annotation folders, as in most datasets). Audio files are those with a
    suffix in :data:`beatsync.io.AUDIO_SUFFIXES`, searched recursively.

    Raises
    ------
    ParameterError
        A folder that is missing or a file; no audio file; no annotation file; no
        audio file with an annotation (of its own: one that several audio files would
        share by name does not count, see :class:`TrackList`).
    """
    a_dir = _folder(audio_dir, "audio")
    b_dir = _folder(annotation_dir, "annotation")
    audio = sorted(
        p for p in a_dir.rglob("*") if p.suffix.lower() in io.AUDIO_SUFFIXES and p.is_file()
    )
    if not audio:
        raise ParameterError(
            f"audio folder {str(a_dir)!r} holds no audio file ({', '.join(io.AUDIO_SUFFIXES)})"
        )
    notes = sorted(p for p in b_dir.rglob(f"*{ANNOTATION_SUFFIX}") if p.is_file())
    if not notes:
        raise ParameterError(
            f"annotation folder {str(b_dir)!r} holds no {ANNOTATION_SUFFIX} file "
            "(one beat time [s] per line)"
        )
    by_rel = {p.relative_to(b_dir).with_suffix("").as_posix(): p for p in notes}
    by_stem: dict[str, list[Path]] = {}
    for p in notes:
        by_stem.setdefault(p.stem, []).append(p)
    tracks, unmatched, duplicates = [], [], []
    by_name: dict[Path, list[Path]] = {}  # annotations found by name only, and their users
    by_path: set[Path] = set()  # annotations found at their audio file's relative path
    seen: set[str] = set()
    for p in audio:
        rel = p.relative_to(a_dir)
        key = rel.with_suffix("").as_posix()
        if key in seen:  # x.wav beside x.flac
            duplicates.append(p)
            continue
        note = by_rel.get(key)
        if note is not None:
            by_path.add(note)
        elif len(by_stem.get(p.stem, [])) == 1:
            note = by_stem[p.stem][0]
            by_name.setdefault(note, []).append(p)
        if note is None:
            unmatched.append(p)
            continue
        seen.add(key)
        group = rel.parent.as_posix()
        tracks.append(Track(key, group, p, note))
    # an annotation found by name that another audio file uses by its path, or that
    # several use by name, fits one recording at most
    shared = {note: users for note, users in by_name.items() if len(users) > 1 or note in by_path}
    if shared:
        taken = {p for users in shared.values() for p in users}
        tracks = [t for t in tracks if t.audio not in taken]
    if not tracks:
        raise ParameterError(
            f"none of the {len(audio)} audio files under {str(a_dir)!r} has an annotation "
            f"of the same name ({ANNOTATION_SUFFIX}) under {str(b_dir)!r}, e.g. "
            f"{audio[0].stem}{ANNOTATION_SUFFIX}"
        )
    return TrackList(tracks, unmatched, shared, duplicates)


def read_annotation(path: str | os.PathLike[str]) -> np.ndarray:
    """Beat times [s] of an annotation file, refused if they are not seconds.

    Raises
    ------
    ParameterError
        Unreadable, empty, unsorted, non-numeric (:func:`beatsync.io.read_beats`),
        values that look like frame indices or milliseconds (the message says which),
        or times closer than a beat at 400 BPM (minutes, or onsets).
    """
    times = io.read_beats(path)
    detail = not_seconds_detail(times)
    if detail is not None:
        raise ParameterError(
            f"annotation {str(path)!r} is not beat times in seconds: it ends at {detail}"
        )
    if times.size >= 3:
        step = float(np.median(np.diff(times)))
        if step < 60.0 / MAX_BPM:
            raise ParameterError(
                f"annotation {str(path)!r} is not beat times in seconds: its times are a "
                f"median {step:.4g} apart ({60.0 / step:.0f} BPM read as seconds, faster "
                f"than any beat, over {MAX_BPM:g} BPM): minutes, or onsets rather than beats?"
            )
    return times
