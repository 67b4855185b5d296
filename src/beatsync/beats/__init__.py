"""Music beat tracking: phase-slope onsets, a metrical model and a tempo/phase HMM
(paper A, section 4).

Data contract
-------------
- Input audio is mono float ``y`` (1-D, finite) with its sample rate ``sr`` > 0 [Hz].
- Output beat times are a 1-D ``float64`` array in seconds, strictly increasing.
- Tempo is in BPM; tempo curves are given per analysis window (centre times [s]).

Layout (along librosa's ``onset`` / ``beat`` / ``sequence`` seams)
------------------------------------------------------------------
- :mod:`.onset`: the phase-slope (group-delay) front end, eqs. 6-8: per-band onsets
  weighted by spectral flux (:func:`onset_strength_psf`, :class:`FrontEnd`).
- :mod:`.tempo`: the tempo HMM over beat periods and a numpy Viterbi decoder.
- :mod:`.phase`: the phase HMM that places the beats for a tempo curve.
- :mod:`.metrical`: the metrical-level decision (which pulse is the beat).
- :mod:`.drums`: the drum-pattern cue of that decision (a bass drum and a snare drum
  that alternate mark the beat; Goto 2001).
- :mod:`.tracker`: the public :func:`track_beats` and its result :class:`BeatTrack`;
  validation happens there, once.

Audio above 22.05 kHz is first resampled to 22.05 kHz (``analysis_sr``), so the
front end behaves the same for 44.1 and 48 kHz input. ``method="librosa"`` wraps
:func:`librosa.beat.beat_track` for comparison (librosa is imported only then).

The front-end parameters (window, hop, FFT size, band edges) are not published in the
paper; the defaults are swept in ``notebooks/paper_a_sec4_beat_tracking.ipynb``.
"""

from ..units import check_bpm
from .onset import FRONTEND_DEFAULTS, FrontEnd, OnsetSignal, onset_strength_psf, phase_slope
from .tracker import (
    MIN_DURATION_S,
    MIN_PATH_SALIENCE,
    MIN_PULSE_CLARITY,
    SILENCE_PEAK,
    BeatTrack,
    beat_tempo,
    check_audio,
    check_duration,
    mix_clicks,
    track_beats,
)

__all__ = [
    "BeatTrack",
    "OnsetSignal",
    "FrontEnd",
    "track_beats",
    "onset_strength_psf",
    "phase_slope",
    "check_audio",
    "check_bpm",
    "check_duration",
    "beat_tempo",
    "mix_clicks",
    "FRONTEND_DEFAULTS",
    "MIN_DURATION_S",
    "SILENCE_PEAK",
    "MIN_PATH_SALIENCE",
    "MIN_PULSE_CLARITY",
]
