"""Audio files (mono float32 ``y`` with ``sr``) and beat-annotation files (times [s])."""

from __future__ import annotations

import contextlib
import os
import re
import sys
import tempfile
import threading
import warnings
from collections.abc import Iterator
from pathlib import Path
from types import MappingProxyType
from typing import Any

import numpy as np

from ..audio_resampling import resample
from ..errors import ParameterError, warn
from ..validation import as_float, check_audio, check_finite, check_sample_rate, check_times
from ._files import atomic_write, check_input_file

#: libsndfile's format for each suffix it reads: such a file it cannot read, when it has
#: the format, is damaged (no audioread fallback).
SOUNDFILE_SUFFIXES = MappingProxyType(
    {
        ".wav": "WAV",
        ".wave": "WAV",
        ".flac": "FLAC",
        ".ogg": "OGG",
        ".oga": "OGG",
        ".mp3": "MP3",
        ".aif": "AIFF",
        ".aiff": "AIFF",
        ".aifc": "AIFF",
        ".au": "AU",
        ".caf": "CAF",
        ".w64": "W64",
        ".rf64": "RF64",
    }
)


def read_audio(path: str | os.PathLike[str], *, sr: int | None = None) -> tuple[np.ndarray, int]:
    """Read an audio file as mono float32 ``(y, sr)``, resampled to ``sr`` [Hz] if given.

    libsndfile's formats (:data:`SOUNDFILE_SUFFIXES`) directly, others (M4A) through
    librosa/audioread. A file cut short (fewer samples than its header says) is refused.
    """
    import soundfile as sf

    p = check_input_file(path, "audio")
    sr = None if sr is None else _integral_rate(sr, name="sr")
    try:
        # libmpg123 prints its own warnings to the process's stderr ("Xing stream size
        # off by more than 1%"): kept apart, then said once the read is judged
        with _c_stderr_captured(p.suffix.lower() == ".mp3") as decoder:
            with sf.SoundFile(p) as f:
                file_sr = f.samplerate
                data = f.read(dtype="float32", always_2d=True)
            info = sf.info(str(p))
        y = data.mean(axis=1)
    except Exception as sf_exc:
        if SOUNDFILE_SUFFIXES.get(p.suffix.lower()) in sf.available_formats():
            # libsndfile reads these formats itself: a failure is a damaged file, and
            # audioread (through librosa, seconds to import) would fail the same way
            _check_wav_header_rate(p)
            detail = (str(sf_exc).strip().splitlines() or [type(sf_exc).__name__])[0]
            if "does not exist" in detail:  # libsndfile's words for content it cannot decode
                detail = "its content is not decodable audio"
            raise ParameterError(
                f"cannot read {str(p)!r} as {p.suffix.lower()[1:].upper()} audio "
                f"({detail}); is the file complete and of that format?"
            ) from None
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
    else:
        _check_complete(p, info, y.size, file_sr)  # its own words if cut short
        if decoder:
            warn(
                f"the MP3 decoder (libmpg123) reported on {str(p)!r}: "
                + "; ".join(decoder)
                + " (the file was read; if it sounds wrong, copy it again)",
                stacklevel=2,
            )
    y = np.asarray(y, dtype=np.float32)
    try:
        file_sr = _integral_rate(file_sr, name="sample rate")
    except ParameterError as exc:
        raise ParameterError(f"audio file {str(p)!r} has a broken header: {exc}") from None
    y, _ = check_audio(y, file_sr, name=f"audio file {str(p)!r}")
    if sr is not None and sr != file_sr:
        return resample(y, file_sr, sr), sr
    return y, file_sr


def resample_audio(y: np.ndarray, orig_sr: float, target_sr: float) -> np.ndarray:
    """Resample mono audio with soxr's high-quality filter (float32, ``ceil(n * ratio)`` samples).

    The samples of ``librosa.resample`` (``res_type="soxr_hq"``), without importing librosa.
    """
    y, orig = check_audio(y, orig_sr)
    target = check_sample_rate(target_sr, name="target_sr")
    return resample(y, orig, target)


#: A file is cut short when it lacks more than this fraction of the samples its header
#: announces and at least :data:`SHORT_FILE_MIN_S` [s] (an MP3's count is an estimate).
SHORT_FILE_FRACTION = 0.01
SHORT_FILE_MIN_S = 0.1


