"""Scores: metrics on arrays, mir_eval style (``validate``, the metrics, ``evaluate``);
no stage runs here (:mod:`beatsync.study` runs them): beat tracking against annotations
(:mod:`.beats`), dance-music beat alignment (:mod:`.alignment`), period boundaries
(:mod:`.segmentation`) and the quality proxies of a composed dance (:mod:`.composition`).
"""

from .alignment import (
    alignment_scores,
    beat_alignment_motion,
    beat_alignment_music,
    beat_phase_consistency,
    offset_control,
    sync_residuals,
)
from .beats import METRICS, octave_relation, tempo_octave
from .segmentation import boundary_errors

__all__ = [
    "octave_relation",
    "tempo_octave",
    "METRICS",
    "alignment_scores",
    "beat_alignment_motion",
    "beat_alignment_music",
    "beat_phase_consistency",
    "offset_control",
    "sync_residuals",
    "boundary_errors",
]
