"""The README's picture: a real dancer re-synchronised to another dancer's song.

The cha-cha dancer of the bundled Dance-with-Melody excerpts (DANCE_C_4, joint
positions at 25 fps) is synchronised to the rumba's song (DANCE_R_3): the song's beats
are tracked, the dancer's own motion beats are landed on them (``mode="beats"``), and
the poses of four beats are drawn, two per beat, the poses on a beat in red; below,
the dancer's mean joint speed with the song's beats.

Usage::

    .venv/bin/python scripts/readme_strip.py [--out docs/img/strip.png]
"""

from __future__ import annotations

import argparse
import warnings
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

from beatsync import datasets, render  # noqa: E402
from beatsync.beats import track_beats  # noqa: E402
from beatsync.errors import BeatsyncWarning  # noqa: E402
from beatsync.motion_beats import kinematic_beats  # noqa: E402
from beatsync.sync import synchronize  # noqa: E402

DANCER, SONG = "DANCE_C_4", "DANCE_R_3"


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", type=Path, default=Path("docs/img/strip.png"))
    ap.add_argument("--start", type=float, default=8.0, help="strip start [s]")
    ap.add_argument("--azimuth", type=float, default=90.0, help="camera about the vertical [deg]")
    args = ap.parse_args()

    dancer = datasets.load_dance_pair(DANCER)
    song = datasets.load_dance_pair(SONG)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", BeatsyncWarning)  # the report says it all
        beats = track_beats(song.y, song.sr).beats
        result = synchronize(dancer.motion, None, beats, mode="beats", fill="loop")
    synced = result.motion

    fig, (top, bottom) = plt.subplots(
        2, 1, figsize=(9.0, 4.6), gridspec_kw={"height_ratios": [3, 1.2]}
    )
    times = render.beat_strip_times(beats, start=args.start, n_beats=4, per_beat=2)
    render.plot_frames(synced, times, beats=beats, ax=top, azimuth=args.azimuth)
    top.set_title(
        f"A real cha-cha dancer ({DANCER}) re-synchronised to a rumba ({SONG}): "
        "poses on the song's beats in red",
        fontsize=9,
    )
    render.plot_beat_timeline(synced, beats=beats, motion_beats=kinematic_beats(synced), ax=bottom)
    bottom.set_xlim(times[0] - 2.0, times[-1] + 2.0)
    bottom.axvspan(times[0], times[-1], color="0.9", zorder=0)
    fig.tight_layout()
    args.out.parent.mkdir(parents=True, exist_ok=True)
    render.save_figure(fig, args.out, dpi=110)
    print(f"wrote {args.out}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
