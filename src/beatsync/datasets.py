"""Bundled real data (``<repo>/data``, or ``$BEATSYNC_DATA``), verified by SHA-256.

Every file is a byte-for-byte copy from a public source (``data/README.md``: origins,
licences, checksums). Each file's checksum is verified once per process, so a
corrupted or edited file is refused rather than silently used.
"""

from __future__ import annotations

import json
import os
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from . import io
from .errors import ParameterError
from .motion import Motion
from .validation import check_choice

__all__ = [
    "CHECKSUMS",
    "data_dir",
    "path",
    "verify_all",
    "load_salsa",
    "load_walk",
    "load_mocap_toolbox",
    "load_madmom_sample",
    "load_click_808",
    "load_real_dev",
    "REAL_DEV_ITEMS",
    "SALSA_CLIPS",
    "WALK_CLIPS",
    "DANCE_PAIRS",
    "DancePair",
    "load_dance_pair",
]

CHECKSUMS: dict[str, str] = {
    "motion/cmu_salsa/60_01_scaled.bvh": "45b79450061bcbd651e0b11afe28349faa9a5beeccf02851eda1720e4cd75189",
    "motion/cmu_salsa/60_04_scaled.bvh": "47ab436c87c706b68770e9704c584285882c6957135153f6c33cdc9f51124af9",
    "motion/cmu_salsa/61_01_scaled.bvh": "c0704e7c6fa0d7bd16e656b0f67b1984aa3de10ce6048f697ffe8fde339e06e8",
    "motion/cmu_salsa/61_04_scaled.bvh": "8c651c30824070dc77cc47ef520d78ba64fbbf2ecebf185ffd0cabe38764a86a",
    "motion/cmu_walk_modern/005_02.bvh": "496dc2ad1ecbf70d8a2d81e4c694134d2f7d2f2210d487ea30e471f8f7d0d45f",
    "motion/cmu_walk_modern/007_01.bvh": "82747519b416ea16aafaec551292e11c4c6b33bcf6d26692e975a2de7755a37a",
    "motion/cmu_walk_modern/007_02.bvh": "33a05a0121da63e1685aa82ef87edc794e235707eecafa258786873e5d902316",
    "motion/cmu_walk_modern/007_12.bvh": "a56ebf53165e596a6754decabd974f8361ec47591fefb97e110d3098b8705901",
    "motion/mocaptoolbox/mcdemodata.mat": "d50f1a73759e86af655f2f9b932c0cb92a2025d9dc92faa22bce9da5ab178553",
    "audio/madmom/sample.beats": "7e68df80cb5c8a77f2a199022e0ffdee771af03c0cfde8794992f9ae0f829503",
    "audio/madmom/sample.onsets": "d847783458758b52c08246f25fd851b1eaf6fb3c0c71aa0b16c6be8b0e44c239",
    "audio/madmom/sample.tempo": "d90c1edbcdbb18b621142fd560c071a4db6b04ffd66631ea5e1e80ad964753f8",
    "audio/madmom/sample.wav": "d06b3c39384c4a0cf59f0bd326eda2443edf668fbb90647e37c801e59602866c",
    "audio/click_808_120bpm/808kick120bpm.mp3": "3158f626d69f15cf8fb60da6775a1a2fd7a10a48694b79175111734e04232245",
    "motion/dance_with_melody/DANCE_C_4/skeletons.json": "2a46e279b4f24e3a43b5e00241f252076d42d2aa5b7af87cb07733ec4b79ed45",
    "motion/dance_with_melody/DANCE_C_4/audio.ogg": "920bc5b516e7552528614546c38698753cd19518c8ba883d09013f07239b1b78",
    "motion/dance_with_melody/DANCE_C_4/excerpt.json": "6e41bb20eb79ed2d0c25aa1c6e39611af6753e72095a56c03730bdfcb9c87ab9",
    "motion/dance_with_melody/DANCE_R_3/skeletons.json": "c9f5c00d6c593c91ba2bb92511572301410d6ba73c8ee462348cb95e480aacf7",
    "motion/dance_with_melody/DANCE_R_3/audio.ogg": "4813bc7a12b34ef8967b5d566c5354b7d47e7ab520c84070406bc88a674d8365",
    "motion/dance_with_melody/DANCE_R_3/excerpt.json": "db642a80c667c57f7ef2f3b4559e2ac29fb3aa7e3035a1f27f12c6b3fa9aa7f4",
    "motion/dance_with_melody/DANCE_W_5/skeletons.json": "e4195da19587285ee7a6f54fdbfb143a41aeae7a0e4efbc07a127945068f0148",
    "motion/dance_with_melody/DANCE_W_5/audio.ogg": "87a84361437911c9a38844dbed31645c3366491510ca765a66a5381c4f43e641",
    "motion/dance_with_melody/DANCE_W_5/excerpt.json": "1474a79aaec2380cc2d104f6b6f6b5e2976e1ea0459481d2daf134709000cabd",
    "motion/dance_with_melody/DANCE_W_10/skeletons.json": "41177133f31c9532778ffa35e9ff8cd8426ef14147babc0ac57ff3bc26651cc6",
    "motion/dance_with_melody/DANCE_W_10/audio.ogg": "71aec927fb9b118dc06a316a9a038b61dba04be30f9d136fc47479e108362944",
    "motion/dance_with_melody/DANCE_W_10/excerpt.json": "f6ba540ecc63a839323e79916b7b6f3a4ed753863da64ab3817e03bf534586bc",
    "audio/real_dev/ballroom_Media-105901.beats": "cf6bcda78741daf5e372cfe451a7665882ceeee60ca51052188efd371b12b91b",
    "audio/real_dev/ballroom_Media-105901.wav": "284c02994f065b0323d68752dbbe5491a3102dba13c5495ddeaed84b7b489780",
    "audio/real_dev/beat_this_annotations_LICENSE.txt": "5476ec1e3de92a2ff96356452c324dc2a566e48d8c98a22503aab88763798aaa",
    "audio/real_dev/hainsworth_001.beats": "114fd1a3c8eb3bfec5ede3975a3fc70e2a91e272878be74984f7026959393437",
    "audio/real_dev/hainsworth_001.flac": "1e8a5d9b959e02d2a85ab3ad8f29c5103794bb77c3b03eaa0458ae26d5a5e1d4",
    "audio/real_dev/mirdata_LICENSE.txt": "acde8606934649e3b903e725f99788a8e2efb2a51437d12f228f31a584b954f6",
}

