"""Solutions to the exercises of tutorial 3 (beat-synchronous resampling)."""

import numpy as np


def landing_beats(beats, n_periods, m, first_beat=0):
    # boundary i lands on beat first_beat + i * m; n_periods periods have n_periods + 1 boundaries
    return np.asarray(beats, dtype=float)[first_beat + m * np.arange(n_periods + 1)]


def period_rates(boundaries, targets):
    # rate = music duration / source duration of each period (> 1 slows the dance down)
    return np.diff(np.asarray(targets, dtype=float)) / np.diff(np.asarray(boundaries, dtype=float))
