"""Audio files (mono float32 ``y`` with ``sr``) and beat-annotation files (times [s])."""

from __future__ import annotations

import os
import warnings
from pathlib import Path

import numpy as np

from ..errors import ParameterError
from ..units import check_finite, check_times
from ._files import _existing_file, atomic_write


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
