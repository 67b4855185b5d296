"""Beat-synchronous resampling of periodic motion (paper A, section 5).

Make every period of a dance land on the music's beats: each motion period is mapped
to a group of ``m`` consecutive music beats, its playback rate is set so that it lasts
exactly as long as that group, the per-period rates are blended into a smoothly
varying rate with Gaussian weights (paper A, eq. 9), and the rate is integrated into a
monotonic time warp on which the motion is resampled (quaternion slerp for rotations,
linear interpolation for positions).

Data contract
-------------
- Event times (period ``boundaries``, music ``beats``) are 1-D float64 arrays in
  seconds, strictly increasing. Boundaries are in the *source* motion's timeline,
  beats in the *music* timeline.
- The synchronised motion's frame ``k`` is shown at music time ``k / out_fps``: its
  time axis *is* the music's, so it can be played together with the song from the
  start. Frames before the first warped frame hold the first pose.
- Rates are dimensionless: ``rate = target duration / source duration`` (> 1 slows
  the dance down). The report's ``tempo_ratio`` is its inverse, the playback speed.
- All frame/second conversion goes through :mod:`beatsync.validation`.

Method (what the paper leaves open, and our choices)
----------------------------------------------------
1. Beats per period (:func:`beats_per_period`): ``m = max(1, round(P / b))`` with
   ``P`` the mean motion period and ``b`` the median inter-beat interval, so a 1 s
   salsa step on a 120 BPM song spans 2 beats, a 6-beat figure 6 beats. When the
   meters are known (the dance's motion beats per period, counted from its
   kinematic beats; the music's beats per bar) ``m`` respects both: a 3-beat waltz
   step spans 3 or 6 beats, never 5; when they cannot both be kept within a factor
   of 2 of ``P / b``, the dance's meter wins and a warning says so. Override with
   ``beats_per_period=``.
2. Period ``i`` (source ``[s_i, s_{i+1}]``) is mapped to beats
   ``B_i = beats[first_beat + i*m]`` and ``B_{i+1}``. Per-period rate
   ``r_i = (B_{i+1} - B_i) / (s_{i+1} - s_i)``.
3. Eq. 9 (our reading): the continuous rate is the Gaussian-weighted mean of the
   period rates, ``r(t) = sum_i w_i(t) r_i / sum_i w_i(t)``,
   ``w_i(t) = exp(-(t - c_i)^2 / (2 delta^2))``, ``c_i`` the centre of period ``i``
   in source time and ``delta`` the mean motion period (default).
4. The blended rate alone does not make boundaries land on beats (it smears each
   period's rate into its neighbours; with ``delta`` = one period the blend is
   nearly the running mean). We correct each period by a bump ``h(u)`` that
   vanishes at both of its ends, ``r~(t) = r(t) (1 + a_i h(u))``, ``u`` the phase in
   the period, with ``a_i`` chosen so that the integral over the period equals
   ``B_{i+1} - B_i`` exactly. ``h`` is a plateau with raised-cosine ramps over a
   quarter period at each end (a Tukey window): inside a period the rate then
   approaches that period's own ``r_i``, and it passes smoothly through the blended
   eq. 9 value at every boundary. (A ``sin^2`` bump would need twice the
   amplitude and overshoot ``r_i``.) The rate stays continuous across boundaries
   (if a correction would need ``a_i <= -0.9`` we fall back to scaling the period's
   rate, which makes the rate jump there; the report counts these).
5. The warp ``tau(t)`` integrates ``r~`` (trapezoid on a fine grid whose knots
   include every boundary, so ``tau(s_i) = B_i`` to rounding). Before the first
   boundary and after the last one the rate is held constant at its boundary value.
   If the music has fewer beats than the motion has periods, the periods that do not
   fit are dropped and the output ends at the last boundary used.
6. Output frames at ``k / out_fps`` are mapped back to source times by inverting the
   warp, and the motion is evaluated there with :func:`beatsync.rotations.sample_motion`.
   Output frames run from music time 0 to the first frame at or after the warp's end
   (motion warped to negative music times, before the song starts, is dropped).
7. ``phase_offset`` [s] lands the boundaries that long after their beats;
   ``land="accents"`` measures the mean lag of the dancer's kinematic beats behind the
   beats after a first pass and lands again with ``phase_offset=-lag``, so the
   dancer's accents rather than the segmentation's boundaries sit on the beat.

Beyond the paper (for real dances)
----------------------------------
- ``mode="beats"``: a dance that is not strictly periodic (ballroom figures vary) is
  warped on its own motion beats (:func:`beatsync.motion_beats.kinematic_beats`)
  instead of periods. The number of beats of every motion-beat interval is chosen
  for the whole dance at once (:func:`.counts.plan_counts`, dynamic programming over
  the intervals): playback speed within 0.8-1.25 wherever the song allows (paper B's
  time-scale bound, :mod:`beatsync.graph.timescale`), and never faster than keeps the
  joints within the dancer's own peak speed; smooth from one interval to the next;
  dance bars (``dance_beats_per_period`` motion beats, else the dance's own phrase
  when the motion shows it clearly) starting on the music's bar lines; where no whole
  number of beats fits, an interval is merged with its neighbour or lands on a half beat
  (the report counts both). The same smooth rate of eq. 9 then lands them.
  ``beats_per_period=`` keeps one count for the median interval and proportional
  counts for the others (:func:`beats_per_unit`).
  ``mode="auto"`` uses periods when the periodicity test accepts the motion and
  falls back to beats, with a warning, when it refuses.
- ``boundaries=None``: the motion is segmented here; in ``mode="periods"`` by default
  over periods of one to eight of the song's beats (a waltz box is 6 beats, about
  4 s), so real dance cycles are found; in ``mode="auto"`` over paper A's 0.25-1.25 s,
  so dances periodic at the step level keep paper A's method and real ballroom
  figures (longer, varying) are warped on their motion beats, which aligned them
  far better with a new song on the four real dancers we have.
- ``fill="loop"``: whole periods (or beat segments) are repeated until the dance
  covers the song to its last beat (:mod:`beatsync.sync.fill`): the loop is chosen
  where the poses at its two ends are most alike (paper B's motion-graph distance),
  each pass is turned and moved on the floor to start where the previous one ended,
  and the joins are blended over 0.6 s with a continuous velocity;
  ``fill="stop"`` (paper A) ends with the last period that fits.
- The report measures what the warp did to the dance (:mod:`.quality`): playback speed
  (instantaneous and per interval, the share of output time within 0.8-1.25), joint
  speed and acceleration against the input's, each loop join's peak joint speed; a
  warning names the tempo that would fit when the song cannot be followed within the
  band. The JSON layout's root track (``center``) is resampled with the joints.
- Position-only motion (joint or marker positions, no skeleton) is resampled
  linearly; rotations by slerp.

Modules: :mod:`.warp` (eq. 9 and the warp), :mod:`.mapping` (beats per period,
meters, accent lag), :mod:`.counts` (beat counts of a whole dance), :mod:`.fill`
(looping), :mod:`.placement` (beats mode: loop, then counts), :mod:`.quality` (the
report's measurements), :mod:`.core` (:func:`synchronize`).

The residual of a boundary is measured twice in the report: on the warp as realised
by the output frames (``residual_ms``: the music time at which the resampled motion
passes the boundary pose, minus its beat) and as the distance from the beat to the
output frame nearest to that crossing, i.e. the frame that shows the boundary
(``residual_nearest_frame_ms``, at most half a frame plus the warp residual).

Notebooks: ``notebooks/paper_a_tab01_frame_counts.ipynb``,
``notebooks/paper_a_fig03_animation_frames.ipynb``.
"""

from .core import FILLS, LANDINGS, MODES, SyncResult, synchronize
from .mapping import BeatCount, accent_lag, beats_per_period, beats_per_unit
from .warp import TimeWarp, blended_rate, time_warp

__all__ = [
    "FILLS",
    "LANDINGS",
    "MODES",
    "BeatCount",
    "SyncResult",
    "TimeWarp",
    "accent_lag",
    "beats_per_period",
    "beats_per_unit",
    "blended_rate",
    "time_warp",
    "synchronize",
]
