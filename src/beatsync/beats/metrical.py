"""The metrical model: tatum, tactus (beat) and measure periods estimated jointly.

Method: Klapuri, Eronen & Astola (2006), "Analysis of the meter of acoustic musical
signals", IEEE Trans. Audio, Speech and Language Processing 14(1), 342-355, on our
phase-slope onset signal (its four bands play the role of the paper's four accent
bands).

1. **Comb-filter resonators** (:func:`resonator_salience`). A comb filter with delay
   ``tau`` and feedback ``alpha = 0.5 ** (tau / T0)`` (half-time ``T0`` = 3 s) resonates
   with the part of a band's accent signal that is periodic with ``tau``. Its output
   energy, divided by the input energy, is normalised by the filter's response to
   white noise ``gamma = (1 - alpha)**2 / (1 - alpha**2)``:
   ``r = (E_out / E_in - gamma) / (1 - gamma)`` (0: no periodicity, 1: all of the
   energy periodic), and summed over the bands: the salience ``s(tau)``. We evaluate
   the resonators' steady-state energy in the frequency domain, per analysis window
   (Parseval: ``E_out = sum_w |V(w)|^2 |H_tau(w)|^2`` with
   ``|H_tau(w)|^2 = (1 - alpha)^2 / (1 - 2 alpha cos(w tau) + alpha^2)``), which allows
   fractional delays on the tempo HMM's log-spaced period grid. The sum over the
   frequencies is taken in the lag domain, against the window's autocorrelation (the
   same sum, at a fraction of the cost: :func:`resonator_salience`).
2. **Probabilistic model** (:func:`tactus_observation`). Log-normal priors on the
   tatum, tactus and measure periods (medians 0.18, 0.55 and 2.1 s, as in the paper)
   and a ratio model ``g(x) = sum_l w_l N(x; l, 0.3)`` for tactus/tatum and
   measure/tactus favouring the ratios of common meters (1, 2, 3, 4, then 6 and 8).
   We weight a beat of three tatums half (``w_3 = 0.5`` for tactus/tatum; a bar of
   three beats keeps ``w_3 = 1``), see :attr:`MeterModel.tatum_ratio_weights`.
   The joint score of ``(tatum, tactus, measure)`` is the sum of the three
   observations ``beta * s(tau)``, the three log priors and the two log ratio terms.
   Tatum and measure are maximised out per window, leaving a tactus observation that
   the tempo HMM (:mod:`beatsync.beats.tempo`, the paper's temporal transition
   model with an added jump probability) decodes with Viterbi.
3. **Meter** (:func:`estimate_meter`): beats per bar, the most frequent ratio of the
   best measure period to the decoded tactus over the windows.

The paper's comb filters run on integer lags sample by sample; we take their
steady-state energy per 8-s window.

The spectrum of each window is zero-padded so that every resonator pass band (about
0.074 Hz wide) spans :data:`BINS_PER_PASS_BAND` bins (:func:`resonator_fft_size`).
Before, padded only to a power of two (0.084 Hz bins for 8 s windows), the salience
was jagged over the period grid; every measurement below that does not say otherwise
was made with that coarser sampling, and the fine sampling changed the synthetic set
little (it fixed the 180 BPM click track with drift on every seed) while it lifted
the short clips of the real recordings and put the madmom sample at its level (see
below and ``benchmarks/RESULTS.md``).

Known limit of the per-window evaluation (measured, not yet fixed): the Hann-windowed
8-s segment smears each spectral line over more than a resonator's pass band, so a
perfectly periodic pattern gets a salience that falls with the period (per band about
0.35, 0.30, 0.25 and 0.19 at 1, 2, 3 and 4 beats of the synthetic 3/4 pattern at
90 BPM). The evidence alone therefore prefers the fastest pulse present, the tactus
prior decides between levels an octave apart (without the drum cue, the synthetic drum
pattern at 180 BPM is tapped at 90), and the bar of a slow 3/4 loses to two beats
(meter 2 at 90 BPM).
Running the resonators in time over the whole signal (as in the paper) reverses the
bias (steady-state salience 3.23, 3.24 and 3.36 for 1, 2 and 3 beats of that pattern,
summed over bands) at several times the cost; correcting the window bias analytically
(dividing by each resonator's gain for a periodic input seen through the window)
amplified the noise of the long periods on real music (meters of 5 to 8). Neither is
used. The resonators run in time were measured in full on 2026-11-29 (a scratch run:
fractional delays by linear interpolation, each band's accents minus their 8 s moving
mean, the output energy over each 8 s window against the input's, the null left as it
is): Hainsworth 001, the waltz and the madmom sample kept F 1.0 and their meters, but
DANCE_C_4 went to 62.5 BPM (half its beat), and the synthetic set (30 s, seed 0) fell to
clean F 0.762, AMLt 0.787 and tempo-change F 0.770 (0.966, 0.962, 0.943 with the
windows): click tracks at 90-180 BPM were tapped at a half or a third of their tempo,
since a converged comb at a multiple of the period passes every harmonic of the period
too. The scratch implementation (numpy, block by block) took 16 times as long.

Two more evaluations of the same resonators were measured and not used. The energy of
a comb filter run over a zero-padded segment has a closed form in the segment's
normalised autocorrelation ``rho``: ``r(tau) = (1 - alpha) sum_{d >= 1} alpha**(d-1)
rho(d tau)``. (a) On a rectangular segment (the biased autocorrelation, each period
searched within its grid cell) every bundled real recording keeps its level and
meter and 3/4 at 90 BPM gets meter 3, but the synthetic set does not improve (seeds
0-2: clean F 0.933, 0.933, 0.966; AMLt 0.961, 0.983, 0.973; tempo-change F 0.933,
0.935, 0.957), 120 BPM items with swing or noise are tapped at 60 on every seed, and
the madmom sample stays at 118 BPM. (b) With the unbiased autocorrelation (Hann
segment divided by the window's own autocorrelation, lags up to half the window) no
multiple of the beat is favoured any more: the madmom sample is tapped at its level
(87.9 BPM, F 1.0) and the real recordings keep theirs for ``beta`` <= 5, but the
tactus prior alone then picks between levels an octave apart, and the synthetic
click tracks at 180 BPM are tapped at 90 (clean F 0.865-0.898). Either would also
need the no-clear-pulse constants of :mod:`beatsync.beats.tracker` calibrated again
(the salience scale changes).

Why the synthetic drums were missed by the prior (measured on seed 0, before the drum
cue of :mod:`beatsync.beats.drums`, which now taps them at their beat). The drum
pattern at 90 and at 180 BPM is the same pattern, only scaled; any salience that does
not depend on the tempo gives both the same evidence in beat units. A prior can tap
both at their labelled level only if the evidence at the labelled level is higher than
the mean of the levels either side of it. Ours is not. At 180 BPM, the labelled level
minus the half-note level is -0.10 (``beta * s`` averaged over windows; -0.24 with the
coarser spectral sampling). At 90 BPM, the labelled level minus the eighth-note level
is -0.02 (-0.03). With the tatum and measure terms as well, the labelled level beats
the half-note level at 180 BPM by 0.56 and loses to the eighth-note level at 90 BPM by
0.68, while the tactus prior favours 90 over 180 BPM by 1.17: no prior of the period
alone can get both. Every evaluation above shares this, because the kick and the snare
fall in different bands and each band on its own repeats every two beats. So with a
wider tactus prior (sigma 0.45 or 0.6) the clean 90 BPM pattern is tapped at 180 on
every seed (0-2), and the 180 BPM pattern with drift or noise still at 90. Every
experiment below was measured before :attr:`MeterModel.tatum_ratio_weights`, against
the scores of that time (Hainsworth 001's 3 s and 5 s clips: mean F 0.416 and 0.654;
now 0.508 and 0.789):

- The band sum added as a fifth band changed no level. The band sum alone tapped
  180 BPM clicks at 90.
- Tukey windows (taper 0.25 and 0.5) in place of the Hann tapped the 150 BPM
  pattern at 75.
- The exact comb energy over rectangular windows, averaged over the multiples of
  the period, tapped 90 and 120 BPM clicks at 45 and 60, and DANCE_C_4 at 62.5.
- That same energy used only for clips that fit in one window did better on short
  real clips, and worse on short synthetic ones. This was measured with the equal
  phase weights of that time; the current phase weights alone score the waltz's 3 s
  and 5 s clips 0.858 and 0.911. On the real clips, mean F went from
  0.418 to 0.672 and from 0.633 to 0.785 on Hainsworth 001 at 3 s and 5 s, and from
  0.625 to 0.724 and from 0.736 to 0.846 on the waltz. On 7 s synthetic clips it fell
  from 0.956 to 0.869.
- A jump distribution that decays with the log tempo ratio (Laplacian, scale 0.1
  and 0.03) did not keep the level through a tempo change. The level is decided
  window by window, and the cost of a single jump cannot outweigh that. On the
  tempo-change drum items (seed 0), the decoded half beats the half at the other
  level by 9-25 (log observation summed over ten windows): 120 BPM over 60 by 22,
  80 over 160 by 25, 135 over 67.5 by 9. Nor would keeping the meter help: the best
  measure is two beats on both sides of the decoded 120 -> 80 BPM switch.
- A narrower ratio model (``ratio_sigma`` 0.15 instead of the paper's 0.3, so that a
  tactus of three tatums counts against one of two or four) changed nothing on the
  synthetic set or the madmom sample (119.8 BPM), lifted the 5 s clips of
  Hainsworth 001 from mean F 0.654 to 0.751, and lowered those of the waltz
  (5 s: 0.911 to 0.905; 7 s: 0.967 to 0.960). Mixed, and seen on two recordings only.
- The decoded level was checked against the levels at 3/4 and 4/3 of it, each decoded
  again within +-4 % of that tempo with its beats placed, and the beat sequence whose
  beats fall on the strongest accents (mean accent at the beats over the mean accent)
  was kept. Hainsworth 001's clips rose (3 s: mean F 0.416 to 0.788; 5 s: 0.654 to
  0.893), but the waltz's fell (5 s: 0.911 to 0.721; 10 s: 0.992 to 0.852; its 15-30 s
  excerpts: 0.993 to 0.940): a slower sequence that keeps to the downbeats scores
  higher. With 2/3 and 3/2 of the level as well (+-8 %), the waltz's excerpts fell to
  0.832. The synthetic set did not change. Not used.
- A contrast of the folded accent was measured as evidence that could peak at the
  beat (per window and period: the band-sum accent folded over the period, the most
  that one phase exceeds the phase half a period later, over the mean accent). On the
  synthetic drums it peaks at half the beat, where the empty sixteenth counts as a
  weak off-beat, and of the seven bundled real recordings it peaks at the beat only
  on DANCE_C_4 (elsewhere at 1/2, 3/4 or 3/2 of it). Not used.
- Goto's (2001) drum-pattern cue was added to the tactus observation: the beat is the
  interval between a bass drum and a snare drum that alternate. We scored it as the
  low band and a higher band both concentrated at twice the period, in antiphase.
  On our phase-slope onsets the low band is too dense to show the kick (the score,
  averaged over windows, was 0.05 at most); weight 300 tapped DANCE_R_3 at 190. With the
  energy of its own STFT's bands (30-150 Hz, 150 Hz-5 kHz) it is used (:mod:`.drums`).
- Nor does a band's accent between the decoded beats tell a beat tapped at half its
  tempo (2026-11-29, scratch run: per band, the strongest onset within 1/8 beat of
  each beat and of each midpoint). Midpoints over beats: the 180 BPM drum pattern
  tapped at 90 (seed 0) 1.17 in the low band, the drums at their level 0.09-0.39; but
  at the annotated level the madmom sample 1.12-1.38 in every band, Hainsworth 001
  1.13 and DANCE_R_3 1.26-1.27 in low bands. A doubling rule would double them too.
- The tatum grid (1 % steps) misses the tactus periods (0.5 %); a periodic pulse's salience
  falls ~40 % within 1 % of its period: clicks at 160, 170, 190-240 BPM are tapped at half.
  Aligned grids fix 160-190 but tap 60 BPM drums at 120: not used (numbers: CHANGELOG).

Why 10-20 s clips of the waltz DANCE_W_10 were tapped faster than its beat, measured
before :attr:`MeterModel.tatum_ratio_weights` weighed a beat of three tatums half (the
disagreeing clips at 85-116 BPM, median 107, against 87 BPM for the 28 s excerpt;
``dance_song_rows`` in ``benchmarks/bench_beats.py``). Its first 20 s were tapped at
110 BPM (now 87.5). Their terms were compared at 87 BPM and at 4/3 of it, 116 BPM, in a
scratch decomposition of :func:`tactus_observation`. The measure is found right for both,
about 2.07 s: three beats at 87 BPM, or four at 116 BPM. Both readings are consistent
metrical trees, and a balance of small terms decides. Summed over the 13 windows:

- the salience favours 87 BPM by 2.9, and the tatum term by 2.0;
- the tactus prior favours 116 BPM by 3.4, and the measure term by 4.0. About 3 of
  the 4.0 is the normalisation of ``P(measure | tactus)``, which is larger for a
  shorter tactus.

The ratio term is where the two readings differ: the faster one is a beat of three
tatums. With that weighed half, DANCE_W_10 still has 9 disagreeing clips (median 105
BPM). Given a range of +-15 % around the excerpt's tempo, 1 of them agrees (tapped at
80-102 BPM, median 90): the salience near the beat is flat on them. Given the tempo
itself, 4 of the 9 agree, and none of DANCE_W_5's 11, most of which are at its tempo on
another phase (``dance_song_rows``). The no-clear-pulse warning of
:mod:`beatsync.beats.tracker` names a known tempo as the way out.

The whole songs (``benchmarks/whole_dance_songs.py``, on the songs of the development
machine's shared data, which are not bundled) showed it most. The cha-cha and the rumba
keep their excerpt's tempo in every window. With equal tatum-ratio weights, only 93 of
197 windows of DANCE_W_5 and 56 of 239 of DANCE_W_10 did, 51 and 129 were at 4/3 of
it, and DANCE_W_10 got 4 beats per bar; forced to one tempo (``time_varying=False``),
DANCE_W_10 got 120.3 BPM. With ``w_3 = 0.5``: 189 of 197 and 147 of 239, none at 4/3,
3 beats per bar for both; DANCE_W_10's other 92 windows are at 95-106 BPM and it still
warns of no clear pulse. The peers do not settle those windows either: on 30 s cut at
95-125 s, essentia's two trackers give 115 and 110 BPM and librosa 116 (ours alone:
101); on 200-230 s essentia gives 86 and ours alone 121 (a scratch check, median beat
intervals).

The madmom sample (2.8 s, 88 BPM, 4 annotated beats) was tapped at 120 BPM, a pulse of
three sixteenths, until the resonators' spectrum was sampled finely enough
(:func:`resonator_fft_size`): with 0.34 Hz bins for a 2.8 s clip (n_fft 512 at 172
frames/s) its salience at 88 BPM came out below the noise level (``s`` = -0.03 against
0.14 at 120 BPM), which no correction of the window bias could lift. It is now tapped
at 87.9 BPM (F 1.0) told nothing; neither librosa nor essentia's two trackers tap it at
its level (117 and 175 BPM).

The meter of the synthetic 3/4 pattern at 60-90 BPM is found as 1 or 2 beats (the
measure term sees the bar through the same window bias). A beat-synchronous meter
class was measured as a fix and not used (Gouyon & Herrera 2003, recurrence of
beat-segment descriptors): triple if the normalised autocorrelation of per-beat
features at a lag of 3 beats exceeds those at 2 and 4. On the synthetic meter grid
(2/4, 3/4, 6/8 at 60-160 BPM, seeds 1 and 3) it names the class of every item tapped
at its beat, which would lift the grid from 28 to 36 of 42. On the real recordings it
does not hold: with the band accents at the beats, the Ballroom waltz and DANCE_W_5
come out duple; with log-mel energies per beat, the Ballroom waltz and DANCE_W_10 do,
and the lag-3 autocorrelation is within 0.2 of the larger of lags 2 and 4 on all six
real items with a known meter, against about 1.4 on the synthetic ones (a scratch
measurement). The metrical model names the meter of all six (Hainsworth 001, the
cha-cha and the rumba 4; the three waltzes 3).

The observation exponent ``beta``, the prior widths and the ratio weights are our
choices (see :data:`METER_MODEL`): they were set on the synthetic test set, except the
tatum ratio weight ``w_3``, chosen on the whole songs of two waltzes (see
:class:`MeterModel`); the annotated recordings were only scored.
"""

