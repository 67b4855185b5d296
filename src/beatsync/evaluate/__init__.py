"""Scores.

- :mod:`beatsync.evaluate.beats`: beat tracking against annotations, every
  ``mir_eval.beat`` metric with an explicit ``min_beat_time``.
- :mod:`beatsync.evaluate.alignment`: dance-music beat alignment, both published
  scores (averaged over motion beats, or over music beats; Gaussian sigma in seconds).
- :mod:`beatsync.evaluate.segmentation`: period boundaries against ground truth
  (boundary error in frames, count error).
"""

from .alignment import (
    alignment_scores,
    beat_alignment_motion,
    beat_alignment_music,
    beat_phase_consistency,
    offset_control,
    sync_residuals,
)
from .beats import METRICS, evaluate_beats, octave_relation
from .segmentation import boundary_errors

__all__ = [
    "evaluate_beats",
    "octave_relation",
    "METRICS",
    "alignment_scores",
    "beat_alignment_motion",
    "beat_alignment_music",
    "beat_phase_consistency",
    "offset_control",
    "sync_residuals",
    "boundary_errors",
]
