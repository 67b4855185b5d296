"""Our tracker on the whole songs that the Dance-with-Melody dancers danced to.

The project bundles 28 s excerpts of the four songs (``data/motion/dance_with_melody``);
the whole songs (204-245 s, MP3) are in the shared data folder of the development
machine and are not redistributed. This script tracks each whole song and compares its
tempo path with our tempo of the bundled excerpt: how many tempo windows are within
8 % of that tempo, how many are at 4/3 or 3/4 of it or at twice or half of it
(another metrical level), and the tempo of the others. The songs have no annotations,
so this measures consistency, not accuracy.

Usage::

    .venv/bin/python benchmarks/whole_dance_songs.py [--shared ../shared/data]

Not part of ``run_all.py``: a clone without the shared folder cannot run it. On
2026-11-29, with the resonators' spectrum sampled at 3 bins per pass band
(``metrical.resonator_fft_size``): the cha-cha and the rumba keep the excerpt's tempo
in every window (199 and 238 windows); the waltzes DANCE_W_5 and DANCE_W_10 in 175 of
197 and 187 of 239 windows (DANCE_W_5's other 22 at 91-95 BPM; DANCE_W_10's 16 at 4/3
of it and 36 at 94-107 BPM); both warn of no clear pulse. On 2026-11-28, with the
coarser sampling: 189 of 197 and 147 of 239, none at 4/3 (DANCE_W_10's other 92 at
95-106 BPM; only it warned). With a beat of three tatums weighed as one of two or four
(before ``MeterModel.tatum_ratio_weights``): 93 and 56 windows, with 51 and 129 at 4/3.
"""

from __future__ import annotations

import argparse
import sys
import warnings
from pathlib import Path

import numpy as np

#: Relative tempo tolerance of "the same tempo" (as ``evaluate.beats.octave_relation``).
TOLERANCE = 0.08


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument(
        "--shared",
        default=str(Path(__file__).resolve().parents[2] / "shared" / "data"),
        help="the shared data folder (holds motion/dance_with_melody/NAME/audio.mp3)",
    )
    args = ap.parse_args()
    root = Path(args.shared) / "motion" / "dance_with_melody"
    if not root.is_dir():
        print(f"{root} does not exist: the whole songs are not on this machine", file=sys.stderr)
        return 2

    from beatsync import datasets, io
    from beatsync.beats import track_beats
    from beatsync.errors import BeatsyncWarning

    print(
        "| song | seconds | excerpt: tempo / beats per bar | whole song: median tempo / "
        "beats per bar | windows within 8 % of the excerpt's tempo | at 4/3 of it | "
        "at 3/4 of it | at 2 or 1/2 times it | the others [bpm] | warned |"
    )
    print("|---|---|---|---|---|---|---|---|---|---|")
    for name in datasets.DANCE_PAIRS:
        pair = datasets.load_dance_pair(name)
        excerpt = track_beats(pair.y, pair.sr)
        y, sr = io.read_audio(root / name / "audio.mp3")
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always", BeatsyncWarning)
            song = track_beats(y, sr)
        warned = any("no clear pulse" in str(w.message) for w in caught)
        ratio = np.asarray(song.tempo_curve) / excerpt.tempo

        def near(r: float, ratio=ratio) -> np.ndarray:
            return np.abs(np.log(ratio / r)) < np.log(1 + TOLERANCE)

        levels = {r: near(r) for r in (1.0, 4 / 3, 3 / 4, 2.0, 0.5)}
        others = np.asarray(song.tempo_curve)[~np.any(list(levels.values()), axis=0)]
        spread = f"{others.min():.0f}-{others.max():.0f} ({others.size})" if others.size else ""

        print(
            f"| {name} ({pair.style}) | {y.size / sr:.0f} | {excerpt.tempo:.1f} / "
            f"{excerpt.beats_per_bar} | {song.tempo:.1f} / {song.beats_per_bar} | "
            f"{levels[1.0].sum()} of {ratio.size} | {levels[4 / 3].sum()} | "
            f"{levels[3 / 4].sum()} | {levels[2.0].sum() + levels[0.5].sum()} | {spread} | "
            f"{'yes' if warned else 'no'} |"
        )
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
