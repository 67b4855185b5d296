"""Dataset pieces of beat evaluation: pairing, annotations, the log, preparing workers."""

import json
import re

import numpy as np
import pandas as pd
import pytest

from beatsync import io
from beatsync.errors import ParameterError
from beatsync.study.beat_dataset import (
    TrackLog,
    evaluate_track,
    find_tracks,
    read_annotation,
    summarize_dataset,
)
from beatsync.synth.audio import beat_times, click_track

SR = 22050


def _touch_audio(path):
    path.parent.mkdir(parents=True, exist_ok=True)
    io.write_audio(path, np.zeros(100, dtype=np.float32), SR)


def test_pairing_prefers_same_relative_path_then_unique_stem(tmp_path):
    a, b = tmp_path / "audio", tmp_path / "notes"
    for rel in ("x.wav", "g1/y.wav", "g2/y.flac", "g2/z.mp3", "g2/lonely.wav", "w.wav", "w.flac"):
        _touch_audio(a / rel) if not rel.endswith(".mp3") else None
    (a / "g2" / "z.mp3").write_bytes(b"not read while pairing")
    (a / "readme.txt").write_text("ignored")
    for rel in ("x.beats", "g1/y.beats", "g2/y.beats", "z.beats", "w.beats"):
        (b / rel).parent.mkdir(parents=True, exist_ok=True)
        (b / rel).write_text("0.5\n1.0\n")
    found = find_tracks(a, b)
    pairs = {t.key: (t.group, t.annotation.relative_to(b).as_posix()) for t in found.tracks}
    assert pairs == {
        "x": (".", "x.beats"),
        "g1/y": ("g1", "g1/y.beats"),
        "g2/y": ("g2", "g2/y.beats"),  # same relative path wins over the ambiguous stem
        "g2/z": ("g2", "z.beats"),  # flat annotations: the only z.beats
        "w": (".", "w.beats"),
    }
    # no annotation; and w.wav beside w.flac: one key, the second file is listed apart
    assert [p.name for p in found.unmatched] == ["lonely.wav"]
    assert [p.name for p in found.duplicates] == ["w.wav"]
    assert found.shared == {}


def test_one_flat_annotation_is_not_shared_by_two_recordings(tmp_path):
    # a/x.wav and b/x.wav were both scored against the flat x.beats (F 0.16 for the one
    # it did not belong to, without a word)
    a, b = tmp_path / "audio", tmp_path / "notes"
    for rel in ("a/x.wav", "b/x.wav", "a/y.wav"):
        _touch_audio(a / rel)
    b.mkdir()
    for name in ("x.beats", "y.beats"):
        (b / name).write_text("0.5\n1.0\n")
    found = find_tracks(a, b)
    assert [t.key for t in found.tracks] == ["a/y"]
    assert found.shared == {b / "x.beats": [a / "a" / "x.wav", a / "b" / "x.wav"]}
    # the one x.beats sits at a/x's relative path: a/x keeps it, b/x may not borrow it
    (b / "x.beats").unlink()
    (b / "a").mkdir()
    (b / "a" / "x.beats").write_text("0.5\n1.0\n")
    found = find_tracks(a, b)
    assert [(t.key, t.annotation) for t in found.tracks] == [
        ("a/x", b / "a" / "x.beats"),
        ("a/y", b / "y.beats"),
    ]
    assert found.shared == {b / "a" / "x.beats": [a / "b" / "x.wav"]}


def test_ambiguous_stem_is_unmatched(tmp_path):
    a, b = tmp_path / "audio", tmp_path / "notes"
    _touch_audio(a / "song.wav")
    for sub in ("s1", "s2"):
        (b / sub).mkdir(parents=True)
        (b / sub / "song.beats").write_text("0.5\n")
    (b / "other.beats").write_text("0.5\n")
    with pytest.raises(ParameterError, match="song.beats"):
        find_tracks(a, b)


def test_annotation_folder_is_a_file(tmp_path):
    _touch_audio(tmp_path / "a" / "x.wav")
    (tmp_path / "n").write_text("x")
    with pytest.raises(ParameterError, match=re.escape(str(tmp_path / "n"))):
        find_tracks(tmp_path / "a", tmp_path / "n")


