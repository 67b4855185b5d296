"""End-to-end tests of ``beatsync evaluate beats`` (dataset scoring on Dask)."""

from __future__ import annotations

import json
import re
import shutil
import time

import numpy as np
import pandas as pd
import pytest

from beatsync import cluster, datasets, io
from beatsync.cli import build_parser, main
from beatsync.errors import ParameterError
from beatsync.study import beat_dataset
from beatsync.study.beat_dataset import TrackLog, find_tracks
from beatsync.synth.audio import beat_times, click_track, drum_pattern

SR = 22050
GOOD = ["rock/drums_96", "rock/drums_132", "clicks/click_110", "sample"]


@pytest.fixture(scope="module")
def dataset(tmp_path_factory):
    """Synthetic songs in two folders, the real madmom sample, a silent and a broken file.

    Annotations are flat (as in most datasets); one audio file has none.
    """
    d = tmp_path_factory.mktemp("dataset")
    audio, notes = d / "audio", d / "annotations"
    for sub in ("rock", "clicks"):
        (audio / sub).mkdir(parents=True)
    notes.mkdir()
    for bpm in (96, 132):
        ref = beat_times(bpm, duration=8.0, start=0.3)
        y = drum_pattern(ref, sr=SR, duration=8.0, seed=bpm)
        io.write_audio(audio / "rock" / f"drums_{bpm}.wav", y, SR)
        io.write_beats(notes / f"drums_{bpm}.beats", ref)
    ref = beat_times(110, duration=8.0, start=0.45)
    io.write_audio(audio / "clicks" / "click_110.flac", click_track(ref, sr=SR, duration=8.0), SR)
    # two columns (time, beat in bar), as the real annotation is written
    (notes / "click_110.beats").write_text(
        "".join(f"{t:.4f}\t{i % 4 + 1}\n" for i, t in enumerate(ref))
    )
    shutil.copy(datasets.path("audio/madmom/sample.wav"), audio / "sample.wav")
    shutil.copy(datasets.path("audio/madmom/sample.beats"), notes / "sample.beats")
    io.write_audio(audio / "silent.wav", np.zeros(4 * SR, dtype=np.float32), SR)
    io.write_beats(notes / "silent.beats", np.arange(0.5, 4.0, 0.5))
    (audio / "broken.wav").write_bytes(b"RIFF....WAVEfmt not really audio")
    io.write_beats(notes / "broken.beats", np.arange(0.5, 4.0, 0.5))
    io.write_audio(audio / "rock" / "orphan.wav", np.zeros(SR, dtype=np.float32), SR)
    return audio, notes


def _click_songs(folder, n, *, seconds, bpm_step=5.0):
    """``n`` click tracks ``sNN.wav`` from 100 BPM up, each with its ``.beats``."""
    folder.mkdir()
    for i in range(n):
        ref = beat_times(100.0 + bpm_step * i, duration=seconds, start=0.2)
        io.write_audio(folder / f"s{i:02d}.wav", click_track(ref, sr=SR, duration=seconds), SR)
        io.write_beats(folder / f"s{i:02d}.beats", ref)
    return folder


def _argv(dataset, out, *extra):
    audio, notes = dataset
    return [
        "evaluate", "beats", "--audio", str(audio), "--annotations", str(notes),
        "--out", str(out), *extra,
    ]  # fmt: skip


def _run(argv, capsys):
    code = main(argv)
    cap = capsys.readouterr()
    return code, cap.out, cap.err


@pytest.mark.slow
def test_end_to_end_two_local_workers(dataset, tmp_path, capsys):
    out = tmp_path / "results"
    code, stdout, err = _run(_argv(dataset, out, "--workers", "2", "--json"), capsys)
    assert code == 0, err
    res = json.loads(stdout)
    assert res["tracks"] == 6 and res["scored_now"] == 6 and res["skipped"] == 0
    assert res["unmatched"] == [str(dataset[0] / "rock" / "orphan.wav")]
    assert "orphan.wav" in err and "without an annotation" in err
    failed = {f["key"]: f["error"] for f in res["failed"]}
    assert set(failed) == {"silent", "broken"}
    assert "silent" in failed["silent"]
    assert "cannot read" in failed["broken"]
    tracks = pd.read_csv(out / "tracks.csv").set_index("key")
    ok = tracks[tracks["status"] == "ok"]
    assert sorted(ok.index) == sorted(GOOD)
    for key in ("rock/drums_96", "rock/drums_132", "clicks/click_110"):
        assert ok.loc[key, "F-measure"] >= 0.9, key
        assert ok.loc[key, "octave"] == "correct", key
    # the real recording: 4 annotated beats, scored whatever the tracker does
    assert ok.loc["sample", "n_ref"] == 4
    assert 0.0 <= ok.loc["sample", "F-measure"] <= 1.0
    summary = pd.read_csv(out / "summary.csv", keep_default_na=False)
    assert set(summary["group"]) == {".", "rock", "clicks", "all"}
    every = summary[summary["group"] == "all"].iloc[0]
    assert every["tracks"] == 6 and every["failed"] == 2
    assert every["F-measure"] == pytest.approx(ok["F-measure"].mean())
    rock = summary[summary["group"] == "rock"].iloc[0]
    assert rock["tracks"] == 2 and rock["failed"] == 0
    rows = TrackLog(out / "tracks.jsonl").rows()
    assert len(rows) == 6
    beats = {r["key"]: r["beats"] for r in rows if r["status"] == "ok"}
    assert len(beats["rock/drums_96"]) == ok.loc["rock/drums_96", "n_est"]


