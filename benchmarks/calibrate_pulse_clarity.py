"""Calibration data of the no-clear-pulse warning (:mod:`beatsync.beats.tracker`).

Prints, for 84 noises (white, 10 seeds, and brown, 2 seeds, at 2, 3, 5, 7, 10, 15 and
30 s) and every bundled real recording (the annotated ones, the madmom sample and the
four Dance-with-Melody songs), the path salience (mean resonator salience along the
decoded tempo path) and its ratio to the null of the same onsets in random order
(:func:`beatsync.beats.tracker.pulse_clarity_null`): the numbers beside
``MIN_PULSE_CLARITY``, ``MIN_PATH_SALIENCE`` and ``CLEAR_PULSE``.

Usage::

    .venv/bin/python benchmarks/calibrate_pulse_clarity.py
"""

from __future__ import annotations

import numpy as np

from beatsync import datasets, io
from beatsync.beats import metrical, tracker
from beatsync.beats.onset import compute_onsets, frontend_settings
from beatsync.beats.tempo import tempo_hmm

NOISE_SECONDS = (2, 3, 5, 7, 10, 15, 30)
SR = 22050


def clarity(y: np.ndarray, sr: float) -> tuple[float, float]:
    """Path salience and the null, as :func:`beatsync.beats.track_beats` computes them."""
    y, sr = tracker.check_audio(y, sr)
    ons = compute_onsets(y, sr, frontend_settings({}, sr))
    model = metrical.METER_MODEL
    obs = tracker.observe(ons, (y, sr), model=model)
    path = tempo_hmm(
        obs.log_obs, obs.periods, trans_sigma=tracker.TRANS_SIGMA, p_jump=tracker.P_JUMP
    )
    path_salience = float(np.mean(obs.salience[path, np.arange(path.size)]))
    null = tracker.pulse_clarity_null(ons, obs.starts, obs.stops, obs.periods, model, obs.max_hz)
    return path_salience, null


def main() -> int:
    rows = []
    for kind, seeds in (("white", 10), ("brown", 2)):
        for seed in range(seeds):
            rng = np.random.default_rng(seed)
            for seconds in NOISE_SECONDS:
                x = rng.standard_normal(int(seconds * SR))
                if kind == "brown":
                    x = np.cumsum(x)
                    x -= np.linspace(x[0], x[-1], x.size)
                x = (0.5 * x / np.abs(x).max()).astype(np.float32)
                sal, null = clarity(x, SR)
                rows.append((f"{kind} noise, seed {seed}", seconds, sal, sal / null))
    print("| noise | seconds | path salience | ratio to the null |\n|---|---|---|---|")
    for name, seconds, sal, ratio in sorted(rows, key=lambda r: -r[3])[:10]:
        print(f"| {name} | {seconds} | {sal:.3f} | {ratio:.2f} |")
    ratios = np.array([r[3] for r in rows])
    saliences = np.array([r[2] for r in rows])
    print(
        f"\n{len(rows)} noises: ratio {ratios.min():.2f}-{ratios.max():.2f}, "
        f"path salience {saliences.min():.3f}-{saliences.max():.3f} (the 10 highest "
        "ratios above)\n"
    )
    real = [("hainsworth_001", *datasets.load_real_dev("hainsworth_001")[:2])]
    real.append(("ballroom_waltz", *datasets.load_real_dev("ballroom_waltz")[:2]))
    real.append(("madmom sample", *datasets.load_madmom_sample()[:2]))
    for song in ("DANCE_C_4", "DANCE_R_3", "DANCE_W_5", "DANCE_W_10"):
        y, sr = io.read_audio(datasets.path(f"motion/dance_with_melody/{song}/audio.ogg"))
        real.append((song, y, sr))
    print("| recording | seconds | path salience | ratio to the null |\n|---|---|---|---|")
    for name, y, sr in real:
        sal, null = clarity(y, sr)
        print(f"| {name} | {y.size / sr:.1f} | {sal:.3f} | {sal / null:.2f} |")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