def test_read_annotation_one_or_two_columns(tmp_path):
    p = tmp_path / "a.beats"
    p.write_text("# beats\n0.50\t1\n1.00\t2\n\n1.50\t3\n")
    np.testing.assert_allclose(read_annotation(p), [0.5, 1.0, 1.5])
    p.write_text("0.5\n1.0\n1.5\n")
    np.testing.assert_allclose(read_annotation(p), [0.5, 1.0, 1.5])


@pytest.mark.parametrize(
    "text, match",
    [
        ("500\n1000\n1500\n2000\n", "2000 .* milliseconds"),
        ("43\n86\n129\n172\n", "172 .* frame indices"),
        ("0.5\nabc\n", "line 2: 'abc'"),
        ("1.0\n0.5\n", r"#1 \(0\.5 s\)"),
        ("# nothing\n", "a.beats is empty"),
    ],
)
def test_read_annotation_refuses(tmp_path, text, match):
    p = tmp_path / "a.beats"
    p.write_text(text)
    with pytest.raises(ParameterError, match=match):
        read_annotation(p)


def test_evaluate_track_records_failures_instead_of_raising(tmp_path):
    ref = beat_times(120, duration=6.0, start=0.3)
    good = io.write_audio(tmp_path / "good.wav", click_track(ref, sr=SR, duration=6.0), SR)
    row = evaluate_track(str(good), ref, method="psf", min_beat_time=0.0, name="good")
    assert row["status"] == "ok" and row["F-measure"] >= 0.95 and row["octave"] == "correct"
    assert row["n_ref"] == ref.size and len(row["beats"]) == row["n_est"]
    json.dumps(io.to_jsonable(row), allow_nan=False)  # one JSON line
    (tmp_path / "bad.wav").write_text("not audio")
    bad = evaluate_track(str(tmp_path / "bad.wav"), ref, method="psf", min_beat_time=0.0, name="b")
    assert bad["status"] == "error" and "cannot read" in bad["error"]
    short = io.write_audio(tmp_path / "short.wav", click_track(ref[:1], sr=SR, duration=0.5), SR)
    row = evaluate_track(str(short), ref, method="psf", min_beat_time=0.0, name="s")
    assert row["status"] == "error" and "0.500 s long" in row["error"]


def test_evaluate_track_records_the_tempo_range_as_checked(tmp_path):
    ref = beat_times(120, duration=6.0, start=0.3)
    good = io.write_audio(tmp_path / "good.wav", click_track(ref, sr=SR, duration=6.0), SR)

    def row(**tempo):
        return evaluate_track(str(good), ref, method="psf", min_beat_time=0.0, name="g", **tempo)

    told = row(min_bpm=40, max_bpm="75")  # the default min_bpm is the same as none
    assert told["status"] == "ok" and (told["min_bpm"], told["max_bpm"]) == (None, 75.0)
    assert 55 <= told["tempo_est"] <= 65  # the half tempo, inside the range
    bad = row(min_bpm=120, max_bpm=90)
    assert bad["status"] == "error"
    assert "min_bpm 120 must be smaller than max_bpm 90" in bad["error"]
    # a bound that is not a number is recorded as given; the summary still builds, and
    # states the settings of the scored rows (failed ones are re-run with others)
    nan = row(min_bpm="abc", max_bpm=90)
    assert nan["status"] == "error" and "min_bpm" in nan["error"]
    s = summarize_dataset([nan, told]).set_index(["method", "group"])
    assert s.loc[("psf", "all"), "max_bpm"] == 75.0 and s.loc[("psf", "all"), "failed"] == 1
    s = summarize_dataset([nan]).set_index(["method", "group"])
    assert pd.isna(s.loc[("psf", "all"), "min_bpm"]) and s.loc[("psf", "all"), "max_bpm"] == 90


def test_track_log_appends_and_skips_a_torn_line(tmp_path):
    log = TrackLog(tmp_path / "tracks.jsonl")
    assert log.rows() == []
    log.append({"key": "a", "method": "psf", "v": 1.0})
    with open(log.path, "a") as fh:
        fh.write('{"key": "b", "meth')  # a crash in the middle of a line
    log.append({"key": "c", "method": "psf", "v": float("nan")})
    log.append({"key": "a", "method": "psf", "v": 2.0})
    assert [r["key"] for r in log.rows()] == ["a", "c", "a"]
    assert log.latest()[("psf", "a")]["v"] == 2.0
    assert log.latest()[("psf", "c")]["v"] is None
    log.rewrite([{"key": "z", "method": "librosa"}])
    assert [r["key"] for r in log.rows()] == ["z"]


