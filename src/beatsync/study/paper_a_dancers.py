"""Real dancers and their music: beat alignment before and after re-synchronisation.

An extension of paper A's study to real dance data: the four Dance-with-Melody excerpts
bundled in ``data/`` (:func:`beatsync.datasets.load_dance_pair`: a cha-cha, a rumba and
two waltzes, joint positions at 25 fps, each with the song it was danced to). For each
dancer:

(a) how well the dancer's own motion beats (kinematic beats,
    :func:`beatsync.motion_beats.kinematic_beats`) align with the beats of their own
    song (tracked with :func:`beatsync.beats.track_beats`), with both published
    beat-alignment scores (:mod:`beatsync.evaluate.alignment`; sigma in seconds);
(b) the same after :func:`beatsync.sync.synchronize` re-synchronises the dancer to
    another song (the other dance of the same meter: cha-cha <-> rumba, waltz <-> waltz),
    covering that song with ``fill="loop"``;
(c) a random-offset control (:func:`beatsync.evaluate.alignment.offset_control`: the
    motion beats shifted by one random offset within a beat period), for (a) and (b);
(d) the dance's period and motion-beat interval against the song's beat period;
(e) whether the re-synchronised dancer still moves like the dancer (:func:`motion_table`:
    playback speed, joint speed and acceleration against the dancer's own, the joins),
    and the same before the whole-dance counts and seamless loops (:func:`before_table`).

The dataset says which part of each song was danced, not that the steps sit on its
(here tracked, not annotated) beats: (a) measures this data, not the dancers' skill, and
four excerpts are four examples, not a benchmark. The scores count only beats inside the
span both the dance and the song (28 s) play.

Notebook: ``notebooks/paper_a_ext_real_dancers.ipynb``.
"""

from __future__ import annotations

import base64
import warnings
from pathlib import Path
from typing import Any

import numpy as np

from ..datasets import DANCE_PAIRS, DancePair, load_dance_pair
from ..errors import BeatsyncWarning, ParameterError
from ..evaluate.alignment import DEFAULT_SIGMA, alignment_scores, offset_control
from ..motion_beats import kinematic_beats
from ..sync.quality import instantaneous_speed
from .artifacts import write_artifacts

__all__ = [
    "OTHER_SONG",
    "load_pairs",
    "track_songs",
    "song_table",
    "own_song_scores",
    "resync_scores",
    "dancer_table",
    "period_table",
    "summary_table",
    "motion_table",
    "before_table",
    "speed_figure",
    "beats_figure",
    "dancer_video",
    "video_html",
    "write_artifacts",
]

#: The song each dancer is re-synchronised to: the other dance of the same meter.
OTHER_SONG = {
    "DANCE_C_4": "DANCE_R_3",
    "DANCE_R_3": "DANCE_C_4",
    "DANCE_W_5": "DANCE_W_10",
    "DANCE_W_10": "DANCE_W_5",
}


def load_pairs(names: list[str] | tuple[str, ...] = DANCE_PAIRS) -> dict[str, DancePair]:
    """The bundled dancer + song excerpts, checksum-verified, by name."""
    unknown = [n for n in names if n not in DANCE_PAIRS]
    if unknown:
        raise ParameterError(f"unknown dance pair(s) {unknown}; choose from {DANCE_PAIRS}")
    return {n: load_dance_pair(n) for n in names}


def track_songs(pairs: dict[str, DancePair]) -> dict[str, dict[str, Any]]:
    """Beats of every song (tracked; times in the excerpt's audio [s]) and its meter:
    name -> ``{"beats", "tempo_bpm", "beats_per_bar", "duration_s", "warning"}``."""
    from ..beats import track_beats

    songs = {}
    for name, pair in pairs.items():
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always", BeatsyncWarning)
            track = track_beats(pair.y, pair.sr)
        beats = np.asarray(track.beats, dtype=np.float64)
        songs[name] = {
            "beats": beats,
            "tempo_bpm": 60.0 / float(np.median(np.diff(beats))),
            "beats_per_bar": getattr(track, "beats_per_bar", None),
            "duration_s": len(pair.y) / pair.sr,
            "warning": "; ".join(str(w.message) for w in caught),
        }
    return songs


def song_table(pairs: dict[str, DancePair], songs: dict[str, dict[str, Any]]) -> Any:
    """One row per song: style, length, tracked beats, tempo, meter, tracker warning."""
    import pandas as pd

    return pd.DataFrame(
        [
            {
                "song of": name,
                "style": pair.style,
                "seconds": len(pair.y) / pair.sr,
                "beats": int(songs[name]["beats"].size),
                "tempo [BPM]": songs[name]["tempo_bpm"],
                "beats/bar": songs[name]["beats_per_bar"],
                "tracker note": songs[name]["warning"] or "",
            }
            for name, pair in pairs.items()
        ]
    )