def test_rerun_skips_finished_tracks_and_force_reruns(dataset, scheduler, tmp_path, capsys):
    out = tmp_path / "results"
    code, stdout, err = _run(_argv(dataset, out, "--scheduler", scheduler, "--json"), capsys)
    assert code == 0, err
    first = TrackLog(out / "tracks.jsonl").rows()
    assert len(first) == 6
    # the rerun re-tries only the two failures, without touching the scored rows
    code, stdout, _ = _run(_argv(dataset, out, "--scheduler", scheduler, "--json"), capsys)
    res = json.loads(stdout)
    assert (res["scored_now"], res["skipped"]) == (2, 4)
    assert TrackLog(out / "tracks.jsonl").rows()[:6] == first
    code, stdout, _ = _run(
        _argv(dataset, out, "--scheduler", scheduler, "--force", "--json"), capsys
    )
    res = json.loads(stdout)
    assert (res["scored_now"], res["skipped"]) == (6, 0)
    assert len(TrackLog(out / "tracks.jsonl").rows()) == 6  # --force replaced the old rows


def _copy_dataset(dataset, tmp_path):
    audio, notes = tmp_path / "audio", tmp_path / "annotations"
    shutil.copytree(dataset[0], audio)
    shutil.copytree(dataset[1], notes)
    return audio, notes


def test_resume_reruns_a_track_whose_audio_or_annotation_changed(
    dataset, scheduler, tmp_path, capsys
):
    # a resume kept a row scored on another file or against an edited annotation
    ds = _copy_dataset(dataset, tmp_path)
    out = tmp_path / "results"
    where = ["--scheduler", scheduler, "--json"]
    assert _run(_argv(ds, out, *where), capsys)[0] == 0
    before = {r["key"]: r for r in TrackLog(out / "tracks.jsonl").latest().values()}
    shifted = io.read_beats(ds[1] / "drums_96.beats") + 0.25  # the annotation edited
    io.write_beats(ds[1] / "drums_96.beats", shifted)
    ref = beat_times(150, duration=8.0, start=0.3)  # another song under the same name
    io.write_audio(ds[0] / "rock" / "drums_132.wav", click_track(ref, sr=SR, duration=6.0), SR)
    code, stdout, err = _run(_argv(ds, out, *where), capsys)
    assert code == 0, err
    res = json.loads(stdout)
    assert res["changed"] == 2 and res["scored_now"] == 4 and res["skipped"] == 2
    after = {r["key"]: r for r in TrackLog(out / "tracks.jsonl").latest().values()}
    assert after["rock/drums_96"]["F-measure"] < before["rock/drums_96"]["F-measure"]
    assert after["rock/drums_132"]["audio_seconds"] == pytest.approx(6.0)
    assert after["clicks/click_110"] == before["clicks/click_110"]
    code, stdout, _ = _run(_argv(ds, out, *where[:2]), capsys)
    assert "2 scored before and run again" not in stdout and "4 already scored" in stdout


def test_resume_through_another_path_to_the_same_files(
    dataset, scheduler, tmp_path, capsys, monkeypatch
):
    # the folder given relative, then absolute: every track was re-run as "changed"
    ds = _copy_dataset(dataset, tmp_path)
    monkeypatch.chdir(tmp_path)
    out = tmp_path / "results"
    where = ["--scheduler", scheduler, "--json"]
    relative = (ds[0].relative_to(tmp_path), ds[1].relative_to(tmp_path))
    assert _run(_argv(relative, out, *where), capsys)[0] == 0
    code, stdout, err = _run(_argv(ds, out, *where), capsys)
    res = json.loads(stdout)
    assert (res["changed"], res["skipped"]) == (0, 4), err


def test_force_on_some_tracks_keeps_the_others(dataset, scheduler, tmp_path, capsys):
    # --force dropped every row of the method, also of tracks outside the run
    ds = _copy_dataset(dataset, tmp_path)
    out = tmp_path / "results"
    assert _run(_argv(ds, out, "--scheduler", scheduler), capsys)[0] == 0
    before = TrackLog(out / "tracks.jsonl").latest()
    sub = tmp_path / "sub"
    (sub / "rock").mkdir(parents=True)
    shutil.copy(ds[0] / "rock" / "drums_96.wav", sub / "rock")
    argv = ["evaluate", "beats", "--audio", str(sub), "--annotations", str(ds[1])]
    code, _, err = _run([*argv, "--out", str(out), "--scheduler", scheduler, "--force"], capsys)
    assert code == 0, err
    after = TrackLog(out / "tracks.jsonl").latest()
    assert set(after) == set(before)  # the same key, rock/drums_96, re-run
    assert after[("psf", "rock/drums_96")]["audio"] == str(sub / "rock" / "drums_96.wav")
    assert len(TrackLog(out / "tracks.jsonl").rows()) == len(after)  # compacted
    table = pd.read_csv(out / "tracks.csv")
    assert len(table) == len(after)
    # with other settings, rows of tracks outside the run would bind every resume: dropped
    extra = ["--scheduler", scheduler, "--force", "--min-beat-time", "1"]
    assert _run([*argv, "--out", str(out), *extra], capsys)[0] == 0
    assert set(TrackLog(out / "tracks.jsonl").latest()) == {("psf", "rock/drums_96")}


