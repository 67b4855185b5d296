"""The public entry :func:`synchronize` and its result (see :mod:`beatsync.sync`)."""

from __future__ import annotations

from dataclasses import dataclass, field, replace
from typing import Any

import numpy as np

from ..errors import NotPeriodicError, ParameterError, silenced, warn
from ..graph.timescale import DEFAULT_SCALE_BOUND
from ..motion import segmentation_view
from ..motion_beats import kinematic_beat_frames, kinematic_beats, motion_positions, speed_curve
from ..rotations import sample_motion
from ..segment.checks import check_alpha, check_period_range
from ..segment.core import (
    PERIOD_BEATS,
    PeriodicityRefused,
    _segment_motion,
    estimate_period_count,
)
from ..validation import (
    as_float,
    as_int,
    check_choice,
    check_interval,
    check_motion_fps,
    check_positive,
    check_times,
    frames_to_time,
    time_to_frames,
)
from .counts import MARGIN
from .fill import LoopedClip, choose_loop, loop_events, with_center
from .landing import dip_floor, land_seen, position_view, release_floor, source_speed
from .mapping import BeatCount, beats_per_unit, choose_count, count_or_none, lag_of
from .placement import check_start, place_whole_dance
from .positions import restore_bone_lengths
from .quality import fitting_tempo, report_entries
from .warp import TimeWarp, integrate_warp

__all__ = [
    "MODES",
    "LANDINGS",
    "FILLS",
    "SyncResult",
    "estimate_dance_meter",
    "motion_beat_count",
    "motion_periods",
    "position_bones",
    "synchronize",
]

MODES = ("periods", "beats", "auto")
LANDINGS = ("boundaries", "accents")
FILLS = ("stop", "loop")
#: period range of the periodicity test in mode="auto": paper A's (steps, not figures)
AUTO_PERIOD_RANGE = (0.25, 1.25)
#: share of periods that must hold the same number of motion beats to call it a meter
METER_AGREEMENT = 0.6
#: beats mode holds the playback speed this long [s] on both sides of every landed motion
#: beat: the motion-beat detector's smoothing width (``kinematic_beats``' ``smooth``), so
#: the speed minimum a viewer sees stays on its beat
LANDING_HOLD = 0.1


@dataclass(frozen=True)
class SyncResult:
    """Output of :func:`synchronize`: the beat-synchronous ``motion`` at ``out_fps``
    (frame ``k`` plays at music time ``k / out_fps``); ``warp_src_times`` [s], the source
    time each output frame shows (in the looped timeline when the clip was repeated);
    the ``warp`` itself (for plots); and the ``report``:

    - what was used and why: ``mode``, ``mode_requested``, ``mode_note``, ``land``,
      ``fill``, ``repetitions`` (passes of the clip the output plays),
      ``beats_per_period`` (the count used most in beats mode), ``beats_per_period_rule``,
      ``meter_fit``, ``meter_note``,
      ``dance_beats_per_period`` with ``dance_meter_rule`` (``"given"``,
      ``"estimated"`` or None) and ``dance_meter_found``,
      ``motion_beats_per_period_counted``, ``beats_per_bar``, ``period_range_s``,
      ``first_beat``, ``phase_offset_s``, ``accent_lag_s``, ``mean_motion_period_s``,
      ``beat_period_s``, ``delta_s``;
    - frames and intervals: ``input_frames``, ``output_frames``, ``input_fps``,
      ``output_fps``, ``periods_available``, ``periods_used`` (over all repetitions),
      ``covered_s``, ``lead_in_hold_frames``, ``n_scaled_periods``, ``rate_range``
      (target/source), ``tempo_ratio_range`` (playback speed);
    - landings: ``boundaries_s`` (source, looped timeline; in beats mode the source
      times the output shows at its motion beats, :mod:`.landing`) and ``target_beats_s``,
      ``residual_ms`` (realised warp) and ``residual_nearest_frame_ms``, their maxima;
    - from the output frames (:mod:`.quality`): ``beats_per_motion_beat_used``,
      ``n_merged_intervals``, ``n_half_beat_landings``, ``phrases_on_bars``,
      ``playback_speed``, ``kinematics``, ``landings_seen`` (beats mode), ``loop``,
      ``joins``, ``speed_warning``.
    """

    motion: Any
    warp_src_times: np.ndarray
    report: dict = field(default_factory=dict)
    warp: TimeWarp | None = None