from __future__ import annotations

import functools
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

__all__ = [
    "MeterModel",
    "METER_MODEL",
    "resonator_salience",
    "resonator_saliences",
    "tactus_observation",
    "estimate_meter",
    "ratio_weight",
    "beat_observation",
]


@dataclass(frozen=True)
class MeterModel:
    """Constants of the metrical model (Klapuri et al. 2006, section IV).

    Attributes
    ----------
    half_time_s : float [s]
        Half-time ``T0`` of the comb filters' feedback (paper: 3 s).
    tatum_median_s, tactus_median_s, measure_median_s : float [s]
        Medians of the log-normal period priors (paper: 0.18, 0.55, 2.1 s).
    tatum_sigma, tactus_sigma, measure_sigma : float
        Their standard deviations in natural-log units.
    ratio_weights : tuple of float
        ``w_l`` of the ratio model for l = 1..9: measure / tactus.
    tatum_ratio_weights : tuple of float
        ``w_l`` for tactus / tatum. As ``ratio_weights`` but ``w_3 = 0.5``: a beat of
        three tatums (compound meter) counts half, as the ratios 6 and 8 do. With equal
        weights the whole waltz songs DANCE_W_5 and DANCE_W_10 were tapped at 4/3 of
        their beat (a "beat" of three sixteenths, four to the bar) in 51 of 197 and 129
        of 239 tempo windows; with ``w_3`` at 0.2, 0.5 or 0.7, in none, and at 0.8 in 95
        of DANCE_W_10's (``benchmarks/whole_dance_songs.py``). Chosen on those two
        songs. The scores of the annotated recordings and their excerpts stayed the
        same. Of Hainsworth 001's 5-10 s clips, 13 moved from 130-135 to about
        100 BPM, 12 onto the beat and one onto the off-beat (7 s at 48 s: F 0.30 to
        0.0), none the other way (5 s: mean F 0.654 to 0.789). Of 204 synthetic items
        (the 30 s set and the 20 s front-end sweep set, seeds 0-2 each), 4 moved to
        another level and none the other way, all at the edges of the tempo range:
        the 180 BPM click track with noise (30 s seed 0, 20 s seed 1) and the 180 BPM
        drums with noise (20 s seed 1) to 90 BPM, the clean 60 BPM drums (20 s seed 1)
        to 120 BPM. The 6/8 pattern at 140 BPM is tapped at its beat rather than at
        half of it, but with 4 beats per bar rather than 2.
    ratio_sigma : float
        Width of each Gaussian of the ratio model.
    beta : float
        Observation exponent: the log likelihood of a period is ``beta * s(tau)``.
    min_tatum_s, max_measure_s : float [s]
        Shortest tatum and longest measure considered.
    """

    half_time_s: float = 3.0
    tatum_median_s: float = 0.18
    tactus_median_s: float = 0.55
    measure_median_s: float = 2.1
    tatum_sigma: float = 0.4
    tactus_sigma: float = 0.3
    measure_sigma: float = 0.3
    ratio_weights: tuple[float, ...] = (1.0, 1.0, 1.0, 1.0, 0.1, 0.5, 0.1, 0.5, 0.1)
    tatum_ratio_weights: tuple[float, ...] = (1.0, 1.0, 0.5, 1.0, 0.1, 0.5, 0.1, 0.5, 0.1)
    ratio_sigma: float = 0.3
    beta: float = 10.0
    min_tatum_s: float = 0.08
    max_measure_s: float = 4.0

    def __post_init__(self) -> None:
        # tuples, so that the model can key the cache of its constant terms
        for name in ("ratio_weights", "tatum_ratio_weights"):
            object.__setattr__(self, name, tuple(float(w) for w in getattr(self, name)))