def test_interrupted_force_keeps_the_earlier_rows(
    dataset, scheduler, tmp_path, capsys, monkeypatch
):
    # --force rewrote the record before any work: Ctrl-C then lost every earlier row
    out = tmp_path / "results"
    where = ["--scheduler", scheduler]
    assert _run(_argv(dataset, out, *where), capsys)[0] == 0
    before = TrackLog(out / "tracks.jsonl").latest()
    real_append = TrackLog.append

    written = []

    def append_then_interrupt(self, *rows):
        real_append(self, *rows)
        written.extend(rows)
        raise KeyboardInterrupt

    monkeypatch.setattr(TrackLog, "append", append_then_interrupt)
    code, _, err = _run(_argv(dataset, out, *where, "--force"), capsys)
    assert code == 130, err
    after = TrackLog(out / "tracks.jsonl").latest()
    assert set(after) == set(before)
    assert 1 <= len(written) < 6  # the first group finished, not the run
    assert len(TrackLog(out / "tracks.jsonl").rows()) == len(before) + len(written)


@pytest.mark.parametrize(
    "cluster",
    ["scheduler", pytest.param("two local workers", marks=pytest.mark.slow)],
)
def test_resume_after_interrupted_run(dataset, cluster, request, tmp_path, capsys, monkeypatch):
    """Ctrl-C after three tracks, on an existing cluster and on a local cluster of two
    worker processes (whose shutdown must not lose the rows already written)."""
    if cluster == "scheduler":
        where = ["--scheduler", request.getfixturevalue("scheduler")]
    else:
        where = ["--workers", "2"]
    out = tmp_path / "results"
    real_append = TrackLog.append
    calls = []

    def append_then_interrupt(self, *rows):
        real_append(self, *rows)
        calls.extend(row["key"] for row in rows)
        if len(calls) >= 3:
            raise KeyboardInterrupt  # Ctrl-C while the other tracks are in flight

    monkeypatch.setattr(TrackLog, "append", append_then_interrupt)
    code, _, err = _run(_argv(dataset, out, *where), capsys)
    assert code == 130
    assert "interrupted by SIGINT; the finished tracks are recorded in" in err
    assert "run the same command again" in err
    assert not (out / "summary.csv").exists()
    done = TrackLog(out / "tracks.jsonl").rows()
    assert [r["key"] for r in done] == calls
    # a torn last line (a crash while writing) is skipped, not fatal
    with open(out / "tracks.jsonl", "a") as fh:
        fh.write('{"key": "rock/drums_96", "meth')
    monkeypatch.setattr(TrackLog, "append", real_append)
    code, stdout, err = _run(_argv(dataset, out, *where, "--json"), capsys)
    assert code == 0, err
    res = json.loads(stdout)
    ok_before = sum(r["status"] == "ok" for r in done)
    assert res["skipped"] == ok_before and res["scored_now"] == 6 - ok_before
    assert res["tracks"] == 6 and len(res["failed"]) == 2
    table = pd.read_csv(out / "tracks.csv")
    assert sorted(table.loc[table["status"] == "ok", "key"]) == sorted(GOOD)


def test_library_entry_in_process_threads(dataset, tmp_path, monkeypatch):
    # the tracks' warnings.catch_warnings blocks, interleaved on threads of this process,
    # could leave its (process-wide) filters changed: here each track changes them
    import warnings

    real_track = beat_dataset.evaluate_track
    changed = []

    def track_and_change_the_filters(*args, **kwargs):
        row = real_track(*args, **kwargs)
        warnings.simplefilter("ignore")
        changed.append(row["key"])
        return row

    monkeypatch.setattr(beat_dataset, "evaluate_track", track_and_change_the_filters)
    filters = list(warnings.filters)
    found = find_tracks(*dataset)
    assert [t.key for t in found.tracks] == sorted(t.key for t in found.tracks)
    assert {t.group for t in found.tracks} == {".", "rock", "clicks"}
    good = [t for t in found.tracks if t.key in ("rock/drums_96", "clicks/click_110")]
    run = beat_dataset.evaluate_dataset(
        good, tmp_path, method="librosa", n_workers=1, processes=False
    )
    assert list(run.tracks["key"]) == ["clicks/click_110", "rock/drums_96"]
    assert (run.tracks["status"] == "ok").all()
    assert (run.tracks["F-measure"] >= 0.9).all()
    assert run.files["summary"].is_file()
    assert sorted(changed) == ["clicks/click_110", "rock/drums_96"]  # each track changed them
    assert warnings.filters == filters


def test_tracks_go_to_the_workers_in_groups_of_decreasing_size():
    todo = list(range(40))
    groups = beat_dataset._groups(todo, 2)
    assert [len(g) for g in groups] == [8, 8, 8, 8, 4, 2, 1, 1]
    assert [t for g in groups for t in g] == todo  # every track once, in order
    assert [len(g) for g in beat_dataset._groups(todo[:5], 2)] == [3, 1, 1]
    assert [len(g) for g in beat_dataset._groups(todo[:3], 8)] == [1, 1, 1]
    assert [len(g) for g in beat_dataset._groups(todo[:20], 0)] == [8, 8, 4]  # no worker yet
    assert beat_dataset._groups([], 2) == []