def test_summarize_dataset_per_folder_and_all():
    rows = [
        {"key": "g/a", "group": "g", "method": "psf", "status": "ok", "F-measure": 1.0,
         "octave": "correct"},
        {"key": "g/b", "group": "g", "method": "psf", "status": "ok", "F-measure": 0.5,
         "octave": "double"},
        {"key": "h/c", "group": "h", "method": "psf", "status": "error", "error": "silent"},
        {"key": "h/d", "group": "h", "method": "psf", "status": "ok", "F-measure": 0.0,
         "octave": "other"},
    ]  # fmt: skip
    s = summarize_dataset(rows).set_index("group")
    assert s.loc["g", "tracks"] == 2 and s.loc["g", "F-measure"] == pytest.approx(0.75)
    assert s.loc["h", "failed"] == 1 and s.loc["h", "F-measure"] == pytest.approx(0.0)
    assert s.loc["all", "tracks"] == 4 and s.loc["all", "failed"] == 1
    assert s.loc["all", "F-measure"] == pytest.approx(0.5)
    assert s.loc["all", "octave errors"] == 1 and s.loc["all", "other tempo"] == 1
    assert pd.isna(s.loc["all", "Goto"])  # a metric no row has
    one_folder = summarize_dataset([dict(r, group=".") for r in rows])
    assert list(one_folder["group"]) == ["all"]


def test_summary_states_the_settings_the_rows_were_scored_with():
    rows = [
        {"key": "g/a", "group": "g", "method": "psf", "status": "ok", "min_beat_time": 5.0,
         "min_bpm": 75.0, "max_bpm": None},
        {"key": "h/b", "group": "h", "method": "psf", "status": "ok", "min_beat_time": 5.0,
         "min_bpm": None, "max_bpm": None},
        {"key": "h/c", "group": "h", "method": "librosa", "status": "ok"},  # an old log
    ]  # fmt: skip
    s = summarize_dataset(rows).set_index(["method", "group"])
    assert s.loc[("psf", "g"), ["min_beat_time", "min_bpm"]].tolist() == [5.0, 75.0]
    assert pd.isna(s.loc[("psf", "g"), "max_bpm"]) and pd.isna(s.loc[("psf", "h"), "min_bpm"])
    assert s.loc[("psf", "all"), "min_beat_time"] == 5.0
    assert pd.isna(s.loc[("psf", "all"), "min_bpm"])  # the rows differ: not one range
    assert s.loc[("librosa", "all"), ["min_beat_time", "min_bpm", "max_bpm"]].isna().all()


_PREPARED: list[tuple[str, str, float, float]] = []


async def _slow_prepare(name, dask_worker=None):
    # module level: dask pickles it by reference, even in-process. A coroutine: the
    # in-process workers share one event loop, where two plain calls could not overlap
    import asyncio
    import time

    start = time.monotonic()
    await asyncio.sleep(0.3)
    _PREPARED.append((name, dask_worker.address, start, time.monotonic()))


def test_workers_are_prepared_one_at_a_time_for_librosa(monkeypatch):
    # a fresh install's workers compiling librosa's numba cache together can crash
    from beatsync import other_trackers
    from beatsync.cluster import dask_client
    from beatsync.study.beat_dataset import _prepare_workers

    _PREPARED.clear()
    monkeypatch.setattr(other_trackers, "prepare", _slow_prepare)
    with dask_client(n_workers=2, processes=False) as client:
        _prepare_workers(client, "psf")
        assert _PREPARED == []
        _prepare_workers(client, "librosa")
    spans = sorted(_PREPARED, key=lambda s: s[2])
    assert [s[0] for s in spans] == ["librosa", "librosa"]
    assert spans[0][1] != spans[1][1]  # each worker once
    assert spans[1][2] >= spans[0][3]  # never two at once