def position_bones(motion: Any) -> np.ndarray | None:
    """Bones of a position-only motion (joint-index pairs), None for other motions."""
    if not getattr(motion, "is_positional", False):
        return None
    bones = np.asarray(motion.bones, dtype=np.int64).reshape(-1, 2)
    return bones if bones.size else None


def _events(
    motion: Any,
    pos: np.ndarray | None,
    boundaries: Any,
    mode: str,
    period_range: tuple[float, float],
    duration: float,
) -> tuple[np.ndarray, str, str]:
    """The motion events to land on beats: ``(events, mode used, note)``; ``pos``: the
    motion's joint positions (None for angle tables)."""
    if boundaries is not None:
        s = check_times(boundaries, name="boundaries", duration=duration)
        if mode != "beats":
            if s.size < 2:
                raise ParameterError(
                    f"got {s.size} period boundary(ies): the motion does not look periodic "
                    "(segmentation found no full period); nothing to synchronise"
                )
            return s, "periods", ""
    if mode == "beats":
        return _motion_beats(motion, pos, "mode='beats'"), "beats", ""
    try:
        seg = motion_periods(motion, period_range=period_range)
    except NotPeriodicError as exc:  # bad settings or no motion stay errors
        if mode == "periods":
            raise NotPeriodicError(
                f"the motion does not look periodic ({exc}); use mode='beats' (--mode beats) "
                "to warp the dancer's own motion beats instead"
            ) from None
        note = (
            f"the periodicity test refused the motion ({exc}); fell back to warping the "
            "dancer's own motion beats onto the music's beats (mode='beats')"
        )
        warn(note, stacklevel=3)
        return _motion_beats(motion, pos, "the fallback to motion beats"), "beats", note
    return np.asarray(seg.boundaries, dtype=np.float64), "periods", ""


def motion_periods(motion: Any, *, period_range: tuple[float, float], alpha: float = 0.1) -> Any:
    """Paper A's segmentation of a dance into its periods (:func:`beatsync.segment.segment`
    on :func:`beatsync.motion.segmentation_view`). NotPeriodicError when not shown periodic,
    too short to tell, or without joint angles while its joints move (its own motion beats
    may still sync it); ParameterError for bad settings or a dancer who does not move.
    """
    alpha = check_alpha(alpha)  # the caller's settings: never a reason to fall back
    period_range = check_period_range(period_range)
    try:
        seg = _segment_motion(segmentation_view(motion), alpha=alpha, n_periods=None,
                              period_range=period_range, method="energy")  # fmt: skip
    except PeriodicityRefused as exc:
        # the channels are segmentation_view's here (sync and batch have no --channels)
        advice = "Try another period_range (--period-range), or a clip with repeated movement"
        raise NotPeriodicError(exc.advised(advice)) from None
    except NotPeriodicError:  # too short to tell: its own message
        raise
    except ParameterError as exc:  # no angles to test, or angles that never change
        try:
            pos = motion_positions(motion)
        except ParameterError:  # no joint positions either: the segmentation's own message
            raise exc from None
        # positions are finite (motion_positions checks): still, or moving
        if not np.abs(pos - pos[:1]).max(initial=0.0) > 1e-9 * np.abs(pos).max(initial=0.0):
            raise ParameterError(
                f"the dancer does not move: every joint keeps its position over the "
                f"{motion.n_frames} frames, so there is nothing to synchronise"
            ) from None
        raise NotPeriodicError(f"its periods cannot be searched ({exc}); its joints move") from None
    if len(seg.boundaries) < 2:
        raise NotPeriodicError("segmentation found no full period")
    return seg


def _positions_or_none(motion: Any) -> np.ndarray | None:
    """The motion's joint positions, or None for a table of angles without a skeleton."""
    try:
        with silenced():
            return motion_positions(motion)
    except ParameterError:
        return None


