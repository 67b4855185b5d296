"""Beat-synchronous resampling of periodic motion (paper A, section 5).

Every motion period is mapped to ``m`` consecutive music beats, played at the rate
that makes it last as long as them; the per-period rates are blended into a smooth
rate (eq. 9) and integrated into a monotonic time warp on which the motion is
resampled (slerp for rotations, linear for positions).

Data contract: event times (period ``boundaries``, music ``beats``) are increasing
float64 seconds, boundaries in the source's timeline, beats in the music's. Output
frame ``k`` plays at music time ``k / out_fps``; frames before the first warped frame
hold the first pose. ``rate = target / source`` (> 1 slows down); the report's
playback speed is its inverse.

Method (what the paper leaves open, our choices)
    1. ``m = max(1, round(P / b))`` (:func:`beats_per_period`; ``P`` mean period,
       ``b`` median beat); with meters, a count that respects both (a 3-beat waltz
       step spans 3 or 6 beats, never 5), the dance's winning with a warning when
       they do not fit.
    2. Period ``i`` lands on ``B_i = beats[first_beat + i m]``: ``r_i = (B_{i+1} - B_i)
       / (s_{i+1} - s_i)``.
    3. Eq. 9, our reading: ``r(t) = sum_i w_i(t) r_i / sum_i w_i(t)``, Gaussian weights
       of width ``delta`` (default the mean period) around the period centres.
    4. The blend alone misses the beats, so each period's rate is corrected by a
       Tukey bump ``r (1 + a_i h(u))`` that vanishes at its ends, ``a_i`` chosen so the
       period lasts exactly its beats (a period needing ``a_i <= -0.9`` is scaled
       instead; the report counts these).
    5. The warp integrates the rate (knots at every boundary, so boundaries land to
       rounding), held constant before the first and after the last boundary.
       Periods the music has no beats for are dropped.
    6. ``phase_offset`` lands boundaries that long after their beats; ``land="accents"``
       measures the dancer's mean lag behind the beats and lands again without it.

Beyond the paper (real dances)
    - ``mode="beats"``: a dance that is not strictly periodic is warped on its own
      motion beats (:func:`beatsync.motion_beats.kinematic_beats`). The beats of every
      interval are chosen for the whole dance at once (:mod:`.counts`): speed within
      0.8-1.25 where the song allows (paper B's bound) and never faster than keeps the
      joints within the dancer's own peak, smooth, dance bars on the music's bar lines
      (``dance_beats_per_period``, else the dance's own phrase when clear), merging an
      interval or landing on a half beat where no whole count fits. The rate is held
      for ``LANDING_HOLD`` on both sides of every landed motion beat (a speed minimum),
      never so fast that a shallow dip fills in, and each landing is moved to where the
      output shows its minimum (:mod:`.landing`), so the stop stays on its beat.
      ``mode="auto"`` uses periods when the periodicity test accepts the motion, else
      beats with a warning.
    - ``boundaries=None`` segments here: in ``"periods"`` over one to eight of the
      song's beats (real dance cycles), in ``"auto"`` over paper A's 0.25-1.25 s, so
      ballroom figures go to ``"beats"``, which aligned the real dancers far better.
    - ``fill="loop"`` repeats a span chosen where the poses at its ends are most alike
      (:mod:`.fill`), turned and moved to go on from the previous pass, blended over
      0.6 s, up to the last beat or on to ``song_end``; ``fill="stop"`` (paper A) ends
      with the last period that fits.
    - The report (:class:`SyncResult`, :mod:`.quality`) says what the warp did to the
      dance. The JSON layout's ``center`` is resampled with the joints.

Modules: :mod:`.warp` (eq. 9), :mod:`.mapping` (beats per period, meters, accent lag),
:mod:`.counts` (whole-dance counts), :mod:`.fill` (loops), :mod:`.placement` (beats
mode), :mod:`.landing` (the landings a viewer sees), :mod:`.quality` (report),
:mod:`.core` (:func:`synchronize`).

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