#: Fewest cycles of a beat period inside an analysis window for its salience to count.
MIN_BEAT_CYCLES = 4

#: The model used by :func:`beatsync.beats.track_beats`.
METER_MODEL = MeterModel()


def resonator_salience(
    bands: np.ndarray,
    fps: float,
    starts: Sequence[int],
    stops: Sequence[int],
    periods: np.ndarray,
    half_time_s: float,
    max_hz: float | None = None,
) -> np.ndarray:
    """Normalised comb-filter resonator energy summed over bands, (n_periods, n_windows).

    Parameters
    ----------
    bands : np.ndarray [shape=(n_bands, n_frames)] or (n_sets, n_bands, n_frames)
        Accent signal per band; with a leading axis, several sets of bands (the draws of
        the pulse-clarity null) at once, and the result has shape
        (n_periods, n_windows, n_sets).
    fps : float [Hz]
    starts, stops : sequence of int [frames]
        Analysis windows.
    periods : np.ndarray [s]
        Comb delays (need not be whole frames).
    half_time_s : float [s]
        Feedback half-time ``T0``.
    max_hz : float, optional [Hz]
        Frequencies of the accent signal above this (where a smoothed accent signal
        has almost no energy) pass every resonator with its mean gain ``gamma``
        instead of being filtered one by one (saves time, changes nothing visible).

    Notes
    -----
    The energy is the sum over the one-sided FFT bins ``b`` of the padded window's
    power ``P(b)`` times ``|H_tau(b)|^2`` (:func:`resonator_fft_size`). It is computed
    in the lag domain, which gives the same sum up to rounding at a fraction of the
    cost: ``P(b)`` is the transform of the window's autocorrelation ``a(k)`` (``|k| <
    L``, the window length), so the sum is ``sum_k a(k) c(k)`` with ``c(k) = sum_b
    |H_tau(b)|^2 cos(2 pi b k / n_fft)`` (:func:`_resonator_lag_weights`, once per
    period grid), and ``a`` needs an FFT of only ``2 L - 1`` points instead of the
    ``n_fft`` of the fine spectral sampling.

    The product ``sum_k a(k) c(k)`` is taken in float32 (the weights are computed in
    float64 and stored in float32; each autocorrelation is first divided by its lag-0
    value, so the salience stays independent of the accents' scale). Each band's
    energy ratio is off by about 1e-7 of its range (1e-15 in float64); the product's
    memory traffic and the cached weights halve (the whole tracker took 0.95 times
    the time on the 2.8 s madmom sample and on a 32 s song, interleaved in one process
    with the float64 code). It changed no beat, tempo, meter or warning of 75 items
    (the bundled recordings, 18 clips of them and the 20 s synthetic set); saliences
    moved by at most 9e-7.
    """
    return resonator_saliences(bands, fps, starts, stops, [periods], half_time_s, max_hz)[0]