def _opening_snap(pos: np.ndarray | None) -> int:
    """Frames a clip opens with that are not dance: each step faster than every later
    one, as a converter's reference pose snaps to the first pose (CMU's BVH files open on a
    T-pose); the output's lead-in never shows them."""
    if pos is None or pos.shape[0] < 3:
        return 0
    step = np.linalg.norm(np.diff(pos, axis=0), axis=-1).max(axis=1)
    later = np.maximum.accumulate(step[::-1])[::-1]  # the fastest step from each on
    k = 0
    while k < step.size - 1 and step[k] > later[k + 1]:
        k += 1
    return k


def _motion_beats(motion: Any, pos: np.ndarray | None, what: str) -> np.ndarray:
    try:  # without positions, kinematic_beats says why
        mb = (
            kinematic_beats(motion)
            if pos is None
            else frames_to_time(kinematic_beat_frames(pos, fps=motion.fps), fps=motion.fps)
        )
    except ParameterError as exc:
        raise ParameterError(
            f"{what} needs joint positions (a skeleton or markers): {exc}"
        ) from None
    if mb.size < 2:
        raise ParameterError(
            f"{what} found {mb.size} motion beat(s) in the dance ({motion.n_frames} frames, "
            f"{motion.duration:.2f} s at fps={motion.fps:g}); at least 2 are needed: is the "
            "dancer standing still, or is the frame rate wrong?"
        )
    return mb


def motion_beat_count(motion: Any, events: np.ndarray) -> int | None:
    """Motion beats per period, counted from the kinematic beats (informative only).

    The count that holds in at least :data:`METER_AGREEMENT` of the periods, else None.
    Speed minima miss steps of a real dance (a real waltz bar shows 2 of its 3), so it is
    never used to choose the beats per period: give the dance's meter instead.
    """
    try:
        with silenced():  # no beats: no count, no news
            mb = kinematic_beats(motion)
    except ParameterError:  # no positions
        return None
    counts = np.histogram(mb, bins=events)[0]
    values, freq = np.unique(counts, return_counts=True)
    k = int(values[np.argmax(freq)])
    return k if k >= 1 and freq.max() >= METER_AGREEMENT * counts.size else None


#: phrase lengths searched for the dance's own meter, in motion beats (median interval)
PHRASE_BEATS = (1.5, 8.5)