#: CMU salsa takes (subject_take); BVH header says 120 fps, the data is 60 fps.
SALSA_CLIPS = ("60_01", "61_01", "60_04", "61_04")
#: CMU subject 7 walking (periodic) and subject 5 pirouette (not periodic).
WALK_CLIPS = ("007_01", "007_02", "007_12", "005_02")
#: Real recordings with human beat annotations (the beat tracker's development set):
#: name -> (audio file, beat file) under ``audio/real_dev/``.
REAL_DEV_ITEMS = {
    "hainsworth_001": ("hainsworth_001.flac", "hainsworth_001.beats"),
    "ballroom_waltz": ("ballroom_Media-105901.wav", "ballroom_Media-105901.beats"),
}
#: Frame rate of every bundled CMU clip [Hz].
CMU_FPS = 60.0

_verified: set[str] = set()


def data_dir() -> Path:
    """The folder holding the bundled data."""
    d = Path(os.environ.get("BEATSYNC_DATA") or Path(__file__).resolve().parents[2] / "data")
    if not (d / "motion").is_dir():
        raise ParameterError(
            f"bundled data folder {str(d)!r} not found; run from a clone of the beatsync "
            "repository or set BEATSYNC_DATA to its data/ folder"
        )
    return d


def path(relpath: str, *, verify: bool = True) -> Path:
    """Path of a bundled data file (relative to ``data/``), checksum-verified."""
    if relpath not in CHECKSUMS:
        raise ParameterError(f"{relpath!r} is not a bundled data file; known: {sorted(CHECKSUMS)}")
    p = data_dir() / relpath
    if not p.is_file():
        raise ParameterError(f"bundled data file {str(p)!r} is missing")
    if verify and relpath not in _verified:
        digest = io.sha256_file(p)
        if digest != CHECKSUMS[relpath]:
            raise ParameterError(
                f"bundled data file {str(p)!r} fails its SHA-256 check ({digest[:12]}... != "
                f"{CHECKSUMS[relpath][:12]}...): it was modified or corrupted; restore it "
                "from git"
            )
        _verified.add(relpath)
    return p


def verify_all() -> dict[str, bool]:
    """Check every bundled file; return ``{relpath: ok}``."""
    out = {}
    for rel in CHECKSUMS:
        try:
            _verified.discard(rel)
            path(rel)
            out[rel] = True
        except ParameterError:
            out[rel] = False
    return out


