"""Music beat tracking (paper A, section 4): :mod:`.onset` (phase-slope onsets),
:mod:`.metrical` and :mod:`.drums` (which pulse is the beat), :mod:`.tempo` and :mod:`.phase`
(the HMMs) and :mod:`.tracker` (:func:`track_beats`, where validation happens, once).

Audio is mono float ``y`` (1-D, finite) at ``sr`` [Hz]; beat times are 1-D ``float64``
seconds, strictly increasing; tempo is in BPM, per analysis window.
"""

from .onset import FRONTEND_DEFAULTS, FrontEnd, OnsetSignal, onset_strength_psf, phase_slope
from .tracker import (
    MIN_DURATION_S,
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
    "check_duration",
    "beat_tempo",
    "mix_clicks",
    "FRONTEND_DEFAULTS",
    "MIN_DURATION_S",
    "SILENCE_PEAK",
]
