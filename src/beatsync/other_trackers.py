"""Every beat tracker by name, ours and the others a user would pick instead.

Every method is a function ``track(y, sr, *, min_bpm=None, max_bpm=None) -> beats``:
mono audio ``y`` at ``sr`` [Hz] in, beat times [s] out (1-D ``float64``, strictly
increasing), each with its published default settings. A tempo range narrows the
tempi searched; a bound not given keeps the method's default (:func:`check_tempo_range`).
Only ours keeps its beats inside the range: librosa's range bounds its tempo estimate,
essentia's trackers take it as a preference (:func:`track` warns when the beats fall
outside it). :data:`TRACKERS` names them:

- ``"psf"``: ours, :func:`beatsync.beats.track_beats` (phase-slope onsets and a
  tempo/phase HMM; paper A, section 4).
- ``"librosa"``: :func:`librosa.beat.beat_track` (Ellis 2007, dynamic programming),
  hop 512.
- ``"essentia-degara"``: essentia's ``BeatTrackerDegara`` (Degara et al. 2012,
  a probabilistic model of beat periods), audio resampled to 44.1 kHz as it requires.
- ``"essentia-multifeature"``: essentia's ``BeatTrackerMultiFeature`` (Zapata et al.
  2014, a committee of five onset features), at 44.1 kHz.

The essentia methods need the optional ``essentia`` package
(``pip install 'beatsync[peers]'``; AGPL-3.0): without it :func:`available` lists them
as missing and :func:`get` refuses them with that instruction.
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
    """A beat-tracking method.

    Attributes
    ----------
    name : str
        Registry key (``--method`` of ``beatsync evaluate beats``).
    description : str
        One line: the algorithm and its reference.
    track : callable ``(y, sr, *, min_bpm=None, max_bpm=None) -> beats [s]``
    requires : str or None
        The optional package it needs (``None``: always available).
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


def track_psf(
    y: np.ndarray, sr: float, *, min_bpm: float | None = None, max_bpm: float | None = None
) -> np.ndarray:
    """Our tracker, :func:`beatsync.beats.track_beats` with its defaults."""
    from .beats import track_beats

    return _as_beats(track_beats(y, sr, **_given(min_bpm, max_bpm)).beats)


def track_librosa(
    y: np.ndarray, sr: float, *, min_bpm: float | None = None, max_bpm: float | None = None
) -> np.ndarray:
    """:func:`librosa.beat.beat_track` with its defaults (hop 512), times in seconds.

    With a tempo range, a flat tempo prior inside it replaces librosa's log-normal one
    (as ``track_beats(method="librosa", min_bpm=, max_bpm=)``).
    """
    import librosa

    from .beats.tracker import LIBROSA_HOP, librosa_tempo_prior

    kwargs = {}
    if min_bpm is not None or max_bpm is not None:
        prior = librosa_tempo_prior(**_given(min_bpm, max_bpm), sr=sr)
        if prior is not None:
            kwargs["prior"] = prior
    _, beats = librosa.beat.beat_track(
        y=np.asarray(y, dtype=np.float32), sr=sr, hop_length=LIBROSA_HOP, units="time", **kwargs
    )
    return _as_beats(beats)