def test_a_rows_warning_gives_advice_the_dataset_command_can_follow(tmp_path):
    # the tracker's no-clear-pulse warning says "give it with bpm= (--bpm)": evaluate
    # beats has no --bpm, but a tempo range
    rng = np.random.default_rng(3)
    audio = io.write_audio(tmp_path / "noise.wav", 0.1 * rng.standard_normal(10 * SR), SR)
    row = evaluate_track(
        str(audio), np.arange(0.5, 9.5, 0.5), method="psf", min_beat_time=0.0, name="noise"
    )
    assert row["status"] == "ok"
    assert "no clear pulse" in row["warning"]
    assert "--bpm" not in row["warning"]
    assert "a tempo range (--min-bpm, --max-bpm) narrows the search" in row["warning"]


def test_each_thread_collects_its_own_warnings():
    # warnings.catch_warnings swaps process-wide state: with two tracks on the threads
    # of one worker, the first one's warning landed in the second one's record
    import threading

    from beatsync.errors import BeatsyncWarning, collect_warnings, warn

    step = threading.Barrier(2)
    seen = {}

    def first():
        with collect_warnings() as mine:
            step.wait()  # both inside their blocks
            step.wait()
            warn("first")
            step.wait()
        seen["first"] = list(mine)

    def second():
        step.wait()
        with collect_warnings() as mine:
            step.wait()
            step.wait()
            warn("second")
        seen["second"] = list(mine)

    threads = [threading.Thread(target=first), threading.Thread(target=second)]
    for t in threads:
        t.start()
    for t in threads:
        t.join(timeout=30)
    assert seen == {"first": ["first"], "second": ["second"]}
    with collect_warnings() as outer:
        with collect_warnings() as inner:
            warn("inner")
        warn("outer")
    assert (outer, inner) == (["outer"], ["inner"])
    with pytest.warns(BeatsyncWarning, match="issued"):  # outside a block: a warning
        warn("issued")


def test_silenced_warnings_are_neither_issued_nor_collected_and_only_in_their_thread():
    # code that expects a warning drops it with errors.silenced (thread-local); with
    # warnings.simplefilter (process-wide) a collecting block recorded it all the same
    import threading
    import warnings

    from beatsync.errors import collect_warnings, silenced, warn
    from beatsync.evaluate.composition import quality_proxies

    with collect_warnings() as got:
        with silenced():
            warn("dropped")
            with silenced():
                warn("dropped too")
            warn("still dropped")
        warn("kept")
    assert got == ["kept"]
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # nothing issued either
        with silenced():
            warn("dropped")
    # another thread's warning while this one is silenced: issued as usual
    other = []

    def elsewhere():
        with collect_warnings() as mine:
            warn("other thread")
        other.extend(mine)

    with silenced():
        t = threading.Thread(target=elsewhere)
        t.start()
        t.join(timeout=30)
    assert other == ["other thread"]
    # a library step that drops its parts' warnings (no motion beats to align: the
    # proxies say 0 themselves); they were collected before
    with collect_warnings() as got:
        scores = quality_proxies(
            motion_beats=np.array([]),
            music_beats=np.array([0.5, 1.0, 1.5]),
            span=(0.0, 2.0),
            positions=np.zeros((50, 3, 3)),
            foot_positions=np.zeros((50, 2, 3)),
            fps=25.0,
            transition_times=np.array([]),
            motion_intensity=np.ones(3),
            music_level=np.ones(3),
        )
    assert got == [] and scores["alignment_motion"] == 0.0


def test_rows_keep_their_own_warnings_on_a_threaded_worker(tmp_path):
    from concurrent.futures import ThreadPoolExecutor

    rng = np.random.default_rng(5)
    ref = beat_times(120, duration=10.0, start=0.3)
    jobs = []
    for i in range(6):
        noise = io.write_audio(tmp_path / f"n{i}.wav", 0.1 * rng.standard_normal(10 * SR), SR)
        clicks = io.write_audio(tmp_path / f"c{i}.wav", click_track(ref, sr=SR, duration=10.0), SR)
        jobs += [(str(noise), f"n{i}"), (str(clicks), f"c{i}")]
    with ThreadPoolExecutor(4) as pool:
        rows = list(
            pool.map(
                lambda job: evaluate_track(
                    job[0], ref, method="psf", min_beat_time=0.0, name=job[1]
                ),
                jobs,
            )
        )
    for row in rows:
        assert row["status"] == "ok"
        assert ("no clear pulse" in row["warning"]) == row["key"].startswith("n"), row