@contextlib.contextmanager
def _c_stderr_captured(active: bool = True) -> Iterator[list[str]]:
    """The lines C code writes to file descriptor 2 inside the block, kept from the terminal.

    Only in the main thread (the descriptor is the whole process's).
    """
    lines: list[str] = []
    if not active or threading.current_thread() is not threading.main_thread():
        yield lines
        return
    try:
        sys.stderr.flush()
        saved = os.dup(2)
    except (OSError, ValueError, AttributeError):  # no descriptor 2 or no sys.stderr
        yield lines
        return
    with tempfile.TemporaryFile() as held:
        os.dup2(held.fileno(), 2)
        try:
            yield lines
        finally:
            os.dup2(saved, 2)
            os.close(saved)
            held.seek(0)
            text = held.read().decode("utf-8", errors="replace")
            lines.extend(line.strip() for line in text.splitlines() if line.strip())


def _check_complete(p: Path, info: Any, n_read: int, rate: float) -> None:
    """Refuse a file cut short. libsndfile reads what is there silently, but logs each size
    a header declares beyond the bytes present (``data : 661500 (should be 165342)``) in
    ``info.extra_info``; an MP3's Xing length is ``info.frames``; Ogg: :func:`_ogg_is_cut`."""
    announced = int(info.frames)
    missing = [
        int(declared) - int(present)
        for declared, present in _SHOULD_BE.findall(info.extra_info)
        if not _unknown_size(int(declared))
    ]
    if missing and max(missing) > 0:
        if info.subtype in _SAMPLE_BYTES:
            frame_bytes = _SAMPLE_BYTES[info.subtype] * info.channels
        else:  # a compressed subtype: its mean frame size
            frame_bytes = p.stat().st_size / max(n_read, 1)
        announced = n_read + int(max(missing) // frame_bytes)
    if p.suffix.lower() == ".mp3" and not _mp3_has_length_header(p):
        # without a Xing/Info/VBRI header libmpg123 guesses the length of a VBR file
        # from its first frame's bit rate (a quiet intro: a guess too long)
        announced = n_read
    if _ogg_is_cut(p):
        raise ParameterError(
            f"audio file {str(p)!r} is cut short: its Ogg stream stops without its last "
            f"page (read {n_read / rate:.3f} s); an interrupted copy or download? Copy "
            "the file again"
        )
    short = announced - n_read
    if short > SHORT_FILE_FRACTION * announced and short >= SHORT_FILE_MIN_S * rate:
        raise ParameterError(
            f"audio file {str(p)!r} is cut short: its header announces "
            f"{announced / rate:.3f} s ({announced} samples at {rate:g} Hz) but it holds "
            f"{n_read / rate:.3f} s; an interrupted copy or download? Copy the file again"
        )


#: libsndfile's log line for a chunk size a header declares beyond the bytes present.
_SHOULD_BE = re.compile(
    r"^\s*(?:RIFF|riff|Riff size|FORM|SSND|data|Data Size)\s*:\s*(\d+) \(should be (\d+)\)",
    re.MULTILINE,
)

#: Bytes per sample of libsndfile's uncompressed subtypes.
_SAMPLE_BYTES = {"PCM_S8": 1, "PCM_U8": 1, "ULAW": 1, "ALAW": 1, "PCM_16": 2, "PCM_24": 3}
_SAMPLE_BYTES.update({"PCM_32": 4, "FLOAT": 4, "DOUBLE": 8})


def _unknown_size(size: int) -> bool:
    """Whether a declared size means "unknown" (0, 0xFFFFFFFF, 64-bit max; SoX to a pipe:
    0x7FFFF000 in a WAV, 0x7F000000 in an AIFF)."""
    return size == 0 or 0x7F000000 <= size < 0x80000000 or size == 0xFFFFFFFF or size >= 2**62


def _mp3_has_length_header(p: Path) -> bool:
    """Whether an MP3's first frame carries a Xing, Info or VBRI header (a frame count)."""
    with open(p, "rb") as f:
        head = f.read(10)
        if head[:3] == b"ID3" and len(head) == 10:  # skip an ID3v2 tag (syncsafe size)
            f.seek(10 + sum((b & 0x7F) << (7 * (3 - i)) for i, b in enumerate(head[6:10])))
        else:
            f.seek(0)
        frame = f.read(4096)
    return any(tag in frame for tag in (b"Xing", b"Info", b"VBRI"))


#: Longest Ogg page [bytes]: a 27-byte header, 255 lacing values of up to 255 each.
_OGG_MAX_PAGE = 27 + 255 + 255 * 255


def _ogg_is_cut(p: Path) -> bool:
    """Whether an Ogg file stops inside a page, or after one without the end-of-stream flag."""
    with open(p, "rb") as f:
        if f.read(4) != b"OggS":
            return False
        f.seek(max(0, p.stat().st_size - _OGG_MAX_PAGE))
        tail = f.read()
    at = len(tail)
    while (at := tail.rfind(b"OggS", 0, at)) >= 0:
        header = tail[at : at + 27]
        if len(header) == 27 and header[4] == 0:  # stream structure version 0
            n_segments = header[26]
            lacing = tail[at + 27 : at + 27 + n_segments]
            page_end = at + 27 + n_segments + sum(lacing)
            if len(lacing) < n_segments or page_end > len(tail):
                return True  # the file ends inside this page
            return not header[5] & 0x04  # the last page must carry end-of-stream
    return False


def _check_wav_header_rate(p: Path) -> None:
    """Name an implausible sample rate in a WAV header (libsndfile only says "incomplete")."""
    import wave

    try:
        with wave.open(str(p), "rb") as w:
            rate = w.getframerate()
    except Exception:  # not a PCM WAV the standard library reads: nothing to add
        return
    try:
        _integral_rate(rate, name="sample rate")
    except ParameterError as exc:
        raise ParameterError(f"audio file {str(p)!r} has a broken header: {exc}") from None


def _integral_rate(sr: object, *, name: str) -> int:
    """A sample rate that files can hold: a plausible whole number of Hz."""
    v = check_sample_rate(sr, name=name)
    if v != round(v):
        raise ParameterError(f"{name}={sr!r} must be a whole number of Hz for an audio file")
    return int(round(v))


def write_audio(path: str | os.PathLike[str], y: np.ndarray, sr: int) -> Path:
    """Write mono or ``(n, channels)`` audio; format from the suffix (atomic)."""
    import soundfile as sf

    dest = Path(path)
    sr = _integral_rate(sr, name="sr")
    y = check_finite(y, name="audio samples").astype(np.float32)
    if y.ndim not in (1, 2) or y.shape[0] == 0:
        raise ParameterError(
            f"audio samples must be (n,) or (n, channels) with n > 0, got shape {y.shape}"
        )
    fmt = dest.suffix.lstrip(".").upper() or "WAV"
    if fmt not in sf.available_formats():
        raise ParameterError(f"cannot write audio as {dest.suffix!r}; use .wav or .flac")
    with atomic_write(dest, "wb") as fh:
        sf.write(fh, y, sr, format=fmt)
    return dest


def read_beats(path: str | os.PathLike[str]) -> np.ndarray:
    """Read event times [s] from the first column of a text file (``#`` comments skipped)."""
    p = check_input_file(path, "beat annotation")
    times = []
    try:
        text = p.read_text(encoding="utf-8-sig")
    except (UnicodeDecodeError, OSError) as exc:
        raise ParameterError(f"cannot read {str(p)!r} as a text file of times: {exc}") from None
    for n, line in enumerate(text.splitlines(), 1):
        s = line.strip()
        if not s or s.startswith("#"):
            continue
        first = s.replace(",", " ").split()[0]
        try:
            times.append(as_float(first, name="time", unit="s", text=True))
        except ParameterError:
            raise ParameterError(
                f"{str(p)!r} line {n}: {first!r} is not a number; a beat file holds one "
                "time in seconds per line"
            ) from None
    return check_times(np.array(times), name=f"beat times in {p.name}", allow_empty=False)


def write_beats(path: str | os.PathLike[str], times: np.ndarray) -> Path:
    """Write event times [s], one per line with 6 decimals (atomic)."""
    t = check_times(times, name="beat times")
    with atomic_write(path) as fh:
        fh.write("".join(f"{x:.6f}\n" for x in t))
    return Path(path)
