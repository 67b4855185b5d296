"""Real dancers re-synchronised to other songs (paper A's method on real dance data).

The Dance-with-Melody pairs (:func:`beatsync.datasets.load_dance_pair`: a real dancer
as joint positions, 25 fps, with the song they danced to) stand in for paper A's
markerless-tracked dancer. For each dancer: how well their motion beats align with
their own song (both published beat-alignment scores, sigma in seconds), after
:func:`beatsync.sync.synchronize` re-synchronises them to another song, and the
random-offset control; and the dance's period against the songs' beat periods. The
dataset's own alignment of dance and song is approximate, so the "own song" score is a
reference, not a ground truth.

Functions: :func:`real_dancer_row`, :func:`real_dancer_table`.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from ..evaluate.alignment import (
    DEFAULT_SIGMA,
    alignment_scores,
    beat_phase_consistency,
    offset_control,
)
from ..motion_beats import kinematic_beats

__all__ = ["real_dancer_row", "real_dancer_table"]


def real_dancer_row(
    pair: Any,
    song: tuple[np.ndarray, int],
    *,
    song_name: str = "",
    mode: str = "auto",
    land: str = "accents",
    sigma: float = DEFAULT_SIGMA,
    n_control: int = 100,
    seed: int = 0,
) -> tuple[dict[str, Any], Any]:
    """A real dancer with their own song, then re-synchronised to another song.

    Both published alignment scores (``_motion``: averaged over motion beats, Siyao et
    al. 2022; ``_music``: averaged over music beats, Li et al. 2021; sigma in seconds)
    of the dancer's kinematic beats against music beats tracked by
    :func:`beatsync.beats.track_beats`:

    - ``own_*``: the dancer as recorded, against their own song, over the time both
      play (motion frame ``i`` at ``pair.audio_offset + i / fps`` of the song: the
      dataset's own alignment, which is approximate);
    - ``after_*``: the dancer re-synchronised to ``song`` by
      :func:`beatsync.sync.synchronize` (``mode``, ``land``, ``fill="stop"``: the
      dancer's own material, not repeated; the song's meter as the tracker estimates
      it);
    - ``control_*``: the re-synchronised motion beats shifted by random offsets within
      one beat (:func:`beatsync.evaluate.alignment.offset_control`, the chance level).

    Parameters
    ----------
    pair : beatsync.datasets.DancePair
    song : (np.ndarray, int)
        The new song ``(y, sr)``.
    song_name : str
    mode, land : str
        Passed to :func:`~beatsync.sync.synchronize`.
    sigma : float > 0 [s]
    n_control, seed : int

    Returns
    -------
    row : dict
        dancer, style, song, mode used, beats per period (or per motion beat), the
        dance's period [s] (mean period, or median motion-beat interval in beats
        mode), the beat periods [s] of the own and the new song, ``own_/after_/
        control_`` ``motion``/``music`` scores, ``after_phase`` (phase consistency),
        max residual [frames], and ``mode_note``.
    result : beatsync.sync.SyncResult
    """
    import warnings

    from ..beats import track_beats
    from ..errors import BeatsyncWarning
    from ..sync import synchronize

    motion = pair.motion
    own_beats = track_beats(pair.y, pair.sr).beats
    new_track = track_beats(*song)
    new_beats = new_track.beats
    bar = int(getattr(new_track, "beats_per_bar", 0)) or None
    mb = kinematic_beats(motion)
    start = float(pair.audio_offset)
    own = alignment_scores(
        mb + start, own_beats, sigma=sigma, span=(start, start + float(motion.duration))
    )
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", BeatsyncWarning)  # the fallback is in the row
        res = synchronize(
            motion, None, new_beats, mode=mode, land=land, fill="stop", beats_per_bar=bar
        )
    rep = res.report
    mb_after = kinematic_beats(res.motion)
    span = (float(rep["covered_s"][0]), float(rep["covered_s"][1]))
    after = alignment_scores(mb_after, new_beats, sigma=sigma, span=span)
    inside = new_beats[(new_beats >= span[0]) & (new_beats <= span[1])]
    ctrl = offset_control(
        mb_after[(mb_after >= span[0]) & (mb_after <= span[1])],
        inside,
        sigma=sigma,
        n_trials=n_control,
        seed=seed,
    )
    row = {
        "dancer": pair.name,
        "style": pair.style,
        "song": song_name,
        "mode": rep["mode"],
        "beats/period": rep["beats_per_period"],
        "new song beats/bar": bar,
        "dance period [s]": rep["mean_motion_period_s"],
        "own beat period [s]": float(np.median(np.diff(own_beats))),
        "new beat period [s]": rep["beat_period_s"],
        "own_motion": own["alignment_motion"],
        "after_motion": after["alignment_motion"],
        "control_motion": ctrl["alignment_motion_mean"],
        "own_music": own["alignment_music"],
        "after_music": after["alignment_music"],
        "control_music": ctrl["alignment_music_mean"],
        "after_phase": beat_phase_consistency(mb_after, new_beats),
        "max residual [frames]": rep["max_abs_residual_frames"],
        "mode_note": rep["mode_note"][:80],
    }
    return row, res


def real_dancer_table(
    names: list[str] | None = None,
    *,
    mode: str = "auto",
    land: str = "accents",
    sigma: float = DEFAULT_SIGMA,
    n_control: int = 100,
    seed: int = 0,
) -> Any:
    """Every bundled real dancer re-synchronised to the next pair's song (cyclically).

    Parameters
    ----------
    names : list of str, optional
        Dance-with-Melody pairs (default all of ``beatsync.datasets.DANCE_PAIRS``).
    mode, land, sigma, n_control, seed
        See :func:`real_dancer_row`.

    Returns
    -------
    pandas.DataFrame
        One :func:`real_dancer_row` per dancer.
    """
    import pandas as pd

    from .. import datasets

    names = list(datasets.DANCE_PAIRS if names is None else names)
    pairs = [datasets.load_dance_pair(n) for n in names]
    rows = []
    for i, pair in enumerate(pairs):
        other = pairs[(i + 1) % len(pairs)]
        row, _ = real_dancer_row(
            pair,
            (other.y, other.sr),
            song_name=f"{other.name} song",
            mode=mode,
            land=land,
            sigma=sigma,
            n_control=n_control,
            seed=seed,
        )
        rows.append(row)
    return pd.DataFrame(rows)
