"""The public beat tracker: :func:`track_beats` and its result :class:`BeatTrack`.

Validation happens here, once; the stage modules (:mod:`.onset`, :mod:`.tempo`,
:mod:`.phase`, :mod:`.metrical`) trust their inputs. The no-clear-pulse warning compares
the salience along the decoded tempo path with that of the same onsets in random order
(:func:`pulse_clarity_null`), so one ratio serves 2 s clips and whole songs
(docs/tuning.md#pulse-clarity).
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from typing import Any, NamedTuple

import numpy as np

from ..errors import ParameterError, warn
from ..validation import check_audio as _units_check_audio
from ..validation import (
    check_bpm,
    check_choice,
    check_positive,
    check_range,
    check_times,
    frames_to_time,
)
from .drums import DRUM_WEIGHT, alternation_cue, drum_envelopes
from .filters import gaussian_smooth
from .metrical import (
    METER_MODEL,
    MeterModel,
    beat_observation,
    estimate_meter,
    tactus_observation,
)
from .onset import SILENCE_PEAK, OnsetSignal, compute_onsets, frontend_settings
from .phase import place_beats
from .tempo import analysis_windows, period_grid, tempo_hmm

__all__ = [
    "check_audio",
    "Observation",
    "observe",
    "SILENCE_PEAK",
    "DEFAULT_MIN_BPM",
    "DEFAULT_MAX_BPM",
    "BeatTrack",
    "track_beats",
    "beat_tempo",
    "mix_clicks",
    "check_duration",
    "MIN_DURATION_S",
    "MIN_PULSE_CLARITY",
    "MIN_PATH_SALIENCE",
    "CLEAR_PULSE",
    "pulse_clarity_null",
]

#: Tempo range [bpm] that :func:`track_beats` searches unless told otherwise.
DEFAULT_MIN_BPM = 40.0
DEFAULT_MAX_BPM = 240.0
#: Audio shorter than this is refused [s]: two beat periods at 80 BPM (a shorter clip
#: would get a tempo made up by the prior). The madmom sample (2.8 s) passes.
MIN_DURATION_S = 1.5
#: Below this ratio of the pulse clarity (mean salience along the tempo path) to the
#: null's, or below :data:`MIN_PATH_SALIENCE`, the pulse is unclear and a warning says so.
MIN_PULSE_CLARITY = 2.9
#: Path salience below which the pulse is unclear whatever the null says.
MIN_PATH_SALIENCE = 0.08
#: Path salience above which the pulse is clear without the null.
CLEAR_PULSE = 0.7
#: How the no-clear-pulse warning ends: what a user who knows the tempo can do.
KNOWN_TEMPO_HINT = "if you know the tempo, give it with bpm= (--bpm) and only the phase is tracked"
#: Seconds of shuffled onsets the null is averaged over, and the most draws.
NULL_AUDIO_S = 15.0
NULL_MAX_DRAWS = 8
#: Tempo HMM: standard deviation of the log period ratio per window, jump probability.
TRANS_SIGMA = 0.02
P_JUMP = 1e-4


@dataclass(frozen=True)
class BeatTrack:
    """Result of :func:`track_beats`: ``tempo`` [bpm] is the median of ``tempo_curve`` [bpm]
    (NaN without beats), one per window centred at ``tempo_times`` [s]; ``beats_per_bar``
    is 0 if not estimated (``method="librosa"`` or no beats)."""

    beats: np.ndarray
    tempo: float
    tempo_times: np.ndarray
    tempo_curve: np.ndarray
    method: str
    beats_per_bar: int = 0


def check_audio(y: Any, sr: Any, *, allow_silent: bool = False) -> tuple[np.ndarray, float]:
    """Validate mono audio for the tracker; return ``(y float64, sr float)``.

    Silence is judged against :data:`SILENCE_PEAK` (not with ``allow_silent=True``).
    """
    arr, sr_f = _units_check_audio(y, sr, silence_peak=None if allow_silent else SILENCE_PEAK)
    return np.asarray(arr, dtype=np.float64), sr_f


def mix_clicks(y: np.ndarray, sr: float, beats: np.ndarray) -> np.ndarray:
    """The audio (peak 0.8) with a 1 kHz click (0.5, 0.1 s) on every beat, float32."""
    y = np.asarray(y, dtype=np.float64)
    t = np.arange(int(0.1 * sr)) / sr
    click = np.sin(2 * np.pi * 1000.0 * t) * np.exp(-t / 0.02)
    mix = 0.8 * y / max(float(np.max(np.abs(y))), 1e-9)
    for i in np.rint(np.asarray(beats) * sr).astype(np.int64):
        if 0 <= i < y.size:
            seg = click[: y.size - i]
            mix[i : i + seg.size] += 0.5 * seg
    return (mix / max(float(np.max(np.abs(mix))), 1.0)).astype(np.float32)


def check_duration(n_samples: int, sr: float, *, bpm: float | None = None) -> float:
    """Refuse audio shorter than :data:`MIN_DURATION_S` or two beat periods of a known
    ``bpm``; return its duration [s]."""
    duration = float(frames_to_time(n_samples, fps=sr))
    need, why = MIN_DURATION_S, "the fixed minimum: two beat periods at 80 BPM"
    if bpm is not None and 2 * 60.0 / bpm > need:
        need, why = 2 * 60.0 / bpm, f"two beat periods at the given bpm={bpm:g}"
    if duration < need:
        raise ParameterError(
            f"the audio is only {duration:.3f} s long ({n_samples} samples at sr={sr:g} Hz): "
            f"beat tracking needs at least {need:.3g} s ({why}); give a longer excerpt "
            "(or check the sample rate)"
        )
    return duration


def beat_tempo(beats: Any) -> tuple[np.ndarray, np.ndarray]:
    """Start [s] and tempo ``60 / (b[i+1] - b[i])`` [bpm] of each beat interval.

    Examples
    --------
    >>> beat_tempo([0.0, 0.5, 1.0, 1.75])[1]
    array([120., 120.,  80.])
    """
    beats = check_times(beats, name="beats")
    return beats[:-1].copy(), 60.0 / np.diff(beats)


def track_beats(
    y: np.ndarray,
    sr: float,
    *,
    method: str = "psf",
    bpm: float | None = None,
    min_bpm: float = DEFAULT_MIN_BPM,
    max_bpm: float = DEFAULT_MAX_BPM,
    prior_period_s: float = METER_MODEL.tactus_median_s,
    prior_sigma: float = METER_MODEL.tactus_sigma,
    tempo_win_s: float = 8.0,
    tempo_hop_s: float = 1.0,
    time_varying: bool = True,
    drum_weight: float = DRUM_WEIGHT,
    **frontend_params: Any,
) -> BeatTrack:
    """Track the beats of mono audio ``y`` at ``sr`` [Hz].

    ``method="psf"``: phase-slope onsets, the metrical model of Klapuri et al. (2006)
    decoded by the tempo HMM, and the phase HMM (paper A, section 4); ``"librosa"``:
    :func:`librosa.beat.beat_track`. A known ``bpm`` [bpm] skips tempo estimation;
    otherwise tempi from ``min_bpm`` to ``max_bpm`` (within 20-400) are searched.
    ``prior_period_s`` [s] and ``prior_sigma`` [natural-log units] are the median and
    width of the log-normal prior on the beat period (0.55 s = 109 BPM, Klapuri et al.).
    ``tempo_win_s``, ``tempo_hop_s`` [s]: the tempo HMM's windows; ``time_varying=False``
    forces one tempo for the whole piece. ``drum_weight``: weight of the drum-pattern cue
    of the metrical level (:mod:`beatsync.beats.drums`; 0 leaves it out).
    ``frontend_params``: the front end's settings (:data:`.onset.FRONTEND_DEFAULTS`).

    Refuses empty, silent, non-finite or too short audio (:func:`check_duration`) and bad
    settings; warns when no onsets are found or the pulse is unclear (e.g. noise).

    Examples
    --------
    >>> from beatsync.synth.audio import beat_times, click_track
    >>> ref = beat_times(120, duration=10.0, start=0.3)
    >>> y = click_track(ref, sr=22050, duration=10.0)
    >>> bt = track_beats(y, 22050)
    >>> round(bt.tempo)
    120
    """
    # float32 stays float32 (the front end runs in float32); any other type becomes float64
    y, sr = _units_check_audio(y, sr, silence_peak=SILENCE_PEAK)
    if y.dtype != np.float32:
        y = np.asarray(y, dtype=np.float64)
    min_bpm, max_bpm = check_range(min_bpm, max_bpm, name="(min_bpm, max_bpm)", unit="bpm")
    check_bpm(min_bpm, name="min_bpm")
    check_bpm(max_bpm, name="max_bpm")
    if bpm is not None:
        bpm = check_bpm(bpm)
        if (min_bpm, max_bpm) != (DEFAULT_MIN_BPM, DEFAULT_MAX_BPM):
            raise ParameterError(
                f"bpm={bpm:g} fixes the tempo, and (min_bpm, max_bpm)=({min_bpm:g}, "
                f"{max_bpm:g}) bounds a tempo search that bpm skips: give one or the other"
            )
    check_duration(y.size, sr, bpm=bpm)
    if method == "librosa":
        if frontend_params:
            raise ParameterError(
                f"front-end parameters {sorted(frontend_params)} only apply to method='psf'"
            )
        return _track_librosa(y, sr, bpm=bpm, min_bpm=min_bpm, max_bpm=max_bpm)
    check_choice(method, ("psf", "librosa"), name="method")
    prior_period_s = check_positive(prior_period_s, name="prior_period_s", unit="s")
    prior_sigma = check_positive(prior_sigma, name="prior_sigma", unit="log-period")
    tempo_win_s = check_positive(tempo_win_s, name="tempo_win_s", unit="s")
    tempo_hop_s = check_positive(tempo_hop_s, name="tempo_hop_s", unit="s")
    drum_weight = check_positive(drum_weight, name="drum_weight", unit="weight", allow_zero=True)
    fe = frontend_settings(frontend_params, sr)
    if y.size / sr * fe.analysis_sr < 4 * fe.win_length:
        raise ParameterError(
            f"the audio is only {y.size / sr:.3f} s long ({y.size} samples at sr={sr:g}): "
            f"shorter than 4 analysis windows of {fe.win_length} samples at "
            f"{fe.analysis_sr:g} Hz"
        )
    ons = compute_onsets(y, sr, fe)
    if ons.onset_times.size == 0 or not np.any(ons.envelope > 0):
        warn("no onsets found in the audio (no attack in any band): no beats", stacklevel=2)
        e = np.empty(0)
        return BeatTrack(e, float("nan"), e, e, "psf")
    duration = y.size / sr
    model = replace(METER_MODEL, tactus_median_s=prior_period_s, tactus_sigma=prior_sigma)
    obs = observe(
        ons, (y, sr), model=model, bpm=bpm, min_bpm=min_bpm, max_bpm=max_bpm,
        tempo_win_s=tempo_win_s, tempo_hop_s=tempo_hop_s, drum_weight=drum_weight,
    )  # fmt: skip
    centres, periods = obs.centres, obs.periods
    if bpm is None:
        log_obs = obs.log_obs
        if not time_varying:
            log_obs = np.repeat(log_obs.sum(axis=1, keepdims=True), centres.size, axis=1)
        path = tempo_hmm(log_obs, periods, trans_sigma=TRANS_SIGMA, p_jump=P_JUMP)
        clarity = float(np.mean(obs.salience[path, np.arange(path.size)]))
        _warn_if_no_clear_pulse(ons, clarity, obs, model, duration, tempo_win_s)
    else:
        path = np.zeros(centres.size, dtype=np.int64)
    period_w = periods[path]
    beats_per_bar = estimate_meter(obs.measure[path, np.arange(path.size)], period_w)
    beats, _ = place_beats(ons, period_w, centres, tempo_win_s, duration)
    tempo_curve = 60.0 / period_w
    if bpm is None and beats.size > 3:
        # refine the grid tempo (0.5 % steps) with the median beat interval per window
        ibi = np.diff(beats)
        mid = (beats[1:] + beats[:-1]) / 2
        reach = tempo_win_s / 2 if time_varying else np.inf  # one tempo: whole piece
        for i, c in enumerate(centres):
            sel = ibi[np.abs(mid - c) <= reach]
            if sel.size >= 3:
                est = 60.0 / np.median(sel)
                if abs(np.log(est / tempo_curve[i])) < 0.05:  # same metrical level
                    tempo_curve[i] = est
    return BeatTrack(
        beats, float(np.median(tempo_curve)), centres, tempo_curve, "psf", beats_per_bar
    )


class Observation(NamedTuple):
    """What the tempo HMM decodes (:func:`observe`): the windows, the period grid, the
    log observation per period and window, the resonator salience and the best measure."""

    starts: np.ndarray
    stops: np.ndarray
    centres: np.ndarray
    periods: np.ndarray
    max_hz: float
    log_obs: np.ndarray
    salience: np.ndarray
    measure: np.ndarray


def observe(
    ons: OnsetSignal,
    audio: tuple[np.ndarray, float],
    *,
    model: MeterModel,
    bpm: float | None = None,
    min_bpm: float = DEFAULT_MIN_BPM,
    max_bpm: float = DEFAULT_MAX_BPM,
    tempo_win_s: float = 8.0,
    tempo_hop_s: float = 1.0,
    drum_weight: float = DRUM_WEIGHT,
) -> Observation:
    """The metrical model's tactus observation plus the drum cue, per tempo window (trusts
    its inputs); a known ``bpm`` gives a grid of one period and no drum cue."""
    fps = ons.fps
    n = ons.envelope.size
    accents = _accents(ons.bands, fps)
    starts, stops, centres = analysis_windows(n, fps, tempo_win_s, tempo_hop_s)
    periods = period_grid(min_bpm, max_bpm) if bpm is None else np.array([60.0 / bpm])
    # above this the 10-ms smoothing leaves < 1 % of the accent power
    max_hz = np.sqrt(np.log(100.0)) / (2 * np.pi * _accent_sigma(fps) / fps)
    log_obs, salience, measure = tactus_observation(
        accents, fps, starts, stops, periods, model, max_hz=max_hz
    )
    if bpm is None and drum_weight > 0:
        y, sr = audio
        cue = alternation_cue(drum_envelopes(y, sr, fps, n), fps, starts, stops, periods)
        log_obs = log_obs + drum_weight * cue
    return Observation(starts, stops, centres, periods, max_hz, log_obs, salience, measure)


def pulse_clarity_null(
    ons: OnsetSignal,
    starts: np.ndarray,
    stops: np.ndarray,
    periods: np.ndarray,
    model: MeterModel,
    max_hz: float,
) -> float:
    """Pulse clarity of the same onsets in random order (seeded): what no pulse looks like,
    at the audio's onset density, window lengths and decoding bias. The mean path salience
    of the tactus terms alone over draws for :data:`NULL_AUDIO_S` of audio.
    """
    fps = ons.fps
    n = ons.bands.shape[1]
    n_draws = int(np.clip(np.ceil(NULL_AUDIO_S * fps / n), 1, NULL_MAX_DRAWS))
    rng = np.random.default_rng(0)
    # all draws at once: one batch of FFTs and one matrix product for the salience
    shuffled = np.stack([ons.bands[:, rng.permutation(n)] for _ in range(n_draws)])
    accents = _accents(shuffled, fps)
    log_obs, sal = beat_observation(accents, fps, starts, stops, periods, model, max_hz)
    values = []
    for d in range(n_draws):
        path = tempo_hmm(log_obs[:, :, d], periods, trans_sigma=TRANS_SIGMA, p_jump=P_JUMP)
        values.append(float(np.mean(sal[path, np.arange(path.size), d])))
    return float(np.mean(values))


def _warn_if_no_clear_pulse(ons, clarity, obs, model, duration, tempo_win_s) -> None:
    if clarity >= CLEAR_PULSE:
        return
    null = pulse_clarity_null(ons, obs.starts, obs.stops, obs.periods, model, obs.max_hz)
    if clarity < MIN_PULSE_CLARITY * null or clarity < MIN_PATH_SALIENCE:
        why = "noise, free rhythm or too short?"
        if duration < tempo_win_s:  # clips shorter than the tempo window warn more often
            why = (
                f"the audio is only {duration:.2f} s long, shorter than the {tempo_win_s:g} s "
                "tempo window: give a longer excerpt if you can (or it is noise or free "
                "rhythm);"
            )
        against = (
            f"less than {MIN_PULSE_CLARITY} times the {null:.2f} of the same onsets in random order"
            if clarity < MIN_PULSE_CLARITY * null
            else f"below {MIN_PATH_SALIENCE}"
        )
        warn(
            f"no clear pulse in the audio (pulse clarity {clarity:.2f}: {against}): {why} the "
            f"beats may be meaningless or at another metrical level; {KNOWN_TEMPO_HINT}",
            stacklevel=3,
        )


def _accent_sigma(fps: float) -> float:
    """Width [frames] of the accents' Gaussian smoothing: 10 ms, at least half a frame."""
    return max(0.01 * fps, 0.5)  # onsets a frame apart still resonate together


