"""Paper A, Figure 2: the segmentation study (clips, period table, figure, error table).

One call per step of ``notebooks/paper_a_fig02_segmentation.ipynb``: the clips that
stand in for the paper's Cretan dances, their segmentation with the default and the
knee channels, the refusal of a non-periodic clip, and the boundary error against
synthetic ground truth beside two baselines. Periods and boundaries are in seconds
unless a column says ``frames``; boundary errors are in frames of the synthetic clip.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from .. import datasets
from ..errors import ParameterError
from ..evaluate.segmentation import boundary_errors
from ..motion import Motion, segmentation_view
from ..segment import Segmentation, segment, segment_values
from ..segment.channels import nonconstant_channels, standardise
from ..segment.checks import check_period_range, check_values
from ..segment.period import estimate_period, estimation_band, uniform_frames
from ..synth.motion import SyntheticMotion, periodic_motion
from ..validation import check_finite, check_fps, frames_to_time, time_to_frames
from .paper_a_sync import crop

__all__ = [
    "SegmentationClips",
    "load_clips",
    "clip_table",
    "period_table",
    "figure",
    "plot_segmentation",
    "nonperiodic_refusal",
    "uniform_baseline",
    "minima_baseline",
    "synthetic_error_table",
    "error_pivot",
]


@dataclass(frozen=True)
class SegmentationClips:
    """The three clips of Figure 2 (MoCap Toolbox markers as joint angles, a CMU salsa
    take, a synthetic clip with its true boundaries), and by clip name its left and
    right knee channels and its documented period."""

    toolbox: Motion
    salsa: Motion
    synth: SyntheticMotion
    knees: dict
    reference: dict

    @property
    def motions(self) -> tuple[Motion, Motion, Motion]:
        """The clips in the order of the table and the figure."""
        return self.toolbox, self.salsa, self.synth.motion


def load_clips(
    *,
    salsa_take: str,
    toolbox_recording: str,
    max_clip_seconds: float,
    synth_n_frames: int,
    synth_channels: int,
    synth_fps: float,
    synth_periods: int,
    synth_snr_db: float | None,
    synth_seed: int,
) -> SegmentationClips:
    """Load the real clips (cropped to ``max_clip_seconds`` [s]) and make the synthetic one.

    The MoCap Toolbox markers become joint angles (:func:`beatsync.motion.segmentation_view`).
    """
    salsa = crop(datasets.load_salsa(salsa_take), max_clip_seconds)
    toolbox = segmentation_view(datasets.load_mocap_toolbox(toolbox_recording))
    toolbox = crop(toolbox, max_clip_seconds)
    synth = periodic_motion(
        n_frames=synth_n_frames,
        n_channels=synth_channels,
        fps=synth_fps,
        n_periods=synth_periods,
        snr_db=synth_snr_db,
        seed=synth_seed,
    )
    knees = {salsa.name: ["lShin_Xrotation", "rShin_Xrotation"],
             toolbox.name: ["knee_L_angle", "knee_R_angle"],
             synth.motion.name: ["ch00_angle", "ch01_angle"]}  # fmt: skip
    reference = {salsa.name: "knee ~1.0 s (data/README.md)",
                 toolbox.name: "0.51 s vertical period (MoCap Toolbox manual)",
                 synth.motion.name: f"{synth.period:.3f} s (ground truth)"}  # fmt: skip
    return SegmentationClips(toolbox, salsa, synth, knees, reference)


def clip_table(clips: SegmentationClips) -> Any:
    """One row per clip: name, frames, frame rate [Hz], channels."""
    import pandas as pd

    return pd.DataFrame([{"clip": m.name, "frames": m.n_frames, "fps": m.fps,
                          "channels": m.n_channels}
                         for m in (clips.salsa, clips.toolbox, clips.synth.motion)])  # fmt: skip


def period_table(
    clips: SegmentationClips,
    *,
    alpha: float,
    period_range: Sequence[float],
    period_method: str,
) -> tuple[dict[tuple[str, str], Segmentation], Any]:
    """Segment every clip with the default channels and with the two knees: the
    segmentations by ``(clip name, "default" or "knees")``, and a table of them."""
    import pandas as pd

    segs, rows = {}, []
    for m in clips.motions:
        for label, chans in (("default", "default"), ("knees", clips.knees[m.name])):
            seg = segment(m, alpha=alpha, period_range=tuple(period_range),
                          period_method=period_method, channels=chans)  # fmt: skip
            segs[(m.name, label)] = seg
            rows.append({"clip": m.name, "channels": f"{label} ({len(seg.channels)})",
                         "periods": seg.n_periods, "mean period [s]": round(seg.mean_period, 3),
                         "normalised energy": round(seg.normalised_energy, 3),
                         "reference": clips.reference[m.name]})  # fmt: skip
    return segs, pd.DataFrame(rows)


def figure(
    clips: SegmentationClips,
    segs: dict[tuple[str, str], Segmentation],
    *,
    alpha: float,
    seconds: float,
) -> Any:
    """Figure 2: knee angles of each clip with the boundaries of the default channels.

    The synthetic panel also shows the true boundaries (dashed); each panel shows the
    first ``seconds`` [s].
    """
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(3, 1, figsize=(11, 8.5))
    for ax, m in zip(axes, clips.motions, strict=True):
        seg = segs[(m.name, "default")]
        truth = clips.synth.boundaries if m is clips.synth.motion else None
        title = (
            f"{m.name}: {seg.n_periods} periods, mean {seg.mean_period:.3f} s "
            f"(default channels, alpha {alpha:g})"
        )
        plot_segmentation(m, seg, clips.knees[m.name], truth=truth, ax=ax, title=title)
        ax.set_xlim(0, min(m.duration, seconds))
    fig.tight_layout()
    return fig


def nonperiodic_refusal(
    motion: Motion, *, alpha: float, period_range: Sequence[float], max_chars: int
) -> str:
    """The message with which :func:`segment` refuses a non-periodic clip, cut after a
    whole word to at most ``max_chars`` characters, " ..." included, if it is longer."""
    import textwrap

    try:
        segment(motion, alpha=alpha, period_range=tuple(period_range))
    except ParameterError as exc:
        return textwrap.shorten(str(exc), width=max_chars, placeholder=" ...")
    return f"{motion.name} was segmented (expected a refusal)"


def plot_segmentation(
    motion: Motion,
    seg: Segmentation,
    channels: Sequence[str],
    *,
    title: str = "",
    truth: Any = None,
    ax: Any = None,
) -> Any:
    """Plot joint angles (e.g. the knees) with the found period boundaries, and the
    ``truth`` [s] if given (dashed), in the style of paper A's Figure 2."""
    import matplotlib.pyplot as plt

    if ax is None:
        fig, ax = plt.subplots(figsize=(10, 2.8))
    else:
        fig = ax.figure
    t = motion.times
    for name in channels:
        v = motion.values[:, motion.channel_index(name)]
        if name.lower().endswith("rotation"):
            v = np.unwrap(v, period=360.0)
        ax.plot(t, v, lw=1.0, label=name)
    for i, b in enumerate(seg.boundaries):
        ax.axvline(b, color="k", lw=0.8, alpha=0.7, label="found boundaries" if i == 0 else None)
    if truth is not None:
        for i, b in enumerate(np.asarray(truth)):
            ax.axvline(b, color="r", lw=0.8, ls="--", label="ground truth" if i == 0 else None)
    ax.set_xlabel("time [s]")
    ax.set_ylabel("angle [deg]")
    ax.set_title(title or f"{motion.name}: {seg.n_periods} periods, mean {seg.mean_period:.3f} s")
    ax.legend(loc="upper right", fontsize=7, ncol=4)
    return fig


