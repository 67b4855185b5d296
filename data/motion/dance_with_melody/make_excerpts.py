"""Cut the bundled Dance-with-Melody excerpts from the full dataset (kept for the record).

Usage: python make_excerpts.py SOURCE_FOLDER [DEST_FOLDER]

SOURCE_FOLDER holds DANCE_C_4/, DANCE_R_3/, DANCE_W_5/, DANCE_W_10/ as published
(skeletons.json, config.json, audio.mp3). For each dancer the same rule: dance frames
125-724 (24 s at 25 fps, starting 5 s into the dance) and the matching part of its song,
with 2 s of music before and after. Skeleton numbers are copied as they are (the
excerpt is the same JSON layout, sliced); the song is decoded with ffmpeg (from the
imageio-ffmpeg package) and stored as mono 22.05 kHz Ogg Vorbis. ``excerpt.json``
records the mapping: dance frame i of the excerpt plays at audio time
``audio_offset_s + i / fps`` of ``audio.ogg``, which is song time
``(start_position + first_frame + i) / fps`` of the original ``config.json``.
"""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import numpy as np
import soundfile as sf

PAIRS = ("DANCE_C_4", "DANCE_R_3", "DANCE_W_5", "DANCE_W_10")
FPS = 25.0
FIRST, N_FRAMES = 125, 600
MARGIN_S = 2.0
SR = 22050


def cut(src: Path, dest: Path, pair: str) -> None:
    import imageio_ffmpeg

    doc = json.loads((src / pair / "skeletons.json").read_text())
    config = json.loads((src / pair / "config.json").read_text())
    stop = FIRST + N_FRAMES
    out = {
        "length": N_FRAMES,
        "center": doc["center"][FIRST:stop],
        "skeletons": doc["skeletons"][FIRST:stop],
    }
    (dest / pair).mkdir(parents=True, exist_ok=True)
    (dest / pair / "skeletons.json").write_text(json.dumps(out))
    song_start = (config["start_position"] + FIRST) / FPS
    t0 = song_start - MARGIN_S
    duration = N_FRAMES / FPS + 2 * MARGIN_S
    cmd = [
        imageio_ffmpeg.get_ffmpeg_exe(), "-v", "error", "-i", str(src / pair / "audio.mp3"),
        "-ss", f"{t0:.3f}", "-t", f"{duration:.3f}", "-ac", "1", "-ar", str(SR),
        "-f", "f32le", "-",
    ]
    y = np.frombuffer(subprocess.run(cmd, check=True, capture_output=True).stdout, np.float32)
    sf.write(dest / pair / "audio.ogg", y, SR, format="OGG", subtype="VORBIS")
    excerpt = {
        "source": f"{pair}/skeletons.json and {pair}/audio.mp3 of the Dance-with-Melody dataset",
        "config": config,
        "fps": FPS,
        "first_frame": FIRST,
        "n_frames": N_FRAMES,
        "song_start_s": round(song_start, 6),
        "audio_offset_s": MARGIN_S,
        "audio_sr": SR,
    }
    (dest / pair / "excerpt.json").write_text(json.dumps(excerpt, indent=2) + "\n")


if __name__ == "__main__":
    source = Path(sys.argv[1])
    target = Path(sys.argv[2]) if len(sys.argv) > 2 else Path(__file__).resolve().parent
    for name in PAIRS:
        cut(source, target, name)
