"""Beat counts for the whole dance: how many music beats every motion-beat interval spans.

Chosen jointly by dynamic programming over the intervals (Viterbi), as paper B chooses
the time-scaling of its composed intervals (:mod:`beatsync.graph.timescale`, whose
speed bound and half-beat grid are reused), instead of ``round(interval / beat)`` one
interval at a time, which plays neighbours at very different speeds.

Event ``i`` lands on point ``k_i`` of the half-beat grid (the beats from the first on
and their midpoints); a step covers ``1 <= c <= MAX_HALF_BEATS`` half beats, from one
interval to the next or, merging two intervals no whole count fits, to the one after
(the middle motion beat is then not pinned). States ``(k, c, merged)`` keep the last
step's count so that its speed change can be charged. Cost of a path:

- speed ``s = source / music duration``: ``(log s)^2`` per second inside the band
  (narrowed by ``MARGIN``), plus ``W_OUT`` and ``W_EXCESS`` times the squared log
  distance to it per second outside, so speeds outside 0.8-1.25 go only where
  nothing else fits;
- ``W_CHANGE (log s_i - log s_{i-1})^2`` between consecutive steps;
- ``W_HALF`` per event on a half beat, ``W_MERGE`` per merge;
- with the dance's meter ``N`` and the music's bar, ``W_BAR`` per phrase start (every
  ``N``-th motion beat) off a bar line.

``end="last_beat"`` (``fill="loop"``) ends on the song's last beat after any number of
intervals; ``"last_event"`` (``fill="stop"``) with the clip's last interval (or on the
last beat if the song ends first). Times in seconds; counts in half beats inside, in
beats in the result.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..graph.timescale import DEFAULT_SCALE_BOUND, music_grid

__all__ = ["CountPlan", "plan_counts", "MAX_HALF_BEATS"]

#: longest interval, in half beats (4 beats)
MAX_HALF_BEATS = 8
#: cost per second of output outside the speed band
W_OUT = 4.0
#: cost per second per squared log distance outside the band
W_EXCESS = 200.0
#: cost of a squared log speed change between consecutive steps
W_CHANGE = 4.0
#: cost of an event landing on a half beat
W_HALF = 1.5
#: cost of merging two intervals
W_MERGE = 1.0
#: cost of a phrase start (dance bar) off a bar line of the music
W_BAR = 3.0
#: states costlier than the best by more than this are dropped (beam)
BEAM = 60.0
#: the counts aim inside the speed band narrowed by this factor at each end: the
#: smooth warp (eq. 9's blend, then the bump that lands every event on its beat,
#: between the held landings) overshoots an interval's mean speed by a few percent
#: where neighbours differ
MARGIN = 1.06


@dataclass(frozen=True)
class CountPlan:
    """The placed events of a whole dance: indices (into the events given) of those
    pinned, their music ``targets`` [s], the ``beats`` each step spans (halves allowed),
    the numbers of merges and half-beat landings, the playback speeds each step aimed
    within (``speed_band``: the lowest, the highest per step; the band narrowed by
    ``MARGIN``, its top lowered by the peak headroom), and the share of phrase starts on
    bar lines (None without meters)."""

    event_index: np.ndarray
    targets: np.ndarray
    beats: np.ndarray
    n_merged: int
    n_half: int
    speed_band: tuple[float, np.ndarray]
    phrases_on_bars: float | None = None


def _speed_cost(ls: np.ndarray, dur: np.ndarray, lo: float, hi: float) -> np.ndarray:
    """Speed cost (module docstring) of steps at log speed ``ls`` lasting ``dur`` [s]."""
    excess = np.maximum(0.0, np.maximum(ls - hi, lo - ls))
    return dur * (ls * ls + W_OUT * (excess > 0) + W_EXCESS * excess * excess)


def plan_counts(
    events: np.ndarray,
    beats: np.ndarray,
    *,
    phrase_index: np.ndarray,
    end: str = "last_beat",
    dance: int | None = None,
    bar: int | None = None,
    band: tuple[float, float] = DEFAULT_SCALE_BOUND,
    max_speed: np.ndarray | None = None,
) -> CountPlan:
    """Place motion ``events`` [s] on the song's (half) ``beats`` [s] (from the one the
    first event lands on) for the whole dance at once; ``end`` as in the module docstring.

    ``dance`` motion beats make a dance bar and ``bar`` music beats a bar; each event's
    ``phrase_index`` (its index in the clip, for a looped timeline)
    marks phrase starts (``% dance == 0``). ``max_speed`` per interval, the fastest
    playback keeping its joints within the dancer's own peak, lowers the band's top.
    """
    d = np.diff(events)
    p = d.size
    lo = np.log(band[0] * MARGIN)
    top = np.full(p, np.log(band[1] / MARGIN))
    if max_speed is not None:  # never below the band's bottom
        top = np.minimum(top, np.log(np.maximum(max_speed, band[0] * MARGIN**2)))
    grid, _ = music_grid(beats, np.zeros(beats.size - 1), 2)
    k_max = grid.size - 1
    cmax = MAX_HALF_BEATS
    phrase = np.zeros(p + 1, dtype=bool)
    if dance is not None and bar is not None:
        phrase = (np.asarray(phrase_index) % dance) == 0
    bar_ok = np.ones(k_max + 1, dtype=bool)
    if bar is not None:
        bar_ok = (np.arange(k_max + 1) % (2 * bar)) == 0
    odd = (np.arange(k_max + 1) % 2 == 1).astype(np.float64) * W_HALF

    # tables over the grid: music duration and log speed of c half beats from k
    span = np.full((k_max + 1, cmax + 1), np.nan)
    for c in range(1, cmax + 1):
        span[: k_max + 1 - c, c] = grid[c:] - grid[:-c] if c <= k_max else np.nan
    # D[i]: cost over states (k, c, m), stored sparsely per event index
    shape = (k_max + 1, cmax + 1, 2)
    cost: dict[int, np.ndarray] = {}
    back: dict[int, tuple[int, np.ndarray, np.ndarray, np.ndarray]] = {}
    start = np.full(shape, np.inf)
    start[0, 0, 0] = 0.0 if (bar is None or not phrase[0] or bar_ok[0]) else W_BAR
    cost[0] = start
    best_end = (np.inf, -1, -1, -1, -1)
    at_last: dict[int, np.ndarray] = {}  # event -> costs of (c, m) on the last beat
    furthest = (-1, 0, np.inf, 0, 0)  # (k, -event, cost, c, m): the latest grid point reached
    for i in range(p):
        cur = cost.pop(i, None)
        if cur is None or not np.isfinite(cur).any():
            continue
        if i in back:  # final now: keep the back pointers of the reached states only
            raw = np.nonzero(np.isfinite(cur).any(axis=(1, 2)))[0]
            lo_k, hi_k = int(raw[0]), int(raw[-1]) + 1
            back[i] = (lo_k, *(a[lo_k:hi_k].copy() for a in back[i][1:]))
        floor = np.min(cur)
        cur = np.where(cur <= floor + BEAM, cur, np.inf)
        ks = np.nonzero(np.isfinite(cur).any(axis=(1, 2)))[0]
        if ks.size == 0:
            continue
        k_lo, k_hi = int(ks[0]), int(ks[-1])
        sub = cur[k_lo : k_hi + 1]  # (nk, C+1, 2)
        # log speed of the step that led to each state (for the change cost)
        prev_src = np.array(
            [d[i - 1] if i >= 1 else np.nan, d[i - 2] + d[i - 1] if i >= 2 else np.nan]
        )
        kidx = np.arange(k_lo, k_hi + 1)
        cs = np.arange(cmax + 1)
        prev_k = kidx[:, None] - cs[None, :]
        prev_dur = np.where(
            (cs[None, :] >= 1) & (prev_k >= 0),
            grid[kidx][:, None] - grid[np.clip(prev_k, 0, k_max)],
            np.nan,
        )
        with np.errstate(invalid="ignore", divide="ignore"):
            prev_ls = np.log(prev_src[None, None, :] / prev_dur[:, :, None])  # (nk, C+1, 2)
        for merged, src in ((0, d[i]), (1, d[i] + d[i + 1] if i + 1 < p else np.nan)):
            if not np.isfinite(src):
                continue
            hi = top[i] if merged == 0 else min(top[i], top[i + 1])
            j = i + 1 + merged
            nxt = cost.get(j)
            if nxt is None:
                nxt = np.full(shape, np.inf)
                back[j] = (
                    0,  # offset of the first grid point stored
                    np.full(shape, -1, dtype=np.int32),
                    np.full(shape, -1, dtype=np.int8),
                    np.full(shape, -1, dtype=np.int8),
                )
            _, bk, bc, bm = back[j]
            # every count c at once: states (k, c_prev, m_prev) -> (k + c, c, merged)
            cs1 = np.arange(1, cmax + 1)
            tgt_k = kidx[:, None] + cs1[None, :]  # (nk, C)
            ok = tgt_k <= k_max
            dur = np.where(ok, span[kidx[:, None], cs1[None, :]], np.nan)
            with np.errstate(invalid="ignore"):
                ls = np.log(src / dur)
            tk = np.minimum(tgt_k, k_max)
            step = _speed_cost(ls, dur, lo, hi) + odd[tk] + W_MERGE * merged
            if bar is not None:
                step = step + W_BAR * (phrase[j] & ~bar_ok[tk])
            change = W_CHANGE * (ls[:, :, None, None] - prev_ls[:, None]) ** 2
            change = np.where(np.isfinite(prev_ls)[:, None], change, 0.0)
            tot = (sub[:, None] + change).reshape(kidx.size, cmax, -1)  # (nk, C, prev)
            arg = np.argmin(tot, axis=2)
            val = np.take_along_axis(tot, arg[:, :, None], axis=2)[:, :, 0] + step
            val = np.where(ok, val, np.inf)
            cc = np.broadcast_to(cs1, tk.shape)
            better = val < nxt[tk, cc, merged]
            if better.any():
                tkb, ccb = tk[better], cc[better]
                nxt[tkb, ccb, merged] = val[better]
                bk[tkb, ccb, merged] = np.broadcast_to(kidx[:, None], tk.shape)[better]
                bc[tkb, ccb, merged] = arg[better] // 2
                bm[tkb, ccb, merged] = arg[better] % 2
            cost[j] = nxt
            at_last[j] = nxt[k_max]
            reached = np.nonzero(np.isfinite(nxt).any(axis=(1, 2)))[0]
            if reached.size and (reached[-1], -j) > furthest[:2]:
                kf = int(reached[-1])
                c_, m_ = np.unravel_index(np.argmin(nxt[kf]), nxt[kf].shape)
                furthest = (kf, -j, float(nxt[kf, c_, m_]), int(c_), int(m_))
            if end == "last_beat":
                c_, m_ = np.unravel_index(np.argmin(nxt[k_max]), nxt[k_max].shape)
                if nxt[k_max, c_, m_] < best_end[0]:
                    best_end = (float(nxt[k_max, c_, m_]), j, k_max, int(c_), int(m_))
            elif j == p:
                a = int(np.argmin(nxt))
                if nxt.flat[a] < best_end[0]:
                    k_, c_, m_ = np.unravel_index(a, shape)
                    best_end = (float(nxt.flat[a]), j, int(k_), int(c_), int(m_))
    if end == "last_event" and not np.isfinite(best_end[0]):
        # the song ends first: the furthest event that reached the last beat
        for j in sorted(at_last, reverse=True):
            cand = at_last[j]
            if np.isfinite(cand).any():
                c_, m_ = np.unravel_index(np.argmin(cand), cand.shape)
                best_end = (float(cand[c_, m_]), j, k_max, int(c_), int(m_))
                break
    if not np.isfinite(best_end[0]):
        # too few events to reach the song's end: stop at the latest grid point reached
        kf, mj, val, c_, m_ = furthest
        best_end = (val, -mj, kf, c_, m_)
    _, j, k, c, m = best_end
    ev, gk = [j], [k]
    while j > 0:
        off, bk, bc, bm = back[j]
        pk, pc, pm = (int(a[k - off, c, m]) for a in (bk, bc, bm))
        j = j - 1 - m
        k, c, m = pk, pc, pm
        ev.append(j)
        gk.append(k)
    ev_a = np.array(ev[::-1], dtype=np.int64)
    gk_a = np.array(gk[::-1], dtype=np.int64)
    step_top = np.array([top[a:b].min() for a, b in zip(ev_a[:-1], ev_a[1:], strict=True)])
    return CountPlan(
        event_index=ev_a,
        targets=grid[gk_a],
        beats=np.diff(gk_a) / 2.0,
        n_merged=int(np.count_nonzero(np.diff(ev_a) == 2)),
        n_half=int(np.count_nonzero(gk_a % 2 == 1)),
        phrases_on_bars=(
            float(np.mean(bar_ok[gk_a[phrase[ev_a]]])) if bar and phrase[ev_a].any() else None
        ),
        speed_band=(float(np.exp(lo)), np.exp(step_top)),
    )