def uniform_baseline(
    values: Any,
    *,
    fps: float,
    period_range: Sequence[float] = (0.25, 1.25),
    method: str = "fft",
) -> np.ndarray:
    """Baseline: one period estimate (``method`` "fft" or "energy"), uniform boundaries
    ``0, T, 2T, ...`` [frames]."""
    fps = check_fps(fps)
    vals = check_values(values)
    lo_s, hi_s = check_period_range(period_range)
    x = standardise(vals[:, nonconstant_channels(vals)])
    lo_p, hi_p = time_to_frames((lo_s, hi_s), fps=fps, round_to_int=False)
    lo_f, hi_f = estimation_band(vals.shape[0], float(lo_p), float(hi_p))
    if hi_f < lo_f:
        raise ParameterError(f"no period of {lo_s:g}-{hi_s:g} s fits twice in the clip")
    return uniform_frames(vals.shape[0], estimate_period(x, lo_f, hi_f, method))


def minima_baseline(signal: Any, *, fps: float, period: float) -> np.ndarray:
    """Baseline: local minima of one joint angle as period boundaries [frames], at
    least 0.7 of the expected ``period`` [s] apart (on the lightly smoothed signal)."""
    from scipy.ndimage import uniform_filter1d
    from scipy.signal import find_peaks

    fps = check_fps(fps)
    y = check_finite(np.asarray(signal, dtype=np.float64).ravel(), name="signal")
    dist = max(1, int(time_to_frames(0.7 * float(period), fps=fps, mode="floor")))
    smooth = uniform_filter1d(y, size=max(1, int(time_to_frames(0.05, fps=fps))) | 1)
    peaks, _ = find_peaks(-smooth, distance=dist)
    return peaks.astype(np.int64)