def test_the_longest_tracks_go_to_the_workers_first(tmp_path):
    from beatsync.study.beat_dataset import Track

    tracks = [Track("gone", ".", tmp_path / "gone.wav", tmp_path / "gone.beats")]
    for name, n in (("a", 10), ("b", 30), ("c", 20), ("d", 30)):
        (tmp_path / f"{name}.wav").write_bytes(b"x" * n)
        tracks.append(Track(name, ".", tmp_path / f"{name}.wav", tmp_path / f"{name}.beats"))
    order = [t.key for t in beat_dataset._longest_first(tracks)]
    assert order == ["b", "d", "c", "a", "gone"]  # ties keep their order; unreadable: last


def test_the_tasks_of_a_run_are_one_dask_task_group(dataset, scheduler, tmp_path):
    # Dask queues tasks at the scheduler (worker-saturation) only for a task group larger
    # than twice the threads; the group is the key's prefix, and a track's name in the
    # key ("evaluate-psf-sample-...") made a group of each task
    from dask.distributed import Client

    seen = []

    def progress(done, total=None):
        if not seen:  # every task submitted (and held by its future)
            with Client(scheduler) as client:
                seen.extend(
                    client.run_on_scheduler(
                        lambda dask_scheduler: [
                            ts.group_key
                            for ts in dask_scheduler.tasks.values()
                            if ts.group_key.startswith("evaluate")
                        ]
                    )
                )

    found = find_tracks(*dataset)
    assert {"sample", "silent", "broken"} <= {t.key for t in found.tracks}  # no digits
    beat_dataset.evaluate_dataset(found.tracks, tmp_path, scheduler=scheduler, progress=progress)
    assert len(seen) == len(beat_dataset._groups(found.tracks, 2)) >= 3
    assert set(seen) == {"evaluate-psf"}


def test_the_scheduler_hands_out_a_group_when_a_thread_is_free(tmp_path):
    # the groups go to the scheduler in one call and wait there (worker-saturation 1.0):
    # submitted one by one, the first 2 x threads went to the workers at once
    from dask.distributed import get_client

    songs = _click_songs(tmp_path / "songs", 20, seconds=8.0)
    found = find_tracks(songs, songs)
    assert len(beat_dataset._groups(found.tracks, 2)) > 4  # enough for Dask to queue them
    states = []

    def progress(done, total=None):
        if not states:  # every group submitted
            states.extend(
                get_client().run_on_scheduler(
                    lambda dask_scheduler: [
                        ts.state
                        for ts in dask_scheduler.tasks.values()
                        if ts.key.startswith("evaluate")
                    ]
                )
            )

    run = beat_dataset.evaluate_dataset(
        found.tracks, tmp_path / "out", n_workers=2, processes=False, progress=progress
    )
    assert (run.tracks["status"] == "ok").all()
    assert len(states) == len(beat_dataset._groups(found.tracks, 2))
    assert states.count("processing") <= 2, states  # one group a thread, the rest wait
    assert "queued" in states, states


@pytest.mark.slow
def test_a_track_that_kills_its_worker_is_the_only_one_recorded_as_failed(tmp_path):
    # a real worker death (a crash in native code, the kernel's out-of-memory killer):
    # its group is run again track by track; the tracks finished on the worker that the
    # bad track then killed lost their results (Dask raised RuntimeError "... bound to a
    # different event loop") and were recorded as failed
    import dask
    from dask.distributed import Client, LocalCluster, WorkerPlugin

    songs = _click_songs(tmp_path / "songs", 10, seconds=6.0)

    class DiesOnOneTrack(WorkerPlugin):  # set up again in every restarted worker
        def setup(self, worker):
            import os

            from beatsync.study import beat_dataset

            real = beat_dataset.evaluate_track

            def track(audio, reference, **kwargs):
                if kwargs["name"] == "s02":
                    os._exit(1)
                return real(audio, reference, **kwargs)

            beat_dataset.evaluate_track = track

    with dask.config.set(cluster.LOCAL_CLUSTER_CONFIG):  # as the command's local cluster
        lc = LocalCluster(n_workers=2, threads_per_worker=1, processes=True, dashboard_address=":0")
    with lc, Client(lc) as client:
        client.register_plugin(DiesOnOneTrack())
        found = find_tracks(songs, songs)
        run = beat_dataset.evaluate_dataset(found.tracks, tmp_path / "out",
                                            scheduler=lc.scheduler_address)  # fmt: skip
    status = dict(zip(run.tracks["key"], run.tracks["status"], strict=True))
    assert status == {f"s{i:02d}": "error" if i == 2 else "ok" for i in range(10)}
    assert run.tracks.set_index("key").loc["s02", "error"].startswith("KilledWorker")
    assert len(TrackLog(run.files["log"]).rows()) == 10


def test_a_failed_group_is_run_again_track_by_track(dataset, tmp_path, monkeypatch):
    # a task that fails outside evaluate_track (its worker died: one track out of memory)
    # must not record the other tracks of its group as failed
    real_track = beat_dataset.evaluate_track

    def dies_on_one_track(audio, reference, *, name, **kwargs):
        if name == "rock/drums_96":
            raise MemoryError("the worker ran out of memory")
        return real_track(audio, reference, name=name, **kwargs)

    monkeypatch.setattr(beat_dataset, "evaluate_track", dies_on_one_track)
    found = find_tracks(*dataset)
    good = [t for t in found.tracks if t.key in GOOD]
    assert len(beat_dataset._groups(good, 1)) == 1  # one group: all four in one task
    run = beat_dataset.evaluate_dataset(good, tmp_path, n_workers=1, processes=False)
    status = dict(zip(run.tracks["key"], run.tracks["status"], strict=True))
    assert status == {k: "error" if k == "rock/drums_96" else "ok" for k in GOOD}
    error = run.tracks.set_index("key").loc["rock/drums_96", "error"]
    assert error == "MemoryError: the worker ran out of memory"
    assert len(TrackLog(run.files["log"]).rows()) == 4