def _accents(bands: np.ndarray, fps: float) -> np.ndarray:
    """Band accent signals: the onset impulses smoothed over 10 ms (along the last axis)."""
    return gaussian_smooth(bands, _accent_sigma(fps))


#: librosa's beat tracker does not search above this tempo [BPM] (its ``max_tempo``).
LIBROSA_MAX_TEMPO = 320.0

#: Hop [samples] of the onset envelope when librosa tracks beats here (its default).
LIBROSA_HOP = 512


def librosa_tempo_steps(sr: float) -> np.ndarray:
    """The tempi [BPM] librosa's beat tracker can choose at ``sr`` [Hz], ascending: one per
    whole lag of its 8 s onset autocorrelation, ``60 sr / (hop lag)``, below 320 BPM."""
    win = int(np.floor(8.0 * sr / LIBROSA_HOP))  # librosa.time_to_frames(ac_size=8, ...)
    bpms = 60.0 * sr / (LIBROSA_HOP * np.arange(1, win))
    return np.sort(bpms[bpms < LIBROSA_MAX_TEMPO])


def librosa_tempo_prior(
    min_bpm: float = DEFAULT_MIN_BPM, max_bpm: float = DEFAULT_MAX_BPM, *, sr: float
):
    """The tempo prior for :func:`librosa.beat.beat_track` at ``sr`` [Hz]: ``None``
    (librosa's own) for the default range, else flat inside it (``scipy.stats.uniform``).

    Refuses a range holding none of :func:`librosa_tempo_steps` (e.g. 185-198 BPM at
    22.05 kHz) or above 320 BPM: librosa would return one beat at an infinite tempo.
    """
    if (min_bpm, max_bpm) == (DEFAULT_MIN_BPM, DEFAULT_MAX_BPM):
        return None
    if min_bpm >= LIBROSA_MAX_TEMPO:
        raise ParameterError(
            f"min_bpm {min_bpm:g}: librosa's beat tracker does not search above "
            f"{LIBROSA_MAX_TEMPO:g} BPM; give a lower min_bpm (or track the half tempo)"
        )
    steps = librosa_tempo_steps(sr)
    if not np.any((steps >= min_bpm) & (steps <= max_bpm)):
        near = [
            f"{v:.1f}"
            for v in steps[steps < min_bpm][-1:].tolist() + steps[steps > max_bpm][:1].tolist()
        ]
        verb = "is" if len(near) == 1 else "are"
        nearest = (
            f"the nearest {verb} {' and '.join(near)} BPM: widen the range to include one"
            if near
            else "it has none at this sample rate"
        )
        raise ParameterError(
            f"tempo range {min_bpm:g}-{max_bpm:g} BPM holds none of the tempi librosa "
            f"can choose at {sr:g} Hz (one lag of its onset autocorrelation, "
            f"hop {LIBROSA_HOP}); {nearest}"
        )
    import scipy.stats  # noqa: PLC0415

    return scipy.stats.uniform(min_bpm, max_bpm - min_bpm)


def _track_librosa(y, sr, *, bpm, min_bpm, max_bpm) -> BeatTrack:
    import librosa  # noqa: PLC0415 (heavy; only for the comparison method)

    kwargs: dict[str, Any] = {}
    if bpm is not None:
        kwargs["bpm"] = bpm
    elif (prior := librosa_tempo_prior(min_bpm, max_bpm, sr=sr)) is not None:
        kwargs["prior"] = prior
    tempo, beats = librosa.beat.beat_track(
        y=y.astype(np.float32), sr=sr, hop_length=LIBROSA_HOP, units="time", **kwargs
    )
    tempo = float(np.atleast_1d(tempo)[0])
    beats = np.unique(np.asarray(beats, dtype=np.float64))
    return BeatTrack(beats, tempo, np.array([y.size / sr / 2]), np.array([tempo]), "librosa")
