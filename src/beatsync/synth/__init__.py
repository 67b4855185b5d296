"""Synthetic signals with exact ground truth.

- :mod:`beatsync.synth.motion`: periodic multi-channel joint-angle signals with known
  period boundaries (paper A, sec. 3 experiments).
- :mod:`beatsync.synth.audio`: click tracks and drum patterns with known beats.
"""
