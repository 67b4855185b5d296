"""Solutions to the exercises of tutorial 5 (real dancers, the two alignment scores)."""

import numpy as np


def _nearest(events, reference):
    # distance from each event to the nearest reference time [s]
    return np.min(np.abs(np.asarray(events)[:, None] - np.asarray(reference)[None, :]), axis=1)


def alignment_motion(motion_beats, music_beats, sigma):
    # Li et al. 2021: averaged over the motion beats
    d = _nearest(motion_beats, music_beats)
    return float(np.mean(np.exp(-(d**2) / (2 * sigma**2))))


def alignment_music(motion_beats, music_beats, sigma):
    # Siyao et al. 2022: averaged over the music beats
    d = _nearest(music_beats, motion_beats)
    return float(np.mean(np.exp(-(d**2) / (2 * sigma**2))))


# every motion beat sits on a music beat (1.0); every second music beat is one beat
# period (0.5 s, ten sigmas) from the nearest motion beat (about 0), so 0.5
every_other_beat = (1.0, 0.5)