def estimate_dance_meter(motion: Any, mb: np.ndarray) -> tuple[int | None, dict | None]:
    """The dance's own phrase in motion beats ``mb`` [s], for ``dance_beats_per_period``
    when the user gives none: ``(count or None, what was found)``.

    Paper A's period ``T`` (the spectral peak of
    :func:`beatsync.segment.core.estimate_period_count`) over ``PHRASE_BEATS`` median
    motion-beat intervals ``b``; ``N = round(T / b)``, used only when every ``N``
    consecutive motion beats span ``T`` to within ``b / 2`` (why: ``docs/tuning.md``).
    """
    iv = np.diff(mb)
    step = float(np.median(iv))
    try:
        view = segmentation_view(motion)
        reach = (PHRASE_BEATS[0] * step, PHRASE_BEATS[1] * step)
        # a phrase lasts seconds: about 15 frames a second resolve it (a long dance at a
        # high frame rate would otherwise cost most of the sync in this one FFT)
        q = max(1, int(view.fps // 15))
        n = estimate_period_count(
            view.values[::q], fps=view.fps / q, period_range=reach, method="fft"
        )
    except ParameterError:  # too short for the range, or nothing to search
        return None, None
    period = float(motion.duration) / n  # >= the spectral peak's: a whole number fits
    found = {"period_s": period, "motion_beats": period / step}
    k = int(np.rint(period / step))
    if period > reach[1] or k < 2 or iv.size < 3 * k:  # no period in range, or too few
        return None, found
    spans = mb[k:] - mb[:-k]
    return (k if np.all(np.abs(spans - period) <= 0.5 * step) else None), found


def synchronize(
    motion: Any,
    boundaries: Any,
    beats: Any,
    *,
    mode: str = "periods",
    land: str = "boundaries",
    fill: str = "stop",
    beats_per_period: int | None = None,
    beats_per_bar: int | None = None,
    dance_beats_per_period: int | None = None,
    first_beat: int = 0,
    out_fps: float | None = None,
    delta: float | None = None,
    phase_offset: float = 0.0,
    period_range: tuple[float, float] | None = None,
    song_end: float | None = None,
) -> SyncResult:
    """Resample a dance so that its periods (or its own motion beats) land on music beats
    (paper A, section 5; see :mod:`beatsync.sync`). The output's time 0 is the music's.

    ``motion`` (BVH joint angles, markers or joint positions) lands on the music's
    ``beats`` [s] (at least 2); ``boundaries`` [s] are its period boundaries in the
    source's time (None: segmented here over ``period_range`` [s], by default
    ``PERIOD_BEATS`` of the music's beats in ``"periods"``, ``AUTO_PERIOD_RANGE`` in
    ``"auto"``).

    - ``mode``: ``"periods"``, paper A's periods on groups of beats; ``"beats"``, the
      dancer's own kinematic beats, counts chosen for the whole dance; ``"auto"``,
      periods when the motion is periodic, else beats with a warning and
      ``report["mode_note"]``.
    - ``land="accents"``: synchronise, measure the mean lag of the kinematic beats behind
      the beats, synchronise again without it.
    - ``fill``: end with the clip's last period that fits (``"stop"``, paper A), or
      repeat a span with blended joins up to the song's last beat (``"loop"``) and on
      to ``song_end`` [s] (the song's end, if given) at the final speed, so the dancer
      does not stand still while the song plays out.
    - ``beats_per_period`` (beats one period or motion beat spans) overrides
      :func:`beats_per_period`'s rule or the whole-dance counts; ``beats_per_bar`` and
      ``dance_beats_per_period`` (3 for a waltz step) are the meters; in beats mode
      without the dance's, its own phrase when clear (:func:`estimate_dance_meter`).
    - ``first_beat``: index of the beat the first boundary lands on; ``phase_offset``
      [s]: land the boundaries this long after their beats (negative: before).
    - ``out_fps`` [Hz], default ``motion.fps``; ``delta`` [s], eq. 9's Gaussian width,
      default the mean motion period (or beat interval).

    Raises
    ------
    ParameterError
        Boundaries outside the motion (frames instead of seconds?), fewer than two
        boundaries or music beats, no motion beats in ``"beats"``, music too short for
        one period after ``first_beat``, an unknown mode/land/fill, ``land="accents"``
        with a ``phase_offset``, a bad ``period_range``, meter or ``out_fps``.
    NotPeriodicError
        ``mode="periods"`` without ``boundaries`` on a motion segmentation does not
        show periodic (:func:`motion_periods`); ``"beats"`` or ``"auto"`` can sync it.
    """
    mode = check_choice(mode, MODES, name="mode")
    land = check_choice(land, LANDINGS, name="land")
    fill = check_choice(fill, FILLS, name="fill")
    fps = check_motion_fps(motion.fps, name="motion.fps")
    out_fps = fps if out_fps is None else check_motion_fps(out_fps, name="out_fps")
    n_frames = int(motion.n_frames)
    if n_frames < 2:
        raise ParameterError(f"motion has {n_frames} frame(s); at least 2 are needed to resample")
    beats = check_times(beats, name="beats")
    if beats.size < 2:
        raise ParameterError(
            f"the music has {beats.size} detectable beat(s); at least 2 are needed "
            "(is it silent or without rhythm? give the tempo with bpm / --bpm)"
        )
    first_beat = as_int(first_beat, name="first_beat", minimum=0)
    if first_beat >= beats.size:
        raise ParameterError(
            f"first_beat={first_beat} but the music has only {beats.size} beats (indices from 0)"
        )
    override = count_or_none(beats_per_period, "beats_per_period")
    bar = count_or_none(beats_per_bar, "beats_per_bar")
    dance = count_or_none(dance_beats_per_period, "dance_beats_per_period")
    phase_offset = as_float(phase_offset, name="phase_offset", unit="s")
    if land == "accents" and phase_offset != 0.0:
        raise ParameterError(
            "land='accents' measures the phase offset itself; do not also give phase_offset"
        )
    if delta is not None:
        delta = check_positive(delta, name="delta", unit="s")
    beat_period = float(np.median(np.diff(beats)))
    if abs(phase_offset) >= beat_period:
        raise ParameterError(
            f"phase_offset={phase_offset:g} s is at least one beat of the music "
            f"({beat_period:.3f} s): an offset is a fraction of a beat (milliseconds given as "
            "seconds?); move boundaries by whole beats with first_beat (--first-beat)"
        )
    if period_range is None and mode == "auto":
        period_range = AUTO_PERIOD_RANGE
    elif period_range is None:
        period_range = (PERIOD_BEATS[0] * beat_period, PERIOD_BEATS[1] * beat_period)
    else:
        period_range = check_interval(period_range, name="period_range", unit="s")
    if song_end is not None:
        song_end = as_float(song_end, name="song_end", unit="s")
        if song_end < beats[-1]:
            raise ParameterError(
                f"song_end={song_end:g} s is before the music's last beat ({beats[-1]:.2f} s): "
                "it is the song's duration in seconds"
            )
        if song_end > 10.0 * beats[-1] + 60.0:  # a real outro is not that long
            raise ParameterError(
                f"song_end={song_end:g} s is over ten times the music's last beat "
                f"({beats[-1]:.2f} s): it is the song's duration in seconds (milliseconds given?)"
            )
    duration = float(frames_to_time(n_frames - 1, fps=fps))  # sample_motion clips here

    # the joint positions (None for angle tables): once for every step that uses them
    positions = _positions_or_none(motion)
    events, used_mode, note = _events(
        motion, positions, boundaries, mode, period_range, float(motion.duration)
    )
    intervals = np.diff(events)
    unit = float(np.median(intervals)) if used_mode == "beats" else float(intervals.mean())
    counted = motion_beat_count(motion, events) if used_mode == "periods" else None
    whole_dance = used_mode == "beats" and override is None
    meter_rule, meter_found = ("given" if dance else None), None
    if whole_dance and dance is None:
        dance, meter_found = estimate_dance_meter(motion, events)
        meter_rule = "estimated" if dance else None
    ideal = unit / beat_period
    if override is not None:
        count = BeatCount(override, "override", ideal)
    elif whole_dance:
        count = BeatCount(max(1, int(np.rint(ideal))), "whole dance (dynamic programming)", ideal)
    else:
        count = choose_count(ideal, dance=dance, bar=bar)
    if count.meter_fit is False:
        warn(count.note, stacklevel=2)
    counts = (
        beats_per_unit(intervals, count.m)
        if used_mode == "beats"
        else np.full(intervals.size, count.m, dtype=np.int64)
    )
    plan = {
        "motion": motion,
        "events": events,
        "counts": None if whole_dance else counts,
        "beats_mode": used_mode == "beats",
        "land": land,
        "dance": dance if used_mode == "beats" else None,
        "bar": bar,
        "beats": beats,
        "fill": fill,
        "first_beat": first_beat,
        "fps": fps,
        "out_fps": out_fps,
        "delta": delta,
        "duration": duration,
        "song_end": song_end if fill == "loop" else None,
        "beat_period": beat_period,
        "positions": positions,
    }
    # the output starts after a converter's reference pose, if the clip opens on one
    plan["start_frame"] = _opening_snap(plan["positions"])
    plan["start"] = plan["start_frame"] / fps
    if whole_dance:  # once for both passes of land="accents"
        plan["speed_curve"] = speed_curve(positions, fps=fps)
    lag = 0.0
    res = _resample(plan, phase_offset)
    if land == "accents":
        try:
            mb = kinematic_beats(res.motion)
        except ParameterError as exc:
            raise ParameterError(
                f"land='accents' needs joint positions (a skeleton or markers): {exc}"
            ) from None
        lag = lag_of(mb, beats)
        if beats[first_beat] - lag < 0:
            plan["first_beat"] = first_beat = first_beat + 1
        res = _resample(plan, -lag)
    ratio = ideal / count.m
    if not whole_dance and (ratio > 2.0 or ratio < 0.5):
        warn(
            f"motion {'beats' if used_mode == 'beats' else 'periods'} ({unit:.3f} s) become "
            f"{count.m} beat(s) of {beat_period:.3f} s: the dance is played {ratio:.2f}x its "
            "speed; check the beats or set beats_per_period",
            stacklevel=2,
        )
    res.report.update(
        {
            "mode": used_mode,
            "mode_requested": mode,
            "mode_note": note,
            "land": land,
            "accent_lag_s": lag,
            "beats_per_period": int(count.m),
            "beats_per_period_rule": count.rule,
            "meter_fit": count.meter_fit,
            "meter_note": count.note,
            "dance_beats_per_period": dance,
            "dance_meter_rule": meter_rule,
            "dance_meter_found": meter_found,
            "motion_beats_per_period_counted": counted,
            "beats_per_bar": bar,
            "period_range_s": None if boundaries is not None else list(period_range),
            "mean_motion_period_s": unit,
            "beat_period_s": beat_period,
        }
    )
    if whole_dance:  # the count used most
        used_counts = res.report["beats_per_motion_beat_used"]
        res.report["beats_per_period"] = float(max(used_counts, key=used_counts.get))
    _speed_warning(res.report, beat_period)
    return res


#: share of output time within the speed band below which a warning is given
BAND_SHARE = 0.95


def _speed_warning(report: dict[str, Any], beat_period: float) -> None:
    """Warn when the song cannot be followed within the speed band, naming a tempo
    that would fit."""
    sp = report["playback_speed"]
    share = (sp["instantaneous"] or sp["per_interval"])["in_band"]
    report["speed_warning"] = ""
    if share < BAND_SHARE:
        lo, hi = sp["band"]
        note = (
            f"the dance plays within x{lo:g}-x{hi:g} of its speed for only {share:.0%} of "
            f"the output (song at {60.0 / beat_period:.0f} BPM); a song at about "
            f"{fitting_tempo(sp['per_interval']['median'], 60.0 / beat_period)} would fit "
            "with the same beat counts"
        )
        report["speed_warning"] = note
        warn(note, stacklevel=3)


def _go_on(warp: TimeWarp, stop: float, last: float) -> TimeWarp:
    """``warp`` (ending on its last boundary) going on at its end rate up to music time
    ``stop`` [s], or as far as the source reaches (``last`` [s]): one more knot."""
    rate = warp.rate[-1]
    end = float(min(warp.src[-1] + (stop - warp.tgt[-1]) / rate, last))
    if end <= warp.src[-1]:
        return warp
    return replace(
        warp,
        src=np.append(warp.src, end),
        tgt=np.append(warp.tgt, warp.tgt[-1] + (end - warp.src[-1]) * rate),
        rate=np.append(warp.rate, rate),
    )


def _resample(plan: dict[str, Any], phase_offset: float) -> SyncResult:
    """Warp and resample (inputs checked by :func:`synchronize`)."""
    motion, events, counts, beats = plan["motion"], plan["events"], plan["counts"], plan["beats"]
    first_beat, fps, out_fps = plan["first_beat"], plan["fps"], plan["out_fps"]
    duration = plan["duration"]
    n_avail = events.size - 1
    last_beat = beats.size - 1
    looped: LoopedClip | None = None
    if counts is None:  # beats mode: the whole dance's counts at once
        looped, used, targets, end, placed = place_whole_dance(plan, phase_offset)
        p = used.size - 1
        last = float(looped.events[-1]) if looped is not None else duration
        speed_at = source_speed(plan["speed_curve"], fps, looped)
        pos_at = position_view(plan["positions"], 2 if motion.is_positional else 1, fps, looped)

        # the fastest each interval may play anywhere: the band's top, or its peak headroom
        # (the counts' band without the margin they aimed inside)
        top = np.minimum(DEFAULT_SCALE_BOUND[1], placed["speed_band"][1] * MARGIN)

        def warp_of(pins: np.ndarray, part: tuple[int, int] | None = None) -> TimeWarp:
            """The warp of ``pins``, or of the landings ``part`` (a, b) of them only
            (eq. 9's width kept: the warp there is the whole warp's, away from its ends)."""
            a, b = (0, pins.size) if part is None else part
            tg = targets[a:b]
            args = {
                "start": plan["start"] if a == 0 else None,
                "end": end if b == pins.size else None,
                "delta": plan["delta"] or float(pins[-1] - pins[0]) / (pins.size - 1),
                "hold": LANDING_HOLD,
            }
            pins = pins[a:b]
            floor = dip_floor(speed_at, pins, tg)
            warp = integrate_warp(pins, tg, floor=floor, **args)
            lower = release_floor(warp, pins, tg, floor, top[a : b - 1])
            if lower is not None:
                warp = integrate_warp(pins, tg, floor=lower, **args)
            if args["end"] is None and b == targets.size and plan["song_end"] is not None:
                warp = _go_on(warp, plan["song_end"], last)  # the song's end: no offset
            return warp

        def view(pins: np.ndarray, span=None, part=None):
            """Joint positions, output and source times of the output frames (within
            ``span`` [s], if given) and the warp (of the landings ``part``)."""
            warp = warp_of(pins, part)
            out_t = _output_times(warp, out_fps)
            if span is not None:
                out_t = out_t[(out_t >= span[0]) & (out_t <= span[1])]
            src_t = warp.to_source(out_t)
            return pos_at(src_t), out_t, src_t, warp

        used, warp = land_seen(view, out_fps, used, targets, placed["speed_band"])
        out_motion, out_times, src_times = _output(plan, warp, looped)
    else:
        cum = np.concatenate([[0], np.cumsum(counts)])
        # beats to cover: up to the last one, and the song's end in beats after it
        reach = last_beat - first_beat
        if plan["song_end"] is not None:
            reach += int(np.ceil((plan["song_end"] - beats[-1]) / plan["beat_period"]))
        if plan["fill"] == "loop" and cum[-1] < reach:
            # enough repetitions that whole intervals reach it, plus one for the tail
            a, b, angle, shift, dist, join = choose_loop(
                motion, events, positions=plan["positions"]
            )
            per_rep = max(int(cum[b] - cum[a]), 1)
            need = b + 1 + -(-max(0, reach - int(cum[b])) // per_rep) * (b - a)
            looped = loop_events(
                events, need, join=join, span=(a, b), angle=angle, shift=shift, distance=dist
            )
            counts = counts[looped.event_index[1:] - 1]
            events = looped.events
            cum = np.concatenate([[0], np.cumsum(counts)])
        n_fit = int(np.searchsorted(cum, last_beat - first_beat, side="right")) - 1
        if n_fit < 1:
            raise ParameterError(
                f"the music is too short: {beats.size - first_beat} beat(s) from beat "
                f"{first_beat} (last at {beats[-1]:.2f} s) cannot hold one motion period of "
                f"{int(counts[0])} beat(s) ({float(events[1] - events[0]):.2f} s of motion); use "
                "a longer song, an earlier first_beat or fewer beats_per_period"
            )
        p = min(events.size - 1, n_fit)
        targets = beats[first_beat + cum[: p + 1]] + phase_offset
        check_start(targets, phase_offset)
        used = events[: p + 1]
        tail = p == events.size - 1 and duration > used[-1]  # the clip's tail after it
        end = duration if tail else None
        warp = integrate_warp(used, targets, start=plan["start"], end=end, delta=plan["delta"])
        if plan["fill"] == "loop" and p < events.size - 1:
            # cover the beats after the last whole interval (and the song's end) with part
            # of the next one, at the warp's end rate
            stop = beats[last_beat] + phase_offset if plan["song_end"] is None else plan["song_end"]
            warp = _go_on(warp, stop, float(events[-1]))
        placed = {"beats": counts[:p].astype(np.float64), "n_merged": 0, "n_half_beat": 0}
        out_motion, out_times, src_times = _output(plan, warp, looped)
    n_out = out_times.size
    tau_end = float(warp.tgt[-1])

    # residuals on the realised warp: output frames joined by straight lines, plus the
    # warp's ends (a boundary may sit exactly where a held lead-in or the clipped tail
    # starts); and at the nearest frame
    live = (out_times > warp.tgt[0]) & (out_times < warp.tgt[-1])
    xs = np.concatenate([warp.src[:1], src_times[live], warp.src[-1:]])
    ys = np.concatenate([warp.tgt[:1], out_times[live], warp.tgt[-1:]])
    realised = np.interp(used, xs, ys)
    residual = (realised - targets) * 1e3
    if np.abs(residual).max() > 1e3 / out_fps:  # the warp lands boundaries to rounding
        raise RuntimeError(
            f"internal error: a boundary lands {np.abs(residual).max():.3f} ms from its beat, "
            "more than one output frame; please report this with the inputs"
        )
    nearest = np.clip(time_to_frames(realised, fps=out_fps), 0, n_out - 1)
    nearest_res = (frames_to_time(nearest, fps=out_fps) - targets) * 1e3
    frame_ms = 1e3 / out_fps
    lead_in = int(np.count_nonzero(out_times < warp.tgt[0]))
    report: dict[str, Any] = {
        "input_frames": int(motion.n_frames),
        "output_frames": n_out,
        "input_fps": fps,
        "output_fps": out_fps,
        "input_duration_s": duration,
        "output_duration_s": float(frames_to_time(n_out - 1, fps=out_fps)),
        "fill": plan["fill"],
        # passes the output plays: the clip, and one more after each join the warp reaches
        "repetitions": 1
        + (0 if looped is None else int(np.sum(looped.join_times <= warp.src[-1]))),
        "periods_available": int(n_avail),
        "periods_used": int(p),
        "first_beat": first_beat,
        "phase_offset_s": phase_offset,
        "delta_s": float(warp.delta),
        "rate_range": [float(warp.period_rates.min()), float(warp.period_rates.max())],
        "continuous_rate_range": [float(warp.rate.min()), float(warp.rate.max())],
        "tempo_ratio_range": [
            float(1.0 / warp.period_rates.max()),
            float(1.0 / warp.period_rates.min()),
        ],
        "target_beats_s": targets,
        "boundaries_s": used,
        "residual_ms": residual,
        "residual_nearest_frame_ms": nearest_res,
        "max_abs_residual_ms": float(np.abs(residual).max()),
        "max_abs_residual_frames": float(np.abs(nearest_res).max() / frame_ms),
        "output_frame_ms": frame_ms,
        "lead_in_hold_frames": lead_in,
        "n_scaled_periods": int(warp.n_scaled),
        "covered_s": [
            float(targets[0]),
            float(min(tau_end, frames_to_time(n_out - 1, fps=out_fps))),
        ],
        "first_boundary_frame": int(time_to_frames(targets[0], fps=out_fps)),  # for trimming
    }
    # where the landed motion beats should show: their targets, or with the accents
    # aligned (landed early by the lag), the beats
    aims = targets - phase_offset if plan["land"] == "accents" else targets
    # the input's figures leave out a reference pose it opens on, as the output does
    pos_in = plan["positions"]
    if pos_in is not None:
        pos_in = pos_in[plan["start_frame"] :]
    args = (motion, out_motion, src_times, warp, used, targets, looped, placed, pos_in)
    report.update(report_entries(*args, aims=aims if plan["beats_mode"] else None))
    if report["repetitions"] > 1 and motion.skeleton is None and not motion.is_positional:
        warn(
            f"a table without a skeleton is looped as it is: {report['repetitions'] - 1} "
            "join(s), at which a root position among its channels jumps back (give a BVH "
            "or joint positions to carry the dance on)",
            stacklevel=3,
        )
    return SyncResult(motion=out_motion, warp_src_times=src_times, report=report, warp=warp)


def _output_times(warp: TimeWarp, out_fps: float) -> np.ndarray:
    """Output frame times [s] up to the first frame at or after the warp's last time
    (> 0: targets increase from check_start's >= 0), so the frame nearest to the last
    boundary exists (the source is clipped there)."""
    n_out = int(np.ceil(float(warp.tgt[-1]) * out_fps - 1e-6)) + 1
    return frames_to_time(np.arange(n_out), fps=out_fps)


def _output(plan: dict[str, Any], warp: TimeWarp, looped: LoopedClip | None):
    """The output of ``warp``: ``(motion, output times [s], source times [s])``."""
    motion, fps, out_fps = plan["motion"], plan["fps"], plan["out_fps"]
    out_times = _output_times(warp, out_fps)
    n_out = out_times.size
    src_times = warp.to_source(out_times)
    values = (
        sample_motion(motion, src_times) if looped is None else looped.sample(motion, src_times)
    )
    bones = position_bones(motion)
    if bones is not None:  # position-only: linear resampling, then bone lengths restored
        a, b, w = (src_times, None, None) if looped is None else looped.locate(src_times)[:3]
        pos = restore_bone_lengths(
            values.reshape(n_out, -1, 3), motion.positions(), bones, fps, a, b, w
        )
        values = pos.reshape(n_out, -1)
    out_motion = with_center(motion.with_values(values, fps=out_fps), motion, src_times, looped)
    return out_motion, out_times, src_times