def _scores(mb: np.ndarray, yb: np.ndarray, span: tuple[float, float], *, sigma, n_control, seed):
    """Both scores and their random-offset control, on the beats inside ``span``."""
    sc = alignment_scores(mb, yb, sigma=sigma, span=span)
    inside = (mb >= span[0]) & (mb <= span[1])
    ctrl = offset_control(
        mb[inside], yb[(yb >= span[0]) & (yb <= span[1])], sigma=sigma,
        n_trials=n_control, seed=seed,
    )  # fmt: skip
    return {
        "motion": sc["alignment_motion"],
        "music": sc["alignment_music"],
        "control_motion": ctrl["alignment_motion_mean"],
        "control_music": ctrl["alignment_music_mean"],
        "n_motion_beats": sc["n_motion_beats"],
        "n_music_beats": sc["n_music_beats"],
    }


def own_song_scores(
    pair: DancePair,
    beats: Any,
    *,
    sigma: float = DEFAULT_SIGMA,
    n_control: int = 200,
    seed: int = 0,
) -> dict[str, Any]:
    """(a) and (c): the real dancer against their own song, as the dataset aligns them.

    Motion beats are moved to the excerpt's audio time (``+ pair.audio_offset``) and
    compared with the song's beats while the dance plays.
    """
    mb = kinematic_beats(pair.motion) + pair.audio_offset
    yb = np.asarray(beats, dtype=np.float64)
    span = (pair.audio_offset, pair.audio_offset + float(pair.motion.duration))
    return _scores(mb, yb, span, sigma=sigma, n_control=n_control, seed=seed)


def resync_scores(
    result: Any, beats: Any, *, sigma: float = DEFAULT_SIGMA, n_control: int = 200, seed: int = 0
) -> dict[str, Any]:
    """(b) and (c): scores of the re-synchronised dancer on the song's beats it covers."""
    yb = np.asarray(beats, dtype=np.float64)
    span = (float(yb[0]), min(float(yb[-1]), float(result.motion.duration)))
    mb = kinematic_beats(result.motion)
    return _scores(mb, yb, span, sigma=sigma, n_control=n_control, seed=seed)


def dancer_table(
    pairs: dict[str, DancePair],
    songs: dict[str, dict[str, Any]],
    *,
    modes: tuple[str, ...] = ("beats", "auto"),
    sigma: float = DEFAULT_SIGMA,
    n_control: int = 200,
    seed: int = 0,
    period_range: tuple[float, float] = (0.8, 5.0),
) -> tuple[Any, dict[tuple[str, str], Any]]:
    """(a)-(c) for every dancer: one row per dancer and sync mode.

    Columns ``own_*`` are the dancer with their own song, ``after_*`` re-synchronised
    to :data:`OTHER_SONG`, ``*_control_*`` the random-offset control of each; ``_motion``
    averages over motion beats (Li et al. 2021), ``_music`` over music beats (Siyao et
    al. 2022); ``sigma`` in seconds. Returns the table and ``(dancer, mode) -> SyncResult``
    (:func:`beatsync.sync.synchronize` with ``fill="loop"``; its warnings, e.g. ``"auto"``
    falling back, in ``report["warnings"]``).
    """
    import pandas as pd

    from ..sync import synchronize

    rows, results = [], {}
    kw = {"sigma": sigma, "n_control": n_control, "seed": seed}
    for name, pair in pairs.items():
        other = OTHER_SONG[name]
        if other not in songs:
            raise ParameterError(f"{name} is re-synchronised to {other}'s song: load {other} too")
        own = own_song_scores(pair, songs[name]["beats"], **kw)
        for mode in modes:
            with warnings.catch_warnings(record=True) as caught:
                warnings.simplefilter("always", BeatsyncWarning)
                res = synchronize(
                    pair.motion,
                    None,
                    songs[other]["beats"],
                    mode=mode,
                    fill="loop",
                    period_range=period_range,
                    beats_per_bar=songs[other]["beats_per_bar"],
                    song_end=songs[other]["duration_s"],
                )
            res.report["warnings"] = [str(w.message) for w in caught]
            results[(name, mode)] = res
            after = resync_scores(res, songs[other]["beats"], **kw)
            rep = res.report
            rows.append(
                {
                    "dancer": name,
                    "style": pair.style,
                    "song": other,
                    "mode": mode,
                    "mode used": rep["mode"],
                    "beats per unit": rep["beats_per_period"],
                    "repetitions": rep["repetitions"],
                    **{
                        f"{w}_{c}{s}": sc[f"{c}{s}"]
                        for s in ("motion", "music")
                        for w, sc in (("own", own), ("after", after))
                        for c in ("", "control_")
                    },
                    "sigma_s": sigma,
                    "note": "; ".join(rep["warnings"])[:160],
                }
            )
    return pd.DataFrame(rows), results