def resonator_saliences(
    bands: np.ndarray,
    fps: float,
    starts: Sequence[int],
    stops: Sequence[int],
    period_blocks: Sequence[np.ndarray],
    half_time_s: float,
    max_hz: float | None = None,
) -> list[np.ndarray]:
    """:func:`resonator_salience` for several period grids, one per block (the tactus,
    tatum and measure grids of :func:`tactus_observation`): the windows'
    autocorrelations are computed once, and each grid's lag weights are cached on
    their own (the pulse-clarity null reuses the tactus grid's)."""
    import scipy.fft  # noqa: PLC0415 (batched real FFTs)

    bands = np.asarray(bands, dtype=np.float64)
    sets = bands.ndim == 3
    if not sets:
        bands = bands[None]
    n_sets, n_bands = bands.shape[:2]
    length = int(max(b - a for a, b in zip(starts, stops, strict=True)))
    n_fft = resonator_fft_size(length, fps, half_time_s)
    n_bins = n_fft // 2 + 1
    if max_hz is not None:
        n_bins = min(n_bins, int(np.ceil(max_hz / fps * n_fft)) + 1)
    # the weights are cached for lags up to the next multiple of LAG_BUCKET: clips of
    # other lengths under it share them (with the exact length as the key, every new
    # clip length computed three grids again, about 0.2 s)
    n_lags = min(n_fft, -(-length // LAG_BUCKET) * LAG_BUCKET)
    weights = [
        _resonator_lag_weights(
            np.ascontiguousarray(periods, dtype=np.float64).tobytes(),
            fps,
            n_fft,
            n_bins,
            half_time_s,
            n_lags,
        )
        for periods in period_blocks
    ]
    weights = [(lag_w[:, :length], gamma) for lag_w, gamma in weights]
    # the lag weights of the window's total energy (every gain 1)
    total_w = _bin_cosine_sums(n_fft, length) * _lag_multiplicity(length)
    n_acf = scipy.fft.next_fast_len(2 * length - 1, real=True)  # linear, not circular
    n_win = len(starts)
    total = np.empty((n_win, n_sets * n_bands))
    energies = [np.empty((w[0].shape[0], n_win, n_sets * n_bands)) for w in weights]
    # windows in chunks: a whole song's windows at once would hold 10 minutes of audio
    # in about 600 padded copies
    for c0 in range(0, n_win, WINDOW_CHUNK):
        chunk = list(
            zip(starts[c0 : c0 + WINDOW_CHUNK], stops[c0 : c0 + WINDOW_CHUNK], strict=True)
        )
        seg = np.zeros((len(chunk), n_sets, n_bands, n_acf))
        for i, (a, b) in enumerate(chunk):
            x = bands[:, :, a:b]
            seg[i, :, :, : b - a] = (x - x.mean(axis=2, keepdims=True)) * _hanning(b - a)
        spec = scipy.fft.rfft(seg, axis=3)
        acf = scipy.fft.irfft(spec.real**2 + spec.imag**2, n=n_acf, axis=3)[..., :length]
        acf = acf.reshape(-1, length).T  # (lag, window x set x band)
        # each column over its lag-0 value: the energy ratios below do not change, and
        # the float32 product cannot overflow or lose precision for any input scale
        lag0 = acf[0]
        acf = acf / np.where(lag0 > 0, lag0, 1.0)
        total[c0 : c0 + len(chunk)] = (total_w @ acf).reshape(len(chunk), -1)
        acf = acf.astype(np.float32)
        for (lag_w, _), energy in zip(weights, energies, strict=True):
            energy[:, c0 : c0 + len(chunk)] = (lag_w @ acf).reshape(lag_w.shape[0], len(chunk), -1)
    span = (np.asarray(stops) - np.asarray(starts)) / fps
    out = []
    for periods, (_, gamma), energy in zip(period_blocks, weights, energies, strict=True):
        ratio = np.divide(energy, total[None], out=np.zeros_like(energy), where=total[None] > 0)
        r = (ratio - gamma[:, None, None]) / (1 - gamma[:, None, None])
        # fewer than two periods inside the window: no evidence either way
        r[np.asarray(periods)[:, None] > span[None, :] / 2] = 0.0
        r = r.reshape(r.shape[0], n_win, n_sets, n_bands).sum(axis=3)
        out.append(r if sets else r[:, :, 0])
    return out


@functools.lru_cache(maxsize=8)
def _hanning(n: int) -> np.ndarray:
    """``np.hanning(n)``, cached (every tempo window of a song has the same length)."""
    w = np.hanning(n)
    w.flags.writeable = False
    return w


#: Analysis windows whose autocorrelations :func:`resonator_salience` holds at once.
WINDOW_CHUNK = 32

#: FFT bins per resonator pass band (see :func:`resonator_fft_size`).
BINS_PER_PASS_BAND = 3


def resonator_fft_size(length: int, fps: float, half_time_s: float) -> int:
    """FFT length of the resonators' windows: fine enough to sample every pass band.

    A comb filter of feedback half-time ``T0`` passes a band about
    ``ln 2 / (pi T0)`` wide around each multiple of ``1 / tau`` (0.074 Hz for the
    paper's 3 s, whatever the period). The window's spectrum is sampled at
    :data:`BINS_PER_PASS_BAND` bins per pass band at least (zero padding), else the
    salience of a period depends on whether its pass bands happen to fall on a bin:
    with bins ``fps / n_fft`` = 0.084 Hz apart (an 8 s window at 172 frames/s padded
    only to a power of two) or 0.17 Hz (a 5 s clip), neighbouring periods on the 0.5 %
    grid differed by up to 7 in log observation, and a clean 5 s click track at 120 BPM
    was tapped at 60. Sampled twice as finely again (7 bins per pass band), the
    bundled real recordings, their clips and the synthetic set kept every tempo and
    score but that of one 3 s clip of the waltz.
    """
    pass_band = np.log(2.0) / (np.pi * half_time_s)  # [Hz]
    need = max(length, 2, int(np.ceil(BINS_PER_PASS_BAND * fps / pass_band)))
    return int(2 ** np.ceil(np.log2(need)))


@functools.lru_cache(maxsize=12)
def _resonator_lag_weights(
    periods_key: bytes, fps: float, n_fft: int, n_bins: int, half_time_s: float, n_lags: int
) -> tuple[np.ndarray, np.ndarray]:
    """Lag weights of the resonators' energy (cached per period grid and number of lags).

    With ``G(b) = |H_tau(b)|^2`` on the one-sided bins ``b < n_bins`` and ``gamma``
    above, returns ``(lag_w, gamma)``: ``lag_w[i, k] = m_k c_i(k)`` with
    ``c_i(k) = sum_{b=0}^{n_fft/2} G_i(b) cos(2 pi b k / n_fft)`` for lags
    ``k < n_lags``, and ``m_k`` 1 at lag 0 and 2 elsewhere (the autocorrelation is
    even), so that ``lag_w @ a`` is the resonators' energy ``sum_b P(b) G(b)`` for a
    window's autocorrelation ``a``. The sums over bins are taken by an inverse real
    FFT, a few periods at a time (the whole grid at once took twice as long), and
    stored in float32 (see :func:`resonator_salience`).
    """
    import scipy.fft  # noqa: PLC0415

    periods = np.frombuffer(periods_key, dtype=np.float64)
    omega = 2.0 * np.pi * np.arange(n_bins) / n_fft  # [rad / frame]
    alpha = 0.5 ** (periods / half_time_s)
    gamma = (1 - alpha) ** 2 / (1 - alpha**2)
    half = n_fft // 2
    sign = np.where(np.arange(n_lags) % 2 == 0, 1.0, -1.0)
    ones = _bin_cosine_sums(n_fft, n_lags)  # the sums for G = 1
    mult = _lag_multiplicity(n_lags)
    lag_w = np.empty((periods.size, n_lags))
    excess = np.zeros((LAG_WEIGHT_ROWS, half + 1))
    for r0 in range(0, periods.size, LAG_WEIGHT_ROWS):
        rows = slice(r0, min(r0 + LAG_WEIGHT_ROWS, periods.size))
        a, g = alpha[rows, None], gamma[rows, None]
        m = a.shape[0]
        # G - gamma on the bins below n_bins (zero above); its cosine sums by irfft:
        # irfft(X)[k] = (X[0] + 2 sum_{0<b<n/2} X[b] cos(2 pi b k / n) + X[n/2] (-1)^k) / n
        excess[:m, :n_bins] = (1 - a) ** 2 / (
            1 - 2 * a * np.cos(np.outer(periods[rows] * fps, omega)) + a**2
        ) - g
        c = n_fft * scipy.fft.irfft(excess[:m], n=n_fft, axis=1)[:, :n_lags]
        c += excess[:m, :1] + excess[:m, half : half + 1] * sign[None, :]
        lag_w[rows] = (c / 2 + g * ones[None, :]) * mult[None, :]
    lag_w = lag_w.astype(np.float32)
    for arr in (lag_w, gamma):
        arr.flags.writeable = False
    return lag_w, gamma


#: Periods whose lag weights :func:`_resonator_lag_weights` computes at once.
LAG_WEIGHT_ROWS = 32

#: Lags are cached in multiples of this: windows of 0-8 s at 172 frames/s fall in three
#: sizes (512, 1024, 1536 lags), three grids each.
LAG_BUCKET = 512


def _lag_multiplicity(n_lags: int) -> np.ndarray:
    """``m_k``: lag 0 counts once, every other lag twice (``k`` and ``-k``)."""
    return np.where(np.arange(n_lags) == 0, 1.0, 2.0)


def _bin_cosine_sums(n_fft: int, n_lags: int) -> np.ndarray:
    """``sum_{b=0}^{n_fft/2} cos(2 pi b k / n_fft)`` for lags ``0 <= k < n_lags <= n_fft``:
    ``n_fft/2 + 1`` at lag 0, else 1 at even and 0 at odd lags (a Dirichlet sum)."""
    k = np.arange(n_lags)
    return np.where(k == 0, n_fft // 2 + 1.0, np.where(k % 2 == 0, 1.0, 0.0))


def _log_prior(periods: np.ndarray, median: float, sigma: float) -> np.ndarray:
    """Log-normal prior per state of a log-spaced grid (no 1/tau Jacobian)."""
    return -0.5 * (np.log(periods / median) / sigma) ** 2


def ratio_weight(
    x: np.ndarray, model: MeterModel = METER_MODEL, *, tatum: bool = False
) -> np.ndarray:
    """The ratio model ``g(x) = sum_l w_l N(x; l, sigma)`` (unnormalised Gaussians).

    ``x`` is measure / tactus, or with ``tatum=True`` tactus / tatum (the weights of
    :attr:`MeterModel.tatum_ratio_weights`).
    """
    x = np.asarray(x, dtype=np.float64)
    out = np.zeros_like(x)
    weights = model.tatum_ratio_weights if tatum else model.ratio_weights
    for ratio, w in enumerate(weights, start=1):
        out += w * np.exp(-0.5 * ((x - ratio) / model.ratio_sigma) ** 2)
    return out


def _level_grid(lo: float, hi: float, step: float = 0.01) -> np.ndarray:
    n = max(int(np.ceil(np.log(hi / lo) / step)) + 1, 2)
    return np.exp(np.linspace(np.log(lo), np.log(hi), n))


def _log_conditional(
    log_g: np.ndarray, levels: np.ndarray, median: float, sigma: float
) -> np.ndarray:
    """``log P(level | tactus)``: ratio model times the level's prior, normalised per tactus."""
    joint = log_g + _log_prior(levels, median, sigma)[None, :]
    finite = np.where(np.isfinite(joint), joint, -np.inf)
    top = finite.max(axis=1, keepdims=True)
    log_z = top + np.log(np.exp(finite - top).sum(axis=1, keepdims=True))
    return log_g - log_z


@functools.lru_cache(maxsize=8)
def _level_terms(periods_key: bytes, model: MeterModel):
    """Tatum and measure grids and ``log P(level | tactus)`` for a tactus grid (cached).

    Returns ``(tatum, measure, g_a, g_c)``: ``g_a[i, j]`` for tatum ``j`` under tactus
    ``i`` (tatum <= tactus), ``g_c[i, k]`` for measure ``k`` (measure >= tactus); the
    two log terms in float32.
    """
    periods = np.frombuffer(periods_key, dtype=np.float64)
    tatum = _level_grid(model.min_tatum_s, float(periods.max()))
    measure = _level_grid(float(periods.min()), model.max_measure_s)
    with np.errstate(divide="ignore"):
        g_a = np.log(ratio_weight(periods[:, None] / tatum[None, :], model, tatum=True))
        g_c = np.log(ratio_weight(measure[None, :] / periods[:, None], model))
    g_a[tatum[None, :] > periods[:, None] * 1.0001] = -np.inf
    g_c[measure[None, :] < periods[:, None] * 0.9999] = -np.inf
    g_a = _log_conditional(g_a, tatum, model.tatum_median_s, model.tatum_sigma)
    g_c = _log_conditional(g_c, measure, model.measure_median_s, model.measure_sigma)
    g_a, g_c = g_a.astype(np.float32), g_c.astype(np.float32)
    for arr in (tatum, measure, g_a, g_c):
        arr.flags.writeable = False
    return tatum, measure, g_a, g_c


def _tactus_terms(
    s_b: np.ndarray,
    fps: float,
    starts: Sequence[int],
    stops: Sequence[int],
    periods: np.ndarray,
    model: MeterModel,
) -> np.ndarray:
    """``beta s(tB) + log p(tB)``; zeroes (in place) the salience of unobservable periods.

    A beat period is observable only if the window holds at least four of its cycles
    (a measure: two); longer periods count as unsupported.
    """
    span = (np.asarray(stops) - np.asarray(starts)) / fps
    s_b[periods[:, None] > span[None, :] / MIN_BEAT_CYCLES] = 0.0
    prior = _log_prior(periods, model.tactus_median_s, model.tactus_sigma)
    return model.beta * s_b + prior.reshape((-1,) + (1,) * (s_b.ndim - 1))


def tactus_observation(
    bands: np.ndarray,
    fps: float,
    starts: Sequence[int],
    stops: Sequence[int],
    periods: np.ndarray,
    model: MeterModel = METER_MODEL,
    max_hz: float | None = None,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Log observation of each tactus period per window, tatum and measure maximised out.

    The score of a tactus period ``tB`` is ``beta s(tB) + log p(tB)`` plus, for the
    tatum, ``max_tA [beta s(tA) + log p(tA) + log g(tB / tA) - log Z_A(tB)]`` and, for
    the measure, the same with ``g(tC / tB)``; ``Z`` normalises ``P(tA | tB)`` (and
    ``P(tC | tB)``) over the candidates (tatum <= tactus <= measure).

    Returns
    -------
    log_obs : np.ndarray [shape=(n_periods, n_windows)]
    salience : np.ndarray [shape=(n_periods, n_windows)]
        Resonator salience ``s`` at the tactus periods.
    measure : np.ndarray [shape=(n_periods, n_windows)] [s]
        The best measure period for each tactus period and window.
    """
    tatum, measure, g_a, g_c = _level_terms(
        np.ascontiguousarray(periods, dtype=np.float64).tobytes(), model
    )
    s_b, s_a, s_c = resonator_saliences(
        bands, fps, starts, stops, [periods, tatum, measure], model.half_time_s, max_hz
    )
    log_b = _tactus_terms(s_b, fps, starts, stops, periods, model)
    # the maximisation over tatum and measure in float32: 2.7 times faster than in
    # float64; its rounding (about 1e-5 of a log likelihood) changed no score, tempo or
    # meter of the bundled real recordings or the synthetic set
    obs_a = model.beta * s_a + _log_prior(tatum, model.tatum_median_s, model.tatum_sigma)[:, None]
    obs_c = (
        model.beta * s_c + _log_prior(measure, model.measure_median_s, model.measure_sigma)[:, None]
    )
    obs_a, obs_c = obs_a.astype(np.float32), obs_c.astype(np.float32)
    n_win = s_b.shape[1]
    rows = np.arange(periods.size)
    best = np.empty((periods.size, n_win))
    best_measure = np.empty((periods.size, n_win))
    for w in range(n_win):
        ta = g_a + obs_a[None, :, w]
        tc = g_c + obs_c[None, :, w]
        ic = np.argmax(tc, axis=1)
        best[:, w] = ta.max(axis=1) + tc[rows, ic]
        best_measure[:, w] = measure[ic]
    return log_b + best, s_b, best_measure


def beat_observation(
    bands: np.ndarray,
    fps: float,
    starts: Sequence[int],
    stops: Sequence[int],
    periods: np.ndarray,
    model: MeterModel = METER_MODEL,
    max_hz: float | None = None,
) -> tuple[np.ndarray, np.ndarray]:
    """The tactus terms alone: ``beta s(tB) + log p(tB)`` and ``s(tB)``, (n_periods, n_windows).

    :func:`tactus_observation` without the tatum and measure; the pulse-clarity null
    of :mod:`beatsync.beats.tracker` decodes with it. ``bands`` of shape
    (n_sets, n_bands, n_frames) give both arrays a last axis of n_sets (see
    :func:`resonator_salience`).
    """
    s_b = resonator_salience(bands, fps, starts, stops, periods, model.half_time_s, max_hz)
    return _tactus_terms(s_b, fps, starts, stops, periods, model), s_b


def estimate_meter(measure_at_tactus: np.ndarray, tactus: np.ndarray) -> int:
    """Beats per bar: the most frequent whole ratio of measure to tactus period."""
    ratios = np.rint(measure_at_tactus / tactus).astype(np.int64)
    ratios = ratios[(ratios >= 1) & (ratios <= 9)]
    if ratios.size == 0:
        return 0
    return int(np.bincount(ratios).argmax())