# ----------------------------------------------------------------------------- bad input


def _bad(tmp_path, dataset, **change):
    """The valid argument set with one value changed."""
    audio, notes = change.get("audio", dataset[0]), change.get("notes", dataset[1])
    out = change.get("out", tmp_path / "results")
    argv = ["evaluate", "beats", "--audio", str(audio), "--annotations", str(notes)]
    return [*argv, "--out", str(out), *change.get("extra", [])]


def _refused(argv, match):
    args = build_parser().parse_args(argv)
    t0 = time.perf_counter()
    with pytest.raises(ParameterError, match=match):
        args.func(args)
    assert time.perf_counter() - t0 < 10.0


def test_empty_audio_folder(dataset, tmp_path):
    empty = tmp_path / "empty"
    empty.mkdir()
    (empty / "notes.txt").write_text("not audio")
    _refused(_bad(tmp_path, dataset, audio=empty), re.escape(str(empty)))
    assert not (tmp_path / "results").exists()


def test_empty_annotation_folder(dataset, tmp_path):
    empty = tmp_path / "empty"
    empty.mkdir()
    _refused(_bad(tmp_path, dataset, notes=empty), re.escape(str(empty)))


def test_no_audio_has_an_annotation(dataset, tmp_path):
    notes = tmp_path / "other"
    notes.mkdir()
    io.write_beats(notes / "unrelated.beats", np.arange(0.5, 4.0, 0.5))
    _refused(_bad(tmp_path, dataset, notes=notes), re.escape(str(notes)))


def test_missing_folder(dataset, tmp_path):
    _refused(_bad(tmp_path, dataset, audio=tmp_path / "nowhere"), "nowhere")


@pytest.mark.parametrize(
    "scale, decimals, match",
    [
        (1000.0, 0, "milliseconds"),
        (100.0, 0, "frame indices"),
        (44100.0, 0, "sample indices"),
        (10.0, 0, "frame indices"),  # 10 frames/s: once taken for seconds
        (1 / 60, 6, r"5760 BPM"),  # once scored F 0
    ],
)
def test_annotation_not_in_seconds(dataset, tmp_path, scale, decimals, match):
    notes = tmp_path / "notes"
    shutil.copytree(dataset[1], notes)
    ref = io.read_beats(notes / "drums_96.beats")
    (notes / "drums_96.beats").write_text(
        "".join(f"{v:.{decimals}f}\n" for v in np.round(ref * scale, decimals))
    )
    _refused(_bad(tmp_path, dataset, notes=notes), f"drums_96.beats'.*{match}")
    assert not (tmp_path / "results").exists()  # refused before anything is written


def test_an_annotation_shared_by_name_is_not_used(dataset, scheduler, tmp_path, capsys):
    audio, notes = tmp_path / "audio", tmp_path / "notes"
    for sub in ("a", "b"):
        (audio / sub).mkdir(parents=True)
        shutil.copy(dataset[0] / "rock" / "drums_96.wav", audio / sub / "drums_96.wav")
    shutil.copy(dataset[0] / "rock" / "drums_132.wav", audio / "a")
    shutil.copy(dataset[0] / "rock" / "drums_132.wav", audio / "a" / "drums_132.flac")
    notes.mkdir()
    for name in ("drums_96", "drums_132"):
        shutil.copy(dataset[1] / f"{name}.beats", notes)
    argv = ["evaluate", "beats", "--audio", str(audio), "--annotations", str(notes)]
    argv += ["--out", str(tmp_path / "r"), "--scheduler", scheduler, "--json"]
    code, stdout, err = _run(argv, capsys)
    assert code == 0, err
    res = json.loads(stdout)
    assert res["tracks"] == 1 and res["duplicates"] == [str(audio / "a" / "drums_132.wav")]
    assert list(res["shared_annotations"]) == [str(notes / "drums_96.beats")]
    assert "would serve more than one recording (found by name only for" in err
    assert "another file of the same name with another suffix is scored instead" in err


def test_results_files_of_someone_else_are_not_replaced(dataset, tmp_path):
    out = tmp_path / "results"
    out.mkdir()
    (out / "summary.csv").write_text("mine\n")
    _refused(_bad(tmp_path, dataset, out=out), "summary.csv")
    assert (out / "summary.csv").read_text() == "mine\n"
    assert sorted(p.name for p in out.iterdir()) == ["summary.csv"]


