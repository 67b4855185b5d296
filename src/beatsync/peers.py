"""The beat trackers a user would pick instead of ours, behind one signature.

Every method is a function ``track(y, sr) -> beats``: mono audio ``y`` (float, finite)
at ``sr`` [Hz] in, beat times [s] out (1-D ``float64``, strictly increasing), each
with its published default settings. :data:`PEERS` names them:

- ``"psf"``: ours, :func:`beatsync.beats.track_beats` (phase-slope onsets and a
  tempo/phase HMM; paper A, section 4).
- ``"librosa"``: :func:`librosa.beat.beat_track` (Ellis 2007, dynamic programming),
  hop 512.
- ``"essentia-degara"``: essentia's ``BeatTrackerDegara`` (Degara et al. 2012,
  a probabilistic model of beat periods), audio resampled to 44.1 kHz as it requires.
- ``"essentia-multifeature"``: essentia's ``BeatTrackerMultiFeature`` (Zapata et al.
  2014, a committee of five onset features), at 44.1 kHz.

The essentia methods need the optional ``essentia`` package
(``pip install 'beatsync[peers]'``; AGPL-3.0): without it they are listed by
:func:`available` as missing and :func:`get` refuses them with that instruction;
everything else works.
"""

from __future__ import annotations

import importlib.util
import warnings
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from .errors import ParameterError
from .io import resample_audio

__all__ = ["Peer", "PEERS", "get", "available", "track", "ESSENTIA_SR"]

#: Sample rate the essentia beat trackers are built for [Hz].
ESSENTIA_SR = 44100


@dataclass(frozen=True)
class Peer:
    """A beat-tracking method.

    Attributes
    ----------
    name : str
        Registry key (``--method`` of ``beatsync evaluate beats``).
    description : str
        One line: the algorithm and its reference.
    track : callable ``(y, sr) -> beats [s]``
    requires : str or None
        The optional package it needs (``None``: always available).
    """

    name: str
    description: str
    track: Callable[[np.ndarray, float], np.ndarray]
    requires: str | None = None

    @property
    def is_available(self) -> bool:
        """Whether the package it needs is installed."""
        return self.requires is None or importlib.util.find_spec(self.requires) is not None


def _as_beats(times: object) -> np.ndarray:
    return np.unique(np.asarray(times, dtype=np.float64).ravel())


def track_psf(y: np.ndarray, sr: float) -> np.ndarray:
    """Our tracker, :func:`beatsync.beats.track_beats` with its defaults."""
    from .beats import track_beats

    return _as_beats(track_beats(y, sr).beats)


def track_librosa(y: np.ndarray, sr: float) -> np.ndarray:
    """:func:`librosa.beat.beat_track` with its defaults (hop 512), times in seconds."""
    import librosa

    _, beats = librosa.beat.beat_track(
        y=np.asarray(y, dtype=np.float32), sr=sr, hop_length=512, units="time"
    )
    return _as_beats(beats)


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


def track_essentia_degara(y: np.ndarray, sr: float) -> np.ndarray:
    """essentia ``BeatTrackerDegara`` with its defaults (at 44.1 kHz)."""
    es = _essentia()
    return _as_beats(es.BeatTrackerDegara()(_essentia_audio(y, sr)))


def track_essentia_multifeature(y: np.ndarray, sr: float) -> np.ndarray:
    """essentia ``BeatTrackerMultiFeature`` with its defaults (at 44.1 kHz)."""
    es = _essentia()
    ticks, _confidence = es.BeatTrackerMultiFeature()(_essentia_audio(y, sr))
    return _as_beats(ticks)


#: Every method by name, ours first.
PEERS: dict[str, Peer] = {
    p.name: p
    for p in (
        Peer("psf", "ours: phase-slope onsets, tempo/phase HMM (paper A)", track_psf),
        Peer("librosa", "librosa.beat.beat_track: dynamic programming (Ellis 2007)", track_librosa),
        Peer(
            "essentia-degara",
            "essentia BeatTrackerDegara: probabilistic beat periods (Degara et al. 2012)",
            track_essentia_degara,
            "essentia",
        ),
        Peer(
            "essentia-multifeature",
            "essentia BeatTrackerMultiFeature: five onset features (Zapata et al. 2014)",
            track_essentia_multifeature,
            "essentia",
        ),
    )
}


def available() -> dict[str, bool]:
    """Every method name -> whether it can run here (its optional package is installed)."""
    return {name: p.is_available for name, p in PEERS.items()}


def get(name: str) -> Peer:
    """The method called ``name``.

    Raises
    ------
    ParameterError
        Unknown name (the message lists the names), or a method whose optional
        package is not installed (the message says how to install it).
    """
    peer = PEERS.get(name)
    if peer is None:
        raise ParameterError(f"unknown beat-tracking method {name!r}; choose from {list(PEERS)}")
    if not peer.is_available:
        raise ParameterError(
            f"method {name!r} needs the optional package {peer.requires!r}, which is not "
            "installed: pip install 'beatsync[peers]'"
        )
    return peer


def track(name: str, y: np.ndarray, sr: float) -> np.ndarray:
    """Run the method ``name`` on ``y`` at ``sr`` [Hz]; return beat times [s].

    Raises
    ------
    ParameterError
        Unknown or unavailable method (:func:`get`); empty, silent or non-finite audio
        or ``sr <= 0`` (checked here for every method, as ours does).
    """
    from .beats import check_audio

    peer = get(name)
    y, sr = check_audio(y, sr)
    with warnings.catch_warnings():
        warnings.filterwarnings("ignore", category=FutureWarning)
        return peer.track(y, sr)
