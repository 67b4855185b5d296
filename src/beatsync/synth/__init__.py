"""Synthetic signals with exact ground truth.

- :mod:`beatsync.synth.motion`: periodic multi-channel joint-angle signals with known
  period boundaries (paper A, sec. 3 experiments).
- :mod:`beatsync.synth.audio`: click tracks and drum patterns with known beats
  (the beat-tracking test set).
"""

from .audio import BeatTestItem, beat_times, click_track, drum_pattern, make_beat_test_set
from .motion import SyntheticMotion, periodic_motion

__all__ = [
    "SyntheticMotion",
    "periodic_motion",
    "BeatTestItem",
    "beat_times",
    "click_track",
    "drum_pattern",
    "make_beat_test_set",
]
