"""Band-limited audio resampling with soxr's high-quality filter, for the audio reader
(:func:`beatsync.io.resample_audio`) and the tracker's analysis rate: the samples of
``librosa.resample`` (``res_type="soxr_hq"``), without importing librosa. soxr filters in
single precision, so float64 input gives the samples of its float32 cast.
"""

from __future__ import annotations

import numpy as np

__all__ = ["resample"]


#: Audio louder than this [peak magnitude] goes through soxr at a lower level, by an exact
#: power-of-two gain (soxr's float32 filter returns NaN from a peak of about 1e37).
LOUDEST = 2.0**100


def resample(
    y: np.ndarray,
    orig_sr: float,
    target_sr: float,
    n_out: int | None = None,
    *,
    keep_level: bool = True,
) -> np.ndarray:
    """Resample mono audio from ``orig_sr`` to ``target_sr`` [Hz] to ``n_out`` samples
    (float32; default ``ceil(n * target_sr / orig_sr)``, as librosa). Trusts its input;
    ``keep_level=False`` leaves audio louder than :data:`LOUDEST` lowered (exactly).
    """
    import soxr  # noqa: PLC0415 (only where audio is resampled)

    y = np.asarray(y)
    shift = 0
    if orig_sr != target_sr and y.size:
        peak = max(float(y.max()), -float(y.min()))
        if peak > LOUDEST:
            shift = 30 - int(np.frexp(peak)[1])  # peak about 2**30 when filtered
            y = np.ldexp(y, shift)
    y = np.asarray(y, dtype=np.float32)
    if n_out is None:
        n_out = int(np.ceil(y.size * float(target_sr) / orig_sr))
    if orig_sr != target_sr:
        y = np.asarray(soxr.resample(y, orig_sr, target_sr, quality="HQ"), dtype=np.float32)
    if shift and keep_level:
        y = np.ldexp(y, -shift).astype(np.float32)
    return np.pad(y[:n_out], (0, max(n_out - y.size, 0)))  # trimmed or zero-padded