def test_annotation_of_another_recording_and_empty_references(dataset, scheduler, tmp_path, capsys):
    # annotations past the audio's end, or none left after --min-beat-time, scored 0
    # in the means with nothing said on the terminal
    audio, notes = tmp_path / "audio", tmp_path / "notes"
    audio.mkdir()
    notes.mkdir()
    for name in ("drums_96", "drums_132"):
        shutil.copy(dataset[0] / "rock" / f"{name}.wav", audio)
        shutil.copy(dataset[1] / f"{name}.beats", notes)
    io.write_beats(notes / "drums_132.beats", np.arange(100.0, 112.0, 0.5))
    argv = ["evaluate", "beats", "--audio", str(audio), "--annotations", str(notes)]
    where = ["--out", str(tmp_path / "r"), "--scheduler", scheduler]
    code, stdout, err = _run([*argv, *where], capsys)
    assert code == 0, err
    assert "failed: drums_132: no annotated beat falls inside the audio: the first is at 100" in (
        stdout
    )
    # both tracks on the two worker threads: each row keeps its own warnings
    where = ["--out", str(tmp_path / "r2"), "--scheduler", scheduler, "--json"]
    code, stdout, err = _run([*argv, *where, "--min-beat-time", "7.9"], capsys)
    res = json.loads(stdout)
    assert res["no_reference_beats"] == ["drums_96"], res
    code, stdout, err = _run([*argv, *where[:-1], "--min-beat-time", "7.9"], capsys)
    assert "1 track(s) have no annotated beat after --min-beat-time 7.9 s" in stdout


def test_a_swallowed_interrupt_stops_the_run_at_the_next_finished_group(
    dataset, scheduler, tmp_path, capsys, monkeypatch
):
    # SIGINT's exception, raised inside a garbage-collector callback, was swallowed
    # ("Exception ignored in ... Interrupted: 2") and the run went on to the end
    import signal

    from beatsync.commands import _common

    real_append = TrackLog.append

    first = []

    def append_then_swallowed_signal(self, *rows):
        real_append(self, *rows)
        if not first:
            first.extend(row["key"] for row in rows)
        _common._RECEIVED.append(signal.SIGINT)  # received, its exception lost

    monkeypatch.setattr(TrackLog, "append", append_then_swallowed_signal)
    out = tmp_path / "results"
    code, _, err = _run(_argv(dataset, out, "--scheduler", scheduler), capsys)
    assert code == 130, err
    assert "interrupted by SIGINT" in err
    # the rows of the group that finished first, and no other (6 tracks, 2 threads)
    assert 1 <= len(first) < 6
    assert [r["key"] for r in TrackLog(out / "tracks.jsonl").rows()] == first


def test_interrupt_before_any_track_finished_says_so(dataset, scheduler, tmp_path, capsys,
                                                      monkeypatch):  # fmt: skip
    def interrupt(*args, **kwargs):
        raise KeyboardInterrupt

    monkeypatch.setattr(beat_dataset, "_run", interrupt)
    out = tmp_path / "results"
    code, _, err = _run(_argv(dataset, out, "--scheduler", scheduler), capsys)
    assert code == 130
    assert "before any track finished: nothing was recorded" in err
    assert not out.exists()


def test_output_folder_is_a_file(dataset, tmp_path):
    f = tmp_path / "results"
    f.write_text("a file")
    _refused(_bad(tmp_path, dataset, out=f), re.escape(str(f)))
    assert f.read_text() == "a file"


@pytest.mark.parametrize(
    "extra, match",
    [
        (["--workers", "0"], "--workers=0"),
        (["--workers", "-1"], "--workers=-1"),
        (["--workers", "2", "--scheduler", "tcp://127.0.0.1:8786"], "--workers 2.*--scheduler"),
        (["--scheduler", "tcp://127.0.0.1:9"], "'tcp://127.0.0.1:9'"),
        (["--scheduler", "not-an-address"], "'not-an-address'"),
        (["--min-beat-time", "-5"], "--min-beat-time=-5"),
        (["--min-bpm", "120", "--max-bpm", "90"], "--min-bpm 120 .*--max-bpm 90"),
        (["--max-bpm", "30"], "--max-bpm 30 .*--min-bpm 40"),
        (
            ["--method", "librosa", "--min-bpm", "330", "--max-bpm", "400"],
            "--min-bpm 330: .*320 BPM",
        ),
        (["--min-bpm", "0.5"], "--min-bpm=0.5 .*20-400 BPM"),
        (["--method", "essentia-degara", "--min-bpm", "30"], "--min-bpm 30: .*40 to 180"),
        (
            ["--method", "essentia-degara", "--min-bpm", "90", "--max-bpm", "100"],
            "--min-bpm 90 .*20 BPM.*--max-bpm 100",
        ),
    ],
)
def test_bad_options(dataset, tmp_path, monkeypatch, extra, match):
    monkeypatch.setattr(cluster, "CONNECT_TIMEOUT", 1.0)
    _refused(_bad(tmp_path, dataset, extra=extra), match)
    assert not (tmp_path / "results").exists()


def test_optional_method_not_installed(dataset, tmp_path, monkeypatch):
    import dataclasses

    from beatsync import other_trackers

    fake = dataclasses.replace(
        other_trackers.TRACKERS["essentia-degara"], requires="no_such_package_xyz"
    )
    monkeypatch.setitem(other_trackers.TRACKERS, "essentia-degara", fake)
    extra = ["--method", "essentia-degara"]
    _refused(_bad(tmp_path, dataset, extra=extra), r"pip install 'beatsync\[peers\]'")


def test_results_scored_otherwise_are_not_mixed(dataset, scheduler, tmp_path, capsys):
    out = tmp_path / "results"
    code, _, err = _run(_argv(dataset, out, "--scheduler", scheduler), capsys)
    assert code == 0, err
    extra = ["--min-beat-time", "5", "--scheduler", scheduler]
    expected = "--min-beat-time 0 s, not 5 s"
    _refused(_bad(tmp_path, dataset, extra=extra), expected)