def prepare(name: str) -> None:
    """Compile what method ``name`` needs into its on-disk cache, in this process.

    Call it in one process before several processes track with the method at once (the
    workers of a cluster, parallel tests). librosa's beat tracker is built on numba
    functions cached on disk; numba writes a generalised ufunc's cache as two files,
    and processes compiling the same function at the same time can leave a pair written
    by different processes, which crashes a later process with a segmentation fault
    when it loads them (numba issue 10128). Compiled once first, the other processes
    only read the cache. A no-op for the methods without a JIT cache (ours, essentia).
    """
    get(name)
    if name != "librosa":
        return
    import librosa

    from .beats.tracker import LIBROSA_HOP

    sr = 22050
    clicks = np.zeros(2 * sr, dtype=np.float32)
    clicks[:: sr // 2] = 1.0
    librosa.beat.beat_track(y=clicks, sr=sr, hop_length=LIBROSA_HOP, units="time")


def _essentia_audio(y: np.ndarray, sr: float) -> np.ndarray:
    y = np.asarray(y, dtype=np.float32)
    if sr != ESSENTIA_SR:
        y = resample_audio(y, sr, ESSENTIA_SR)
    return np.ascontiguousarray(y, dtype=np.float32)


def _essentia():
    import essentia

    essentia.log.infoActive = False  # no banner per algorithm on stdout
    essentia.log.warningActive = False
    import essentia.standard as es

    return es


def _essentia_tempo(min_bpm: float | None, max_bpm: float | None) -> dict[str, int]:
    params = {"minTempo": min_bpm, "maxTempo": max_bpm}
    return {k: int(round(v)) for k, v in params.items() if v is not None}


def track_essentia_degara(
    y: np.ndarray, sr: float, *, min_bpm: float | None = None, max_bpm: float | None = None
) -> np.ndarray:
    """essentia ``BeatTrackerDegara`` with its defaults (at 44.1 kHz)."""
    es = _essentia()
    algo = es.BeatTrackerDegara(**_essentia_tempo(min_bpm, max_bpm))
    return _as_beats(algo(_essentia_audio(y, sr)))


def track_essentia_multifeature(
    y: np.ndarray, sr: float, *, min_bpm: float | None = None, max_bpm: float | None = None
) -> np.ndarray:
    """essentia ``BeatTrackerMultiFeature`` with its defaults (at 44.1 kHz)."""
    es = _essentia()
    algo = es.BeatTrackerMultiFeature(**_essentia_tempo(min_bpm, max_bpm))
    ticks, _confidence = algo(_essentia_audio(y, sr))
    return _as_beats(ticks)


#: Every method by name, ours first.
TRACKERS: dict[str, Tracker] = {
    p.name: p
    for p in (
        Tracker("psf", "ours: phase-slope onsets, tempo/phase HMM (paper A)", track_psf),
        Tracker(
            "librosa", "librosa.beat.beat_track: dynamic programming (Ellis 2007)", track_librosa
        ),
        Tracker(
            "essentia-degara",
            "essentia BeatTrackerDegara: probabilistic beat periods (Degara et al. 2012)",
            track_essentia_degara,
            "essentia",
        ),
        Tracker(
            "essentia-multifeature",
            "essentia BeatTrackerMultiFeature: five onset features (Zapata et al. 2014)",
            track_essentia_multifeature,
            "essentia",
        ),
    )
}


def available() -> dict[str, bool]:
    """Every method name -> whether it can run here (its optional package is installed)."""
    return {name: p.is_available for name, p in TRACKERS.items()}


def get(name: str) -> Tracker:
    """The method called ``name``.

    Raises
    ------
    ParameterError
        Unknown name (the message lists the names), or a method whose optional
        package is not installed (the message says how to install it).
    """
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

    A bound not given keeps the method's default: 40 and 240 BPM for ``psf`` and
    ``librosa`` (within 20-400 BPM, as :func:`beatsync.beats.track_beats`; librosa
    given a bound other than its default searches a flat prior from ``min_bpm`` to
    ``max_bpm`` instead of its own log-normal one, and refuses at tracking time a range
    holding none of its tempo steps, :func:`beatsync.beats.tracker.librosa_tempo_prior`),
    and essentia's own for its trackers (:data:`ESSENTIA_TEMPO`: whole numbers,
    ``min_bpm`` in 40-180 and ``max_bpm`` in 60-250, at least 20 apart).

    Parameters
    ----------
    names : (str, str)
        How the two bounds are named in the errors (e.g. the options ``--min-bpm``).

    Returns
    -------
    dict
        The bounds given, as floats (``min_bpm``, ``max_bpm``), for :func:`track`; a
        bound equal to the method's default is left out (the same search as none).

    Raises
    ------
    ParameterError
        An unknown method, or a bound that is not a number, out of the method's range,
        not whole for essentia, a ``min_bpm`` of 320 or more for librosa (it does not
        search above 320 BPM), or a range that is empty (or, for essentia, narrower
        than 20 BPM); the message names the option and the default it was set against.
    """
    from .beats.tracker import LIBROSA_MAX_TEMPO
    from .units import check_bpm

    tracker = TRACKERS.get(name)
    if tracker is None:
        get(name)  # raises: unknown method
    given = {
        key: check_bpm(value, name=label)
        for key, label, value in zip(("min_bpm", "max_bpm"), names, (min_bpm, max_bpm), strict=True)
        if value is not None
    }
    if not given:
        return {}
    defaults = _default_range(tracker)
    if tracker.requires == "essentia":
        span = ESSENTIA_TEMPO["span"]
        limits = {"min_bpm": ESSENTIA_TEMPO["min"], "max_bpm": ESSENTIA_TEMPO["max"]}
    else:
        span = 0
        limits = {}
    label = dict(zip(("min_bpm", "max_bpm"), names, strict=True))
    for key, value in given.items():
        if key in limits:
            a, b = limits[key]
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
        raise ParameterError(
            f"{label['min_bpm']} {lo:g} must be {what} {label['max_bpm']} {hi:g}"
            f"{_one_bound_hint(given, label, defaults, name)}"
        )
    # a bound equal to the method's default is the same search as no bound: record it
    # as not given, so that a folder scored without it resumes with it and vice versa
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
    """Warn if ``beats`` (tracked with the range ``tempo``) hold a median tempo outside it."""
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


def _one_bound_hint(given, label, defaults, name) -> str:
    """The likely mistake when only one bound was given and it crosses the other default."""
    if len(given) != 1:
        return ""
    (key,) = given
    other = "max_bpm" if key == "min_bpm" else "min_bpm"
    side = "below" if key == "max_bpm" else "above"
    return (
        f"; {label[key]} {given[key]:g} is {side} {name}'s default {label[other]} "
        f"{defaults[other]:g}: give {label[other]} too"
    )


def track(
    name: str,
    y: np.ndarray,
    sr: float,
    *,
    min_bpm: float | None = None,
    max_bpm: float | None = None,
) -> np.ndarray:
    """Run the method ``name`` on ``y`` at ``sr`` [Hz]; return beat times [s].

    ``min_bpm``/``max_bpm`` narrow the tempo range searched (:func:`check_tempo_range`);
    a bound not given keeps the method's default.

    Warns
    -----
    BeatsyncWarning
        Given a range, the beats' median tempo lies more than
        :data:`OUT_OF_RANGE_TOLERANCE` outside it: only ours keeps to the range; librosa's
        bounds its tempo estimate, not the beats it then picks, and essentia's trackers
        take it as a preference (outside it, their beats can differ from one call to the
        next; MTG/essentia issue 1097).

    Raises
    ------
    ParameterError
        Unknown or unavailable method (:func:`get`); a tempo range the method does not
        accept; empty, silent, constant or non-finite audio, ``sr <= 0``, or audio
        shorter than 1.5 s (:func:`beatsync.beats.tracker.check_duration`): checked
        here for every method, as ours does.
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
