"""Every beat tracker by name, ours and the others a user would pick instead.

Every method is ``track(y, sr, *, min_bpm=None, max_bpm=None) -> beats``: mono audio at
``sr`` [Hz] in, beat times [s] out (1-D ``float64``, strictly increasing), with its
published defaults. A tempo range narrows the tempi searched (:func:`check_tempo_range`);
only ours keeps its beats inside it (:func:`track` warns otherwise). The methods are
:data:`TRACKERS`; essentia's (at the 44.1 kHz they require) need the optional ``essentia``
package (``pip install 'beatsync[peers]'``; AGPL-3.0).
"""

from __future__ import annotations

import importlib.util
import warnings
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from .errors import ParameterError
from .io import resample_audio

__all__ = [
    "Tracker",
    "TRACKERS",
    "get",
    "available",
    "track",
    "prepare",
    "check_tempo_range",
    "ESSENTIA_SR",
    "ESSENTIA_TEMPO",
]

#: Sample rate the essentia beat trackers are built for [Hz].
ESSENTIA_SR = 44100

#: essentia's beat trackers' tempo range parameters [BPM]: whole numbers, ``minTempo``
#: in 40-180 (default 40), ``maxTempo`` in 60-250 (default 208), ``maxTempo`` at least
#: 20 above ``minTempo``.
ESSENTIA_TEMPO = {"min": (40, 180), "max": (60, 250), "default": (40, 208), "span": 20}


@dataclass(frozen=True)
class Tracker:
    """A beat-tracking method: its registry key (``--method``), a one-line description, its
    ``track`` function and the optional package it ``requires`` (None: always available).
    """

    name: str
    description: str
    track: Callable[..., np.ndarray]
    requires: str | None = None

    @property
    def is_available(self) -> bool:
        """Whether the package it needs is installed."""
        return self.requires is None or importlib.util.find_spec(self.requires) is not None


def _as_beats(times: object) -> np.ndarray:
    return np.unique(np.asarray(times, dtype=np.float64).ravel())


def _given(min_bpm: float | None, max_bpm: float | None) -> dict[str, float]:
    bounds = {"min_bpm": min_bpm, "max_bpm": max_bpm}
    return {k: float(v) for k, v in bounds.items() if v is not None}


def _ours(method: str) -> Callable[..., np.ndarray]:
    """``track`` of :func:`beatsync.beats.track_beats` with ``method`` and its defaults."""

    def track(
        y: np.ndarray, sr: float, *, min_bpm: float | None = None, max_bpm: float | None = None
    ) -> np.ndarray:
        from .beats import track_beats

        return _as_beats(track_beats(y, sr, method=method, **_given(min_bpm, max_bpm)).beats)

    return track