def test_tempo_range_reaches_the_tracker_and_is_recorded(dataset, scheduler, tmp_path, capsys):
    # the real madmom sample (88 BPM) alone, told nothing and told 75-101 BPM
    audio, notes = tmp_path / "audio", tmp_path / "notes"
    audio.mkdir(), notes.mkdir()
    shutil.copy(dataset[0] / "sample.wav", audio)
    shutil.copy(dataset[1] / "sample.beats", notes)
    base = ["evaluate", "beats", "--audio", str(audio), "--annotations", str(notes)]
    base += ["--scheduler", scheduler, "--json"]
    told = ["--min-bpm", "75", "--max-bpm", "101"]
    code, stdout, err = _run([*base, "--out", str(tmp_path / "told"), *told], capsys)
    assert code == 0, err
    res = json.loads(stdout)
    assert (res["min_bpm"], res["max_bpm"]) == (75.0, 101.0)
    (row,) = TrackLog(tmp_path / "told" / "tracks.jsonl").rows()
    assert (row["min_bpm"], row["max_bpm"]) == (75.0, 101.0)
    assert row["F-measure"] >= 0.95 and row["octave"] == "correct"
    code, stdout, err = _run([*base, "--out", str(tmp_path / "default")], capsys)
    assert code == 0, err
    (row,) = TrackLog(tmp_path / "default" / "tracks.jsonl").rows()
    assert (row["min_bpm"], row["max_bpm"]) == (None, None)
    # the default bounds given are the same search, and a log written before rows held
    # the range (no keys), or before a default bound was recorded as none (40 and 240),
    # was tracked with the default: the folder resumes (nothing re-run)
    log = TrackLog(tmp_path / "default" / "tracks.jsonl")
    (row,) = log.rows()
    no_keys = {k: v for k, v in row.items() if k not in ("min_bpm", "max_bpm")}
    default = ["--min-bpm", "40", "--max-bpm", "240"]
    for stored in (no_keys, {**row, "min_bpm": 40.0, "max_bpm": 240.0}):
        log.rewrite([stored])
        for again in ([], default):
            code, stdout, err = _run([*base, "--out", str(tmp_path / "default"), *again], capsys)
            assert code == 0, err
            assert json.loads(stdout)["skipped"] == 1 and json.loads(stdout)["min_bpm"] is None
    # results of one range are never mixed with another's in the same folder
    code, _, err = _run([*base, "--out", str(tmp_path / "default"), *told], capsys)
    assert code == 3
    assert "tracked with the default tempo range, not --min-bpm 75 and --max-bpm 101" in err
    text = [a for a in base if a != "--json"]  # the summary line names the options
    code, stdout, err = _run([*text, "--out", str(tmp_path / "default"), *told, "--force"], capsys)
    assert code == 0, err
    assert "1/1 tracks scored with psf, --min-bpm 75, --max-bpm 101 (1 run now)" in stdout
    (row,) = TrackLog(tmp_path / "default" / "tracks.jsonl").rows()
    assert row["min_bpm"] == 75.0


def test_failed_rows_do_not_bind_a_resume(dataset, scheduler, tmp_path, capsys):
    # a track that failed under one range is re-run under another: only scored rows
    # hold a folder to their settings
    audio, notes = tmp_path / "audio", tmp_path / "notes"
    audio.mkdir(), notes.mkdir()
    shutil.copy(dataset[0] / "sample.wav", audio)
    shutil.copy(dataset[1] / "sample.beats", notes)
    out = tmp_path / "out"
    out.mkdir()
    failed = {"key": "sample", "group": ".", "audio": str(audio / "sample.wav")}
    failed |= {"method": "psf", "min_beat_time": 5.0, "min_bpm": 185.0, "max_bpm": 198.0}
    TrackLog(out / "tracks.jsonl").rewrite([{**failed, "status": "error", "error": "boom"}])
    argv = ["evaluate", "beats", "--audio", str(audio), "--annotations", str(notes)]
    argv += ["--scheduler", scheduler, "--json", "--out", str(out)]
    code, stdout, err = _run(argv, capsys)
    assert code == 0, err
    assert json.loads(stdout)["scored_now"] == 1
    (row,) = TrackLog(out / "tracks.jsonl").latest().values()
    assert row["status"] == "ok" and (row["min_bpm"], row["min_beat_time"]) == (None, 0.0)


def test_tracks_tapped_outside_the_range_are_counted(scheduler, tmp_path, capsys):
    # librosa's range bounds its tempo estimate, not its beats: an 80 BPM pattern given
    # 180-250 BPM is tapped at 161; the row warns and the command counts it
    audio, notes = tmp_path / "audio", tmp_path / "notes"
    audio.mkdir(), notes.mkdir()
    ref = beat_times(80, duration=12.0, start=0.37)
    io.write_audio(audio / "drums_80.wav", drum_pattern(ref, sr=SR, duration=12.0), SR)
    io.write_beats(notes / "drums_80.beats", ref)
    argv = ["evaluate", "beats", "--audio", str(audio), "--annotations", str(notes)]
    argv += ["--method", "librosa", "--scheduler", scheduler, "--out", str(tmp_path / "o")]
    code, stdout, err = _run([*argv, "--min-bpm", "180", "--max-bpm", "250"], capsys)
    assert code == 0, err
    text = " ".join(stdout.split())
    assert (
        "1 track(s) tapped outside the tempo range given (only psf keeps to it; the "
        "warning column of tracks.csv says which)" in text
    )
    table = pd.read_csv(tmp_path / "o" / "tracks.csv")
    assert "librosa tapped a median tempo of 161 BPM, outside the range" in table["warning"][0]
    code, stdout, err = _run([*argv, "--force", "--json", "--max-bpm", "100"], capsys)
    assert code == 0, err
    assert json.loads(stdout)["outside_range"] == []


