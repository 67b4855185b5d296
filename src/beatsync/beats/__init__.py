"""Music beat tracking: phase-slope onsets, a metrical model and a tempo/phase HMM
(paper A, section 4).

Audio is mono float ``y`` (1-D, finite) at ``sr`` [Hz]; beat times are 1-D ``float64``
seconds, strictly increasing; tempo is in BPM, per analysis window. Modules, along
librosa's ``onset`` / ``beat`` / ``sequence`` seams: :mod:`.onset` (the front end, eqs.
6-8), :mod:`.metrical` (which pulse is the beat) and :mod:`.drums` (its drum cue),
:mod:`.tempo` (the tempo HMM), :mod:`.phase` (the phase HMM placing the beats) and
:mod:`.tracker` (the public :func:`track_beats`, where validation happens, once).
``method="librosa"`` wraps :func:`librosa.beat.beat_track` for comparison.
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