def synthetic_error_table(
    *,
    snr_dbs: Sequence[float | None] = (30.0, 20.0, 10.0, 5.0),
    alphas: Sequence[float] = (0.1, 0.2),
    seeds: Sequence[int] = (0, 1, 2),
    n_frames: int = 750,
    n_channels: int = 29,
    fps: float = 25.0,
    n_periods: int = 25,
    jitter: float = 0.08,
    variation: float = 0.05,
    period_range: Sequence[float] = (0.25, 1.25),
) -> Any:
    """Boundary error [frames] vs ground truth, one row per SNR, alpha and method.

    For every SNR, alpha and seed, a :func:`beatsync.synth.motion.periodic_motion`
    signal is segmented (a) by :func:`segment` with the period count estimated, (b)
    with the count given, and by the baselines (c) FFT period + uniform boundaries and
    (d) local minima of channel 0 (offset-corrected); errors are averaged over seeds
    (``max``: the largest).
    """

    import pandas as pd

    rows = []
    for snr in snr_dbs:
        for alpha in alphas:
            per_method: dict[str, list[dict]] = {}
            for seed in seeds:
                s = periodic_motion(n_frames=n_frames, n_channels=n_channels, fps=fps,
                                    n_periods=n_periods, jitter=jitter, variation=variation,
                                    snr_db=snr, seed=seed)  # fmt: skip
                truth = s.boundary_frames
                vals = s.motion.values
                found = {}
                for name, kw in (("optimal, count estimated", {}),
                                 ("optimal, count given", {"n_periods": n_periods})):  # fmt: skip
                    try:
                        seg = segment_values(
                            vals, fps=fps, alpha=alpha, period_range=tuple(period_range), **kw
                        )
                        found[name] = (seg.boundary_frames, False)
                    except ParameterError:
                        found[name] = (np.array([], dtype=np.int64), False)
                uni = uniform_baseline(vals, fps=fps, period_range=period_range, method="fft")
                found["baseline: FFT period + uniform"] = (uni, False)
                per = float(frames_to_time((uni[-1] - uni[0]) / max(uni.size - 1, 1), fps=fps))
                found["baseline: minima of channel 0"] = (
                    minima_baseline(vals[:, 0], fps=fps, period=per),
                    True,
                )
                for name, (fr, off) in found.items():
                    per_method.setdefault(name, []).append(
                        boundary_errors(fr, truth, remove_offset=off)
                    )
            for name, errs in per_method.items():
                rows.append({
                    "snr_db": snr if snr is not None else np.inf,
                    "alpha": alpha,
                    "method": name,
                    "mean_error_frames": float(np.nanmean([e["mean"] for e in errs])),
                    "max_error_frames": float(np.nanmax([e["max"] for e in errs])),
                    "failed_runs": int(sum(e["n_matched"] == 0 for e in errs)),
                    "count_error": float(np.mean([abs(e["count_error"]) for e in errs])),
                })  # fmt: skip
    return pd.DataFrame(rows)


def error_pivot(table: Any) -> Any:
    """The error table as mean / max error [frames] per noise level and alpha (columns: methods)."""
    import pandas as pd

    return pd.concat({stat: table.pivot_table(index=["snr_db", "alpha"], columns="method",
                                              values=f"{stat}_error_frames", aggfunc="first")
                      for stat in ("mean", "max")}, axis=1)  # fmt: skip
