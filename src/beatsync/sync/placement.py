"""Beats mode for a whole dance: loop the clip where it loops best, then place every
motion beat on the song's (half) beats at once (:mod:`.fill`, :mod:`.counts`), each
interval no faster than keeps its joints within the dancer's own peak (:func:`peak_headroom`).
"""

from __future__ import annotations

from typing import Any

import numpy as np

from ..errors import ParameterError
from .counts import plan_counts
from .fill import choose_loop, joint_positions, loop_events

__all__ = ["LOOP_REACH", "check_start", "peak_headroom", "place_whole_dance"]

#: source covered by the looped timeline of a whole dance, per second of song: speeds
#: up to this are within reach of the beat counts
LOOP_REACH = 1.6


def check_start(targets: np.ndarray, phase_offset: float) -> None:
    if targets[0] < 0:
        raise ParameterError(
            f"phase_offset={phase_offset:.3f} s puts the first boundary at {targets[0]:.3f} s, "
            "before the music starts; use first_beat >= 1 or a smaller offset"
        )


def place_whole_dance(plan: dict[str, Any], phase_offset: float):
    """Beats mode: loop the clip if needed (:func:`.fill.choose_loop`) and place every
    motion beat with :func:`.counts.plan_counts`. Returns ``(looped, used, targets,
    end, placed)``."""
    motion, events, beats = plan["motion"], plan["events"], plan["beats"]
    song = beats[plan["first_beat"] :]
    if song.size < 2:
        raise ParameterError(
            f"the music is too short: {song.size} beat(s) from beat {plan['first_beat']} "
            "cannot hold one motion beat; use a longer song or an earlier first_beat"
        )
    looped = None
    timeline, index = events, np.arange(events.size)
    # music to cover: to the last beat, or on to the song's end
    span_s = float(max(song[-1], plan["song_end"] or 0.0) - song[0])
    if plan["fill"] == "loop" and events[-1] - events[0] < LOOP_REACH * span_s:
        a, b, angle, shift, dist, join = choose_loop(
            motion, events, dance=plan["dance"], positions=plan["positions"]
        )
        length = events[b] - events[a]
        extra = max(0.0, LOOP_REACH * span_s - (events[b] - events[0]))
        need = b + int(np.ceil(extra / length)) * (b - a)
        looped = loop_events(
            events, max(need, b), join=join, span=(a, b), angle=angle, shift=shift, distance=dist
        )
        if looped.repetitions == 1:
            looped = None
        else:
            timeline, index = looped.events, looped.event_index
    # a reference pose the clip opens on is not the dancer's (the output never shows it)
    headroom = peak_headroom(motion, events, plan["positions"], skip=plan["start_frame"])
    placed = plan_counts(
        timeline,
        song,
        end="last_beat" if plan["fill"] == "loop" else "last_event",
        dance=plan["dance"],
        bar=plan["bar"],
        phrase_index=index,
        max_speed=None if headroom is None else headroom[index[1:] - 1],
    )
    used = timeline[placed.event_index]
    targets = placed.targets + phase_offset
    check_start(targets, phase_offset)
    end = None
    if looped is None and placed.event_index[-1] == events.size - 1:
        end = max(plan["duration"], float(used[-1]))  # the clip's tail after its last beat
    info = {
        "beats": placed.beats,
        "n_merged": placed.n_merged,
        "n_half_beat": placed.n_half,
        "phrases_on_bars": placed.phrases_on_bars,
        "speed_band": placed.speed_band,
    }
    return looped, used, targets, end, info


def peak_headroom(
    motion: Any, events: np.ndarray, positions: np.ndarray | None = None, *, skip: int = 0
) -> np.ndarray | None:
    """Per interval of ``events``: the dancer's peak joint speed over the interval's
    peak, the fastest playback that keeps its joints within the dancer's own peak
    (None without joint positions; ``positions``: the motion's, if already computed;
    the first ``skip`` frames, a reference pose the clip opens on, are not the dancer's)."""
    got = joint_positions(motion, positions)
    if got is None:
        return None
    v = np.linalg.norm(np.diff(got[0], axis=0), axis=-1).max(axis=1)  # per frame step
    v[:skip] = 0.0
    frames = np.clip(np.rint(events * motion.fps).astype(np.int64), 0, v.size)
    peak = np.array(
        [v[a:b].max() if b > a else 0.0 for a, b in zip(frames[:-1], frames[1:], strict=True)]
    )
    return np.where(peak > 0, v.max() / np.maximum(peak, 1e-300), np.inf)
