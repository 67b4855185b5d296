"""Answers to the exercises of tutorial 01 (periodic motion segmentation). Try first!"""

import numpy as np


def pearson_distance(a, b):
    # the later period b resampled linearly onto the earlier period's len(a) samples
    clock = np.linspace(0, b.size - 1, a.size)
    b_on_a = np.interp(clock, np.arange(b.size), b)
    return 1.0 - np.corrcoef(a, b_on_a)[0, 1]


def energy(x, frames):
    total = 0.0
    for a, b, c in zip(frames[:-2], frames[1:-1], frames[2:]):
        for channel in x:
            total += pearson_distance(channel[a : b + 1], channel[b : c + 1])
    return total


def fft_period(x, fps, period_range):
    n = x.shape[1]
    nfft = 8 * 2 ** int(np.ceil(np.log2(n)))
    power = (np.abs(np.fft.rfft(x * np.hanning(n), n=nfft, axis=1)) ** 2).sum(axis=0)
    freqs = np.fft.rfftfreq(nfft, d=1 / fps)
    band = (freqs >= 1 / period_range[1]) & (freqs <= 1 / period_range[0])
    return 1 / freqs[band][np.argmax(power[band])]
