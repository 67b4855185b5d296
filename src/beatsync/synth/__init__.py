"""Synthetic signals with exact ground truth: periodic joint-angle signals with known period
boundaries (:mod:`.motion`), click tracks and drum patterns with known beats
(:mod:`.audio`) and dance clips with known motion beats (:mod:`.library`).
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