def prepare(name: str) -> None:
    """Compile what method ``name`` needs (librosa's numba functions) into its on-disk cache,
    once before several processes track with it: processes compiling at the same time can
    crash a later one (numba issue 10128)."""
    get(name)
    if name != "librosa":
        return
    import librosa

    from .beats.tracker import LIBROSA_HOP

    sr = 22050
    clicks = np.zeros(2 * sr, dtype=np.float32)
    clicks[:: sr // 2] = 1.0
    librosa.beat.beat_track(y=clicks, sr=sr, hop_length=LIBROSA_HOP, units="time")


def _essentia():
    import essentia

    essentia.log.infoActive = False  # no banner per algorithm on stdout
    essentia.log.warningActive = False
    import essentia.standard as es

    return es


def _essentia_track(algorithm: str) -> Callable[..., np.ndarray]:
    """``track`` of essentia's ``algorithm`` with its defaults (and a tempo range), at 44.1 kHz."""

    def track(
        y: np.ndarray, sr: float, *, min_bpm: float | None = None, max_bpm: float | None = None
    ) -> np.ndarray:
        tempo = {"minTempo": min_bpm, "maxTempo": max_bpm}
        algo = getattr(_essentia(), algorithm)(
            **{k: int(round(v)) for k, v in tempo.items() if v is not None}
        )
        y = np.asarray(y, dtype=np.float32)
        if sr != ESSENTIA_SR:
            y = resample_audio(y, sr, ESSENTIA_SR)
        out = algo(np.ascontiguousarray(y, dtype=np.float32))
        return _as_beats(out[0] if isinstance(out, tuple) else out)  # MultiFeature: + confidence

    return track


#: Every method by name, ours first.
TRACKERS: dict[str, Tracker] = {
    p.name: p
    for p in (
        Tracker("psf", "ours: phase-slope onsets, tempo/phase HMM (paper A)", _ours("psf")),
        Tracker(
            "librosa", "librosa.beat.beat_track: dynamic programming (Ellis 2007)", _ours("librosa")
        ),
        Tracker(
            "essentia-degara",
            "essentia BeatTrackerDegara: probabilistic beat periods (Degara et al. 2012)",
            _essentia_track("BeatTrackerDegara"),
            "essentia",
        ),
        Tracker(
            "essentia-multifeature",
            "essentia BeatTrackerMultiFeature: five onset features (Zapata et al. 2014)",
            _essentia_track("BeatTrackerMultiFeature"),
            "essentia",
        ),
    )
}


def available() -> dict[str, bool]:
    """Every method name -> whether it can run here (its optional package is installed)."""
    return {name: p.is_available for name, p in TRACKERS.items()}


def get(name: str) -> Tracker:
    """The method called ``name``; refuses an unknown name or a missing optional package."""
    tracker = TRACKERS.get(name)
    if tracker is None:
        raise ParameterError(f"unknown beat-tracking method {name!r}; choose from {list(TRACKERS)}")
    if not tracker.is_available:
        raise ParameterError(
            f"method {name!r} needs the optional package {tracker.requires!r}, which is not "
            "installed: pip install 'beatsync[peers]'"
        )
    return tracker


def check_tempo_range(
    name: str,
    min_bpm: float | None = None,
    max_bpm: float | None = None,
    *,
    names: tuple[str, str] = ("min_bpm", "max_bpm"),
) -> dict[str, float]:
    """The tempo range [BPM] that method ``name`` will search, checked; ``{}`` if none.

    A bound not given (or equal to the default) keeps the method's default (essentia's:
    :data:`ESSENTIA_TEMPO`). ``names``: the bounds' names in the errors (``--min-bpm``).
    """
    from .beats.tracker import LIBROSA_MAX_TEMPO
    from .validation import check_bpm

    tracker = TRACKERS.get(name) or get(name)  # get refuses an unknown method
    label = dict(zip(("min_bpm", "max_bpm"), names, strict=True))
    bounds = {"min_bpm": min_bpm, "max_bpm": max_bpm}
    given = {k: check_bpm(v, name=label[k]) for k, v in bounds.items() if v is not None}
    if not given:
        return {}
    defaults = _default_range(tracker)
    essentia = tracker.requires == "essentia"
    span = ESSENTIA_TEMPO["span"] if essentia else 0
    for key, value in given.items() if essentia else ():
        a, b = ESSENTIA_TEMPO[key[:3]]  # "min" or "max"
        if value != round(value) or not a <= value <= b:
            hint = (
                f"round it to {round(value)}"
                if a <= round(value) <= b
                else "to search outside them, use psf or librosa"
            )
            raise ParameterError(
                f"{label[key]} {value:g}: {name} takes a whole number of BPM from {a} to "
                f"{b} (essentia's limits); {hint}"
            )
    if name == "librosa" and given.get("min_bpm", 0.0) >= LIBROSA_MAX_TEMPO:
        raise ParameterError(
            f"{label['min_bpm']} {given['min_bpm']:g}: librosa's beat tracker does not search "
            f"above {LIBROSA_MAX_TEMPO:g} BPM; give a lower {label['min_bpm']} (or track the "
            "half tempo)"
        )
    lo = given.get("min_bpm", defaults["min_bpm"])
    hi = given.get("max_bpm", defaults["max_bpm"])
    if not (hi - lo >= span if span else lo < hi):
        what = f"at least {span} BPM below" if span else "smaller than"
        hint = ""  # the likely mistake: one bound given, crossing the other's default
        if len(given) == 1:
            (key,) = given
            other = "max_bpm" if key == "min_bpm" else "min_bpm"
            side = "below" if key == "max_bpm" else "above"
            hint = (
                f"; {label[key]} {given[key]:g} is {side} {name}'s default {label[other]} "
                f"{defaults[other]:g}: give {label[other]} too"
            )
        raise ParameterError(
            f"{label['min_bpm']} {lo:g} must be {what} {label['max_bpm']} {hi:g}{hint}"
        )
    # a bound equal to the default is the same search as none: recorded as not given
    return {k: v for k, v in given.items() if v != defaults[k]}


def _default_range(tracker: Tracker) -> dict[str, float]:
    """The tempo range [BPM] ``tracker`` searches when given no bound."""
    if tracker.requires == "essentia":
        return dict(zip(("min_bpm", "max_bpm"), ESSENTIA_TEMPO["default"], strict=True))
    from .beats.tracker import DEFAULT_MAX_BPM, DEFAULT_MIN_BPM

    return {"min_bpm": DEFAULT_MIN_BPM, "max_bpm": DEFAULT_MAX_BPM}


#: How far [fraction] the tracked median tempo may lie outside a given range before
#: :func:`track` warns (beat times are quantised to frames; a slow drift moves the median).
OUT_OF_RANGE_TOLERANCE = 0.05

#: The words of that warning that say which track it concerns (a command counts them).
OUT_OF_RANGE_TEXT = "outside the range it was given"


def _warn_out_of_range(name: str, beats: np.ndarray, tempo: dict[str, float]) -> None:
    """Warn if ``beats`` (tracked with the range ``tempo``) hold a median tempo outside it
    (essentia's beats can then differ from one call to the next; MTG/essentia issue 1097)."""
    if not tempo or beats.size < 3:
        return
    from .errors import warn

    bounds = {**_default_range(TRACKERS[name]), **tempo}
    lo, hi = bounds["min_bpm"], bounds["max_bpm"]
    # evaluate.beats.median_tempo is a layer above this module: the same two lines here
    bpm = 60.0 / float(np.median(np.diff(beats)))
    tol = OUT_OF_RANGE_TOLERANCE
    if lo / (1 + tol) <= bpm <= hi * (1 + tol):
        return
    if TRACKERS[name].requires == "essentia":
        why = "essentia's trackers take the range as a preference, not a limit"
    elif name == "librosa":
        why = "librosa's range bounds its tempo estimate, not the beats it then picks"
    else:  # ours decodes only tempi inside the range: beats are missing or doubled
        why = "some beats were skipped or doubled"
    alt = "" if name == "psf" else " (psf keeps to the range)"
    warn(
        f"{name} tapped a median tempo of {bpm:.0f} BPM, {OUT_OF_RANGE_TEXT} "
        f"({lo:g}-{hi:g} BPM): {why}; check the beats{alt}",
        stacklevel=3,
    )


def track(
    name: str,
    y: np.ndarray,
    sr: float,
    *,
    min_bpm: float | None = None,
    max_bpm: float | None = None,
) -> np.ndarray:
    """Beat times [s] of the method ``name`` on ``y`` at ``sr`` [Hz], the audio checked as
    ours checks it. Warns when the beats' median tempo lies more than
    :data:`OUT_OF_RANGE_TOLERANCE` outside a given range (see :func:`_warn_out_of_range`).
    """
    from .beats import check_audio
    from .beats.tracker import check_duration

    tracker = get(name)
    tempo = check_tempo_range(name, min_bpm, max_bpm)
    y, sr = check_audio(y, sr)
    check_duration(y.size, sr)
    with warnings.catch_warnings():
        warnings.filterwarnings("ignore", category=FutureWarning)
        beats = tracker.track(y, sr, **tempo)
    _warn_out_of_range(name, beats, tempo)
    return beats