def period_table(
    pairs: dict[str, DancePair],
    songs: dict[str, dict[str, Any]],
    *,
    period_range: tuple[float, float] = (0.8, 5.0),
) -> Any:
    """(d) The dance's period (paper A's segmentation of its joint angles over
    ``period_range``) and median motion-beat interval against its song's median beat."""
    import pandas as pd

    from ..motion import segmentation_view
    from ..segment import segment

    rows = []
    for name, pair in pairs.items():
        seg = segment(segmentation_view(pair.motion), period_range=period_range)
        mb = kinematic_beats(pair.motion)
        beat = 60.0 / songs[name]["tempo_bpm"]
        period = float(np.mean(np.diff(seg.boundaries)))
        interval = float(np.median(np.diff(mb)))
        rows.append(
            {
                "dancer": name,
                "style": pair.style,
                "dance period [s]": period,
                "motion-beat interval [s]": interval,
                "song beat period [s]": beat,
                "period / beat": period / beat,
                "motion-beat interval / beat": interval / beat,
                "song beats/bar": songs[name]["beats_per_bar"],
            }
        )
    return pd.DataFrame(rows)


def summary_table(table: Any, *, mode: str = "beats") -> Any:
    """Per dancer for one sync mode: after re-sync vs control vs own song (both scores),
    and whether the target holds (after > both, on both scores)."""
    t = table[table["mode"] == mode].copy()
    for s in ("motion", "music"):
        t[f"beats_{s}_target"] = (t[f"after_{s}"] > t[f"after_control_{s}"]) & (
            t[f"after_{s}"] > t[f"own_{s}"]
        )
    cols = ["dancer", "style", "song"]
    cols += [f"{w}_{s}" for s in ("motion", "music") for w in ("own", "after", "after_control")]
    return t[cols + ["beats_motion_target", "beats_music_target"]].reset_index(drop=True)


def _playback_speed(res: Any) -> np.ndarray:
    covered = (res.warp.tgt[0], res.warp.tgt[-1])
    return instantaneous_speed(res.warp_src_times, res.motion.fps, covered)


def motion_table(
    pairs: dict[str, DancePair],
    table: Any,
    results: dict[tuple[str, str], Any],
    *,
    mode: str = "beats",
    band: tuple[float, float] = (0.8, 1.25),
) -> Any:
    """(e) Per dancer re-synchronised to :data:`OTHER_SONG` (one sync ``mode``): playback
    speed, joint kinematics against the dancer's own, the joins, and the alignment
    scores of :func:`dancer_table` (after, random-offset control, own song); speeds and
    kinematics as the sync report computes them from the output frames
    (:mod:`beatsync.sync.quality`).
    """
    import pandas as pd

    rows = []
    t = table[table["mode"] == mode].set_index("dancer")
    for name in pairs:
        res = results[(name, mode)]
        kin = res.report["kinematics"]
        ratio, own_peak = kin["ratio"], kin["input"]["peak_joint_speed"]
        speed = _playback_speed(res)
        joins = [j.get("peak_joint_speed", np.nan) for j in res.report.get("joins", [])]
        used = res.report.get("beats_per_motion_beat_used", {})
        rows.append(
            {
                "dancer": name,
                "song": OTHER_SONG[name],
                "beats per motion beat used": ", ".join(f"{k}x{v}" for k, v in used.items()),
                "speed in band": float(np.mean((speed >= band[0]) & (speed <= band[1]))),
                "speed min": float(speed.min()),
                "speed median": float(np.median(speed)),
                "speed max": float(speed.max()),
                "p99 speed / own": ratio["p99_joint_speed"],
                "p99 accel / own": ratio["p99_joint_accel"],
                "peak / own peak": ratio["peak_joint_speed"],
                "joins": len(joins),
                "join peak / own peak": float(np.max(joins) / own_peak) if joins else np.nan,
                **{
                    f"{w}_{s}": t.loc[name, f"{col}_{s}"]
                    for s in ("motion", "music")
                    for w, col in (("after", "after"), ("control", "after_control"), ("own", "own"))
                },
            }
        )
    return pd.DataFrame(rows)