def test_librosa_range_without_a_tempo_step_is_refused_before_any_track(dataset, tmp_path, capsys):
    # librosa's tempi near 188 BPM are 184.6 and 191.4 at 44.1 kHz (the madmom sample)
    # and 184.6 and 198.8 at 22.05 kHz, hop 512: 185-191 holds none at either rate;
    # refused up front, every rate named, not once per track
    audio, notes = tmp_path / "audio", tmp_path / "notes"
    audio.mkdir(), notes.mkdir()
    shutil.copy(dataset[0] / "sample.wav", audio)
    shutil.copy(dataset[1] / "sample.beats", notes)
    shutil.copy(dataset[0] / "rock" / "drums_96.wav", audio)
    shutil.copy(dataset[1] / "drums_96.beats", notes)
    # a file at an implausible rate is left to its own row, not blamed for the range
    import soundfile as sf

    sf.write(audio / "tiny.wav", np.zeros(400, dtype=np.float32), 100)
    io.write_beats(notes / "tiny.beats", np.arange(0.5, 4.0, 0.5))
    out = tmp_path / "out"
    argv = ["evaluate", "beats", "--audio", str(audio), "--annotations", str(notes)]
    argv += ["--method", "librosa", "--out", str(out), "--workers", "1"]
    code, _, err = _run([*argv, "--min-bpm", "185", "--max-bpm", "191"], capsys)
    assert code == 3
    assert "'drums_96' (and any other track at 22050 Hz): tempo range 185-191 BPM holds" in err
    assert "the nearest are 184.6 and 198.8 BPM" in err
    assert "'sample' (and any other track at 44100 Hz): tempo range 185-191 BPM holds" in err
    assert "the nearest are 184.6 and 191.4 BPM" in err and "nothing was run" in err
    assert "tiny" not in err and "Traceback" not in err and not out.exists()
    code, stdout, err = _run([*argv, "--min-bpm", "180", "--max-bpm", "200", "--json"], capsys)
    assert code == 0, err
    res = json.loads(stdout)
    assert [f["key"] for f in res["failed"]] == ["tiny"] and res["scored_now"] == 3


def test_tempo_range_help_states_each_methods_defaults_and_limits(capsys):
    from beatsync.beats.tracker import DEFAULT_MAX_BPM, DEFAULT_MIN_BPM
    from beatsync.other_trackers import ESSENTIA_TEMPO

    with pytest.raises(SystemExit):
        main(["evaluate", "beats", "--help"])
    text = " ".join(capsys.readouterr().out.split())
    (lo_lo, lo_hi), (hi_lo, hi_hi) = ESSENTIA_TEMPO["min"], ESSENTIA_TEMPO["max"]
    assert ESSENTIA_TEMPO["default"][0] == DEFAULT_MIN_BPM
    assert f"(default {DEFAULT_MIN_BPM:g})" in text
    max_default = ESSENTIA_TEMPO["default"][1]
    assert f"(default {DEFAULT_MAX_BPM:g} for psf and librosa, {max_default}" in text
    assert f"whole BPM from {lo_lo} to {lo_hi}, at least {ESSENTIA_TEMPO['span']} below" in text
    assert "librosa searches a flat tempo prior inside the range" in text
    assert "Only psf keeps its beats inside the range" in text
    assert f"whole BPM from {hi_lo} to {hi_hi}" in text


def test_exit_code_and_message_on_bad_input(dataset, tmp_path, capsys):
    code, _, err = _run(_bad(tmp_path, dataset, extra=["--workers", "-1"]), capsys)
    assert code == 3  # bad input (2 is for usage errors)
    assert err.startswith("beatsync evaluate: error: --workers=-1")


@pytest.mark.slow
def test_ctrl_c_in_a_terminal_prints_no_worker_traceback(tmp_path):
    # a terminal's Ctrl-C reaches the whole process group: each local worker printed a
    # KeyboardInterrupt traceback, and one could log a failed heartbeat with two more,
    # before the command's own message
    import os
    import signal
    import subprocess
    import sys

    songs = _click_songs(tmp_path / "songs", 40, seconds=20.0, bpm_step=1.0)
    out = tmp_path / "results"
    argv = ["evaluate", "beats", "--audio", str(songs), "--annotations", str(songs)]
    proc = subprocess.Popen(
        [sys.executable, "-m", "beatsync.cli", *argv, "--out", str(out), "--workers", "2"],
        stdout=subprocess.DEVNULL,
        stderr=subprocess.PIPE,
        text=True,
        start_new_session=True,  # its own process group, as a terminal's foreground job
    )
    log = out / "tracks.jsonl"
    deadline = time.monotonic() + 120
    while proc.poll() is None and time.monotonic() < deadline:
        if log.exists() and log.stat().st_size:  # the workers are up and tracking
            break
        time.sleep(0.02)
    os.killpg(proc.pid, signal.SIGINT)
    _, err = proc.communicate(timeout=120)
    assert proc.returncode == 130, err
    assert "interrupted by SIGINT; the finished tracks are recorded in" in err
    assert "Traceback" not in err and "KeyboardInterrupt" not in err, err
