"""Scores: metrics on arrays, mir_eval style (``validate``, the metrics, ``evaluate``).

No module here runs a pipeline stage; :mod:`beatsync.study` runs them and calls these.

- :mod:`beatsync.evaluate.beats`: beat tracking against annotations, every
  ``mir_eval.beat`` metric with an explicit ``min_beat_time``; the tempo octave.
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