def before_table(path: str | Path, pairs: dict[str, DancePair] | None = None) -> Any:
    """(e) before: the record of ``benchmarks/bench_resync.py --label before`` (the code
    before the whole-dance beat counts and seamless loops; every dancer on every other
    song with ``sync``'s defaults), for the pairs of :data:`OTHER_SONG`, in the columns
    of :func:`motion_table`. Empty when the record is missing (a benchmark not run)."""
    import json

    import pandas as pd

    p = Path(path)
    if not p.is_file():
        return pd.DataFrame()
    names = list(OTHER_SONG) if pairs is None else list(pairs)
    rows = []
    for r in json.loads(p.read_text())["rows"]:
        if r["dancer"] not in names or OTHER_SONG[r["dancer"]] != r["song"]:
            continue
        s = r["speed"]
        rows.append(
            {
                "dancer": r["dancer"],
                "song": r["song"],
                "speed in band": s["in_band"],
                "speed min": s["min"],
                "speed median": s["median"],
                "speed max": s["max"],
                "p99 speed / own": r["p99_speed_ratio"],
                "p99 accel / own": r["p99_accel_ratio"],
                "peak / own peak": r["peak_ratio"],
                **{
                    f"{w}_{s}": r[w][s]
                    for s in ("motion", "music")
                    for w in ("after", "control", "own")
                },
            }
        )
    return pd.DataFrame(rows)


def speed_figure(results: dict[tuple[str, str], Any], *, mode: str = "beats") -> Any:
    """Distribution of the instantaneous playback speed of every re-synchronised dancer
    (share of output time), the band 0.8-1.25 shaded."""
    import matplotlib.pyplot as plt

    names = [d for d, m in results if m == mode]
    fig, axes = plt.subplots(1, len(names), figsize=(3.0 * len(names), 2.6), sharey=True)
    axes = np.atleast_1d(axes)
    bins = np.linspace(0.3, 2.5, 45)
    for ax, name in zip(axes, names, strict=True):
        speed = _playback_speed(results[(name, mode)])
        w = np.full(speed.size, 1.0 / max(speed.size, 1))
        ax.axvspan(0.8, 1.25, color="tab:green", alpha=0.15, lw=0)
        ax.hist(np.clip(speed, bins[0], bins[-1]), bins=bins, weights=w, color="tab:blue")
        ax.set_title(f"{name} on {OTHER_SONG[name]}", fontsize=9)
        ax.set_xlabel("playback speed")
    axes[0].set_ylabel("share of output time")
    fig.tight_layout()
    return fig


def beats_figure(
    pair: DancePair, own_beats: Any, result: Any, new_beats: Any, *, seconds: float = 12.0
) -> Any:
    """Motion beats against music beats over the first ``seconds``: the dancer with their
    own song (audio time), then re-synchronised to the new song."""
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(2, 1, figsize=(10, 3.6), sharex=False)
    before = kinematic_beats(pair.motion) + pair.audio_offset
    lo = pair.audio_offset
    panels = [
        (axes[0], before, np.asarray(own_beats), lo, f"{pair.name} with its own song"),
        (axes[1], kinematic_beats(result.motion), np.asarray(new_beats), 0.0,
         f"{pair.name} re-synchronised ({result.report['mode']} mode) to another song"),
    ]  # fmt: skip
    for ax, mb, yb, t0, title in panels:
        ax.vlines(yb, 0.0, 1.0, color="tab:red", lw=1.5, label="music beats")
        ax.vlines(mb, 0.15, 0.85, color="tab:blue", lw=3, alpha=0.7, label="motion beats")
        ax.set_xlim(t0, t0 + seconds)
        ax.set_yticks([])
        ax.set_title(title, fontsize=10)
    axes[1].set_xlabel("song time [s]")
    axes[0].legend(loc="upper right", fontsize=8, ncols=2)
    fig.tight_layout()
    return fig


def dancer_video(
    result: Any,
    pair_of_song: DancePair,
    beats: Any,
    path: str | Path,
    *,
    seconds: float,
    fps: float = 15.0,
    size: tuple[int, int] = (640, 480),
    title: str | None = None,
) -> Path:
    """The re-synchronised dancer over the first ``seconds`` of the new song, as MP4."""
    from .paper_a_sync import animation_video

    return animation_video(
        result,
        (pair_of_song.y, pair_of_song.sr),
        beats,
        path,
        seconds=min(float(seconds), float(result.motion.duration)),
        fps=fps,
        size=size,
        azimuth=30.0,
        title=title,
    )


def video_html(path: str | Path, *, width: int = 400) -> Any:
    """An HTML5 ``<video>`` element with the MP4 embedded (plays inside JupyterLab)."""
    from IPython.display import HTML

    p = Path(path)
    if p.suffix.lower() != ".mp4":
        return HTML(f"<p>No MP4 was written (ffmpeg missing?): {p.name}</p>")
    data = base64.b64encode(p.read_bytes()).decode("ascii")
    return HTML(
        f'<video width="{int(width)}" controls><source src="data:video/mp4;base64,{data}" '
        'type="video/mp4">Your browser cannot play this MP4.</video>'
    )