def load_salsa(take: str = "60_01") -> Motion:
    """A CMU salsa clip (``"60_01"``, ``"61_01"``, ``"60_04"``, ``"61_04"``) at 60 fps."""
    check_choice(take, SALSA_CLIPS, name="take")
    m = io.read_bvh(path(f"motion/cmu_salsa/{take}_scaled.bvh"), fps=CMU_FPS)
    return m.rename(f"salsa_{take}")


def load_walk(clip: str = "007_01") -> Motion:
    """A CMU subject 7 walk (``"007_01"``, ``"007_02"``, ``"007_12"``) or the 5 pirouette
    (``"005_02"``, not periodic) at 60 fps."""
    check_choice(clip, WALK_CLIPS, name="clip")
    m = io.read_bvh(path(f"motion/cmu_walk_modern/{clip}.bvh"), fps=CMU_FPS)
    return m.rename(f"cmu_{clip}")


def load_mocap_toolbox(variable: str = "dance2") -> Motion:
    """MoCap Toolbox demo markers (``"dance1"``, ``"dance2"``, ``"walk1"``, ``"walk2"``), 60 Hz, metres."""
    check_choice(variable, ("dance1", "dance2", "walk1", "walk2"), name="variable")
    return io.read_mocap_mat(path("motion/mocaptoolbox/mcdemodata.mat"), variable)


def load_madmom_sample() -> tuple[np.ndarray, int, np.ndarray]:
    """The madmom test recording (2.8 s, 44.1 kHz) and its 4 hand-annotated beats [s]."""
    y, sr = io.read_audio(path("audio/madmom/sample.wav"))
    return y, sr, io.read_beats(path("audio/madmom/sample.beats"))


def load_click_808() -> tuple[np.ndarray, int]:
    """The BeatNet 808 kick loop (10 s, 120 BPM; tempo only, no beat list)."""
    return io.read_audio(path("audio/click_808_120bpm/808kick120bpm.mp3"))


#: Dance-with-Melody excerpts (dancer + song): cha-cha, rumba, two waltzes.
DANCE_PAIRS = ("DANCE_C_4", "DANCE_R_3", "DANCE_W_5", "DANCE_W_10")
_DANCE_STYLE = {"C": "cha-cha", "R": "rumba", "W": "waltz"}


@dataclass(frozen=True)
class DancePair:
    """A real dancer with the song they danced to (a bundled 24 s excerpt).

    ``motion``: 23 joints, 25 fps, metres, z up; ``y``: the song's matching part, mono;
    ``audio_offset`` [s]: time in ``y`` of motion frame 0 (the dataset's own alignment
    is approximate); ``excerpt``: what was cut (``config``, first frame, song time).
    """

    name: str
    style: str
    motion: Motion
    y: np.ndarray
    sr: int
    audio_offset: float
    excerpt: dict


def load_dance_pair(name: str = "DANCE_C_4") -> DancePair:
    """A Dance-with-Melody dancer and song (excerpt), checksum-verified.

    Frame ``i`` of the motion plays at time ``audio_offset + i / fps`` of ``y``.
    """
    check_choice(name, DANCE_PAIRS, name="name")
    folder = f"motion/dance_with_melody/{name}"
    excerpt = json.loads(path(f"{folder}/excerpt.json").read_text(encoding="utf-8"))
    motion = io.read_motion(
        path(f"{folder}/skeletons.json"), fps=excerpt["fps"], up="y", units="cm"
    )
    y, sr = io.read_audio(path(f"{folder}/audio.ogg"))
    style, offset = _DANCE_STYLE[name.split("_")[1]], float(excerpt["audio_offset_s"])
    return DancePair(name, style, motion.rename(name), y, sr, offset, excerpt)


def load_real_dev(name: str) -> tuple[np.ndarray, int, np.ndarray]:
    """``(y, sr, beats [s])`` of a real recording with human beat annotations: Hainsworth
    excerpt 001 (4/4, about 100 BPM) or ``"ballroom_waltz"`` (Media-105901, 3/4, 84 BPM)."""
    check_choice(name, REAL_DEV_ITEMS, name="name")
    audio, beats = REAL_DEV_ITEMS[name]
    y, sr = io.read_audio(path(f"audio/real_dev/{audio}"))
    return y, sr, io.read_beats(path(f"audio/real_dev/{beats}"))
