"""Whole-command behaviour of the program: outputs, errors, exit codes, feedback.

Every output is checked before any work and written all-or-nothing; errors are one
line (or a JSON object with ``--json``) with a distinct exit code per kind.
"""

from __future__ import annotations

import json
import os
import shutil
import signal
import subprocess
import sys
import time
from pathlib import Path

import nbformat
import pytest

from beatsync import datasets, io
from beatsync.cli import build_parser, main
from beatsync.commands import COMMAND_HELP, COMMAND_MODULES
from beatsync.commands._common import Feedback, Outputs
from beatsync.synth.audio import beat_times, click_track

SR = 22050
SRC = str(Path(__file__).resolve().parents[1] / "src")


@pytest.fixture
def inputs(tmp_path):
    """A valid song, motion clip and beats file, in a folder of their own."""
    d = tmp_path / "in"
    d.mkdir()
    song = d / "song.wav"
    io.write_audio(song, click_track(beat_times(120, duration=4.0), sr=SR, duration=4.0), SR)
    clip = d / "clip.bvh"
    shutil.copy(datasets.path("motion/cmu_walk_modern/007_12.bvh"), clip)
    beats = d / "song.beats"
    io.write_beats(beats, beat_times(120, duration=4.0))
    return {"song": song, "clip": clip, "beats": beats, "dir": d}


# (subcommand argv with {out} for the output under test, the option named in the message)
OUTPUT_OPTIONS = {
    "segment --out": (["segment", "{clip}", "--out", "{out}.csv"], "--out"),
    "beats --out": (["beats", "{song}", "--out", "{out}.beats"], "--out"),
    "beats --click": (["beats", "{song}", "--click", "{out}.wav"], "--click"),
    "sync -o": (["sync", "{clip}", "{song}", "-o", "{out}.bvh"], "-o/--output"),
    "sync --video": (
        ["sync", "{clip}", "{song}", "-o", "{o}/ok.bvh", "--video", "{out}.mp4"],
        "--video",
    ),
    "sync --report": (
        ["sync", "{clip}", "{song}", "-o", "{o}/ok.bvh", "--report", "{out}.json"],
        "--report",
    ),
    "compose -o": (
        ["compose", "{song}", "--library", "{clip}", "-o", "{out}.bvh"],
        "-o/--output",
    ),
    "compose --video": (
        ["compose", "{song}", "--library", "{clip}", "-o", "{o}/ok.bvh", "--video", "{out}.mp4"],
        "--video",
    ),
    "compose --report": (
        ["compose", "{song}", "--library", "{clip}", "-o", "{o}/ok.bvh", "--report", "{out}.json"],
        "--report",
    ),
    "batch --summary": (
        [
            "batch",
            "--clips",
            "{clip}",
            "--songs",
            "{song}",
            "--out-dir",
            "{o}",
            "--summary",
            "{out}.csv",
        ],
        "--summary",
    ),  # fmt: skip
}


def _argv(template, inputs, out, outdir):
    return [a.format(clip=inputs["clip"], song=inputs["song"], out=out, o=outdir) for a in template]


def _run(argv, capsys):
    code = main(argv)
    cap = capsys.readouterr()
    return code, cap.out, cap.err


def _assert_refused(code, err, *words):
    assert code == 3, err
    assert "Traceback" not in err
    assert err.startswith("beatsync ") and ": error: " in err
    for w in words:
        assert w in err, err


def _listing(d: Path) -> list[str]:
    return sorted(str(p.relative_to(d)) for p in d.rglob("*"))


@pytest.mark.parametrize("case", sorted(OUTPUT_OPTIONS))
def test_output_that_is_a_folder_is_refused(case, inputs, tmp_path, capsys):
    template, option = OUTPUT_OPTIONS[case]
    outdir = tmp_path / "o"
    outdir.mkdir()
    target = outdir / "taken"
    suffix = Path(template[-1]).suffix
    Path(str(target) + suffix).mkdir()  # the output path is an existing folder
    before = _listing(tmp_path)
    code, _, err = _run(_argv(template, inputs, target, outdir), capsys)
    _assert_refused(code, err, "existing folder", option)
    assert _listing(tmp_path) == before


@pytest.mark.parametrize("ending", ["/", "/."])
@pytest.mark.parametrize("exists", [False, True])
@pytest.mark.parametrize("case", sorted(OUTPUT_OPTIONS))
def test_output_ending_in_a_slash_is_refused(case, exists, ending, inputs, tmp_path, capsys):
    # "out/" names a folder; Path() dropped the slash and wrote (or replaced) a file "out"
    template, option = OUTPUT_OPTIONS[case]
    assert template[-1].startswith("{out}")
    outdir = tmp_path / "o"
    outdir.mkdir()
    target = outdir / "taken"
    victim = Path(str(target) + Path(template[-1]).suffix)
    if exists:
        victim.write_text("keep me\n")
    before = _listing(tmp_path)
    argv = _argv(template, inputs, target, outdir)
    argv[-1] += ending
    code, _, err = _run(argv, capsys)
    _assert_refused(code, err, "which names a folder", option)
    assert _listing(tmp_path) == before
    if exists:
        assert victim.read_text() == "keep me\n"


@pytest.mark.parametrize("case", sorted(OUTPUT_OPTIONS))
def test_read_only_output_is_refused_and_kept(case, inputs, tmp_path, capsys):
    template, option = OUTPUT_OPTIONS[case]
    outdir = tmp_path / "o"
    outdir.mkdir()
    target = outdir / "taken"
    ro = Path(str(target) + Path(template[-1]).suffix)
    ro.write_text("keep me\n")
    ro.chmod(0o444)
    before = _listing(tmp_path)
    code, _, err = _run(_argv(template, inputs, target, outdir), capsys)
    _assert_refused(code, err, "read-only", option)
    assert ro.read_text() == "keep me\n"
    assert _listing(tmp_path) == before


@pytest.mark.parametrize("case", sorted(OUTPUT_OPTIONS))
def test_output_in_missing_folder_is_refused(case, inputs, tmp_path, capsys):
    template, option = OUTPUT_OPTIONS[case]
    outdir = tmp_path / "o"
    outdir.mkdir()
    target = tmp_path / "missing" / "x"
    before = _listing(tmp_path)
    code, _, err = _run(_argv(template, inputs, target, outdir), capsys)
    _assert_refused(code, err, "does not exist", option)
    assert _listing(tmp_path) == before


@pytest.mark.parametrize(
    "argv, option",
    [
        (["beats", "{song}", "--click", "{song}"], "--click"),
        (["sync", "{clip}", "{song}", "-o", "{clip}", "--beats", "{beats}"], "-o/--output"),
        (["compose", "{song}", "--library", "{clip}", "-o", "{clip}"], "-o/--output"),
        (["segment", "{clip}", "--out", "{link}"], "--out"),  # a link to the input
    ],
)
def test_output_same_as_input_is_refused(argv, option, inputs, tmp_path, capsys):
    outdir = tmp_path / "o"
    outdir.mkdir()
    link = inputs["dir"] / "link.csv"
    link.symlink_to(inputs["clip"])
    argv = [
        a.format(o=outdir, link=link, **{k: v for k, v in inputs.items() if k != "dir"})
        for a in argv
    ]
    sums = {p: p.read_bytes() for p in inputs["dir"].iterdir() if p.is_file()}
    code, _, err = _run(argv, capsys)
    _assert_refused(code, err, "same file as the input", option)
    assert {p: p.read_bytes() for p in sums} == sums
    assert not any(outdir.iterdir())


@pytest.mark.parametrize(
    "argv, victim",
    [
        # --out where --click was meant: the beat times as text would replace a sound file
        (["beats", "{song}", "--out", "{o}/mix.wav"], "mix.wav"),
        (["segment", "{clip}", "--out", "{o}/dance.bvh"], "dance.bvh"),
    ],
)
def test_text_output_named_like_a_media_file_is_refused(argv, victim, inputs, tmp_path, capsys):
    outdir = tmp_path / "o"
    outdir.mkdir()
    target = outdir / victim
    target.write_bytes(b"precious")
    argv = [a.format(o=outdir, **inputs) for a in argv]
    code, _, err = _run(argv, capsys)
    _assert_refused(code, err, "as text", "--out")
    assert target.read_bytes() == b"precious"


def test_two_options_naming_one_file_are_refused(inputs, tmp_path, capsys):
    out = tmp_path / "same.json"
    argv = ["sync", str(inputs["clip"]), str(inputs["song"]), "-o", str(tmp_path / "a.bvh")]
    code, _, err = _run([*argv, "--report", str(out), "--video", str(out)], capsys)
    _assert_refused(code, err)
    assert not out.exists()


# ------------------------------------------------------------ the transaction


def test_outputs_commit_all_or_nothing(tmp_path):
    a, b = tmp_path / "a.txt", tmp_path / "b.txt"
    b.write_text("old b\n")
    with pytest.raises(OSError, match="disk full"):
        with Outputs() as outs:
            outs.add(a, option="--a")
            outs.add(b, option="--b")
            outs.path(a).write_text("new a\n")
            outs.path(b).write_text("half")
            raise OSError("disk full")
    assert not a.exists() and b.read_text() == "old b\n"
    assert _listing(tmp_path) == ["b.txt"]  # no staging folder left
    with Outputs() as outs:
        outs.add(a, option="--a")
        outs.add(b, option="--b")
        outs.path(a).write_text("new a\n")
        outs.path(b).write_text("new b\n")
        assert not a.exists()  # nothing in place before the command succeeded
    assert a.read_text() == "new a\n" and b.read_text() == "new b\n"
    assert _listing(tmp_path) == ["a.txt", "b.txt"]


def test_outputs_keep_an_existing_files_mode(tmp_path):
    a = tmp_path / "a.txt"
    a.write_text("old")
    a.chmod(0o640)
    with Outputs() as outs:
        outs.add(a)
        outs.path(a).write_text("new")
    assert a.read_text() == "new" and a.stat().st_mode & 0o777 == 0o640


def _notebook(path: Path, body: str) -> None:
    nb = nbformat.v4.new_notebook()
    params = nbformat.v4.new_code_cell("n: int = 3  # how many")
    params.metadata["tags"] = ["parameters"]
    nb.cells = [params, nbformat.v4.new_code_cell(body)]
    nb.metadata["kernelspec"] = {"name": "python3", "display_name": "Python", "language": "python"}
    nbformat.write(nb, path)


@pytest.fixture
def study(tmp_path):
    """Two notebooks: ``a`` runs at once, ``b`` runs ``B_BODY`` (default: fails)."""
    nbs = tmp_path / "notebooks"
    nbs.mkdir()
    _notebook(nbs / "a.ipynb", "print(n * 2)")
    _notebook(nbs / "b.ipynb", "raise RuntimeError('broken analysis')")
    params = tmp_path / "p.yaml"
    params.write_text("a: {}\nb: {}\n")
    out = tmp_path / "out"
    out.mkdir()
    return {"nbs": nbs, "params": params, "out": out}


def _reproduce_argv(study, *extra):
    return ["reproduce", "--params", str(study["params"]), "--notebooks", str(study["nbs"]),
            "--output", str(study["out"]), *extra]  # fmt: skip


@pytest.mark.slow
def test_a_later_output_failing_leaves_nothing_behind(study, capsys):
    """Notebook b fails: a's executed copy and the manifest are not written either."""
    (study["out"] / "a.ipynb").write_text("previous run\n")
    code, _, err = _run(_reproduce_argv(study), capsys)
    assert code == 70 and "broken analysis" in err  # an error inside the study's code
    assert (study["out"] / "a.ipynb").read_text() == "previous run\n"
    # only the deliberately kept diagnostic copy of the failed notebook
    assert _listing(study["out"]) == ["a.ipynb", "b.failed.ipynb"]


@pytest.mark.slow
@pytest.mark.parametrize("sig, code", [(signal.SIGTERM, 143), (signal.SIGINT, 130)])
def test_signal_during_multi_output_command_leaves_no_temporaries(study, sig, code):
    _notebook(study["nbs"] / "b.ipynb", "import time\ntime.sleep(120)")
    env = {**os.environ, "PYTHONPATH": SRC}
    proc = subprocess.Popen(
        [sys.executable, "-m", "beatsync.cli", *_reproduce_argv(study)],
        stderr=subprocess.PIPE,
        text=True,
        env=env,
    )
    lines = []
    for line in proc.stderr:  # type: ignore[union-attr]
        lines.append(line)
        if line.startswith("running b"):
            break
    deadline = time.monotonic() + 60.0  # a's kernel starts slowly on a loaded machine
    while not _listing(study["out"]) and time.monotonic() < deadline:
        time.sleep(0.2)
    time.sleep(1.0)  # b's kernel is sleeping; a's copy is in flight
    assert _listing(study["out"]) != []  # something is in flight
    proc.send_signal(sig)
    rest = proc.communicate(timeout=60)[1]
    assert proc.returncode == code, "".join(lines) + rest
    # (the notebook kernel and its client library may print their own complaints)
    assert f"reproduce: error: interrupted by {sig.name}; no output was written\n" in rest
    # no traceback through our code (the checkout's own folder may be named beatsync)
    ours = (f"{SRC}/beatsync/", "site-packages/beatsync/")
    assert not any(place in rest for place in ours), rest
    assert _listing(study["out"]) == []
    assert _listing(study["nbs"]) == ["a.ipynb", "b.ipynb"]


# ----------------------------------------------------------- errors and codes


def test_json_errors_are_objects_on_stderr(inputs, tmp_path, capsys):
    out = tmp_path / "o"
    out.mkdir()
    code, stdout, err = _run(["beats", str(inputs["song"]), "--json", "--out", str(out)], capsys)
    assert code == 3 and stdout == ""
    obj = json.loads(err)
    assert obj["kind"] == "bad-input" and obj["exit_code"] == 3 and obj["command"] == "beats"
    assert "existing folder" in obj["error"]
    code, stdout, err = _run(["beats", str(inputs["song"]), "--json", "--bmp", "120"], capsys)
    obj = json.loads(err)
    assert code == 2 and obj["kind"] == "usage" and "--bmp" in obj["error"]


def test_exit_codes(inputs, tmp_path, capsys, monkeypatch):
    code, _, err = _run(["beats", str(inputs["song"]), "--no-such-option"], capsys)
    assert code == 2 and "unrecognized arguments: --no-such-option" in err
    code, _, err = _run(["beats", str(tmp_path / "nope.wav")], capsys)
    _assert_refused(code, err, "does not exist")
    code, _, err = _run(["frobnicate"], capsys)
    assert code == 2 and "invalid choice" in err

    def broken():
        raise RuntimeError("invariant broken")

    monkeypatch.setattr(datasets, "verify_all", broken)
    code, _, err = _run(["data"], capsys)
    assert code == 70
    assert "Traceback" in err and "internal error RuntimeError: invariant broken" in err
    code, _, err = _run(["data", "--json"], capsys)
    obj = json.loads(err)
    assert code == 70 and obj["kind"] == "internal" and "Traceback" in obj["traceback"]

    def full():
        raise OSError(28, "No space left on device", "/x/out.bvh")

    monkeypatch.setattr(datasets, "verify_all", full)
    code, _, err = _run(["data"], capsys)
    assert code == 4 and "No space left on device: '/x/out.bvh'" in err


def test_exit_codes_are_documented():
    import beatsync.cli

    doc = beatsync.cli.__doc__
    for code in ("0 ", "1 ", "2 ", "3 ", "4 ", "70 ", "130 ", "143"):
        assert f"\n{code}" in doc or f" {code}" in doc


# ----------------------------------------------------------------- feedback


def test_quiet_silences_progress_lines(study, capsys):
    params = study["params"]
    params.write_text("a: {}\n")
    (study["nbs"] / "b.ipynb").unlink()
    code, _, err = _run(_reproduce_argv(study), capsys)
    assert code == 0 and "running a" in err
    code, _, err = _run(_reproduce_argv(study, "--quiet"), capsys)
    assert code == 0 and err == ""
    assert _listing(study["out"]) == ["a.ipynb", "run_manifest.json"]


_BAR_SCRIPT = """
import time
from beatsync.commands._common import Feedback
fb = Feedback("demo", quiet={quiet})
with fb.step("crunching numbers", total=3) as progress:
    for i in range(3):
        time.sleep(0.2)
        progress(i + 1)
fb.info("info line")
"""


def _stderr_on_terminal(script: str) -> str:
    import fcntl
    import pty
    import struct
    import termios

    master, slave = pty.openpty()
    fcntl.ioctl(slave, termios.TIOCSWINSZ, struct.pack("HHHH", 24, 80, 0, 0))  # 80 columns
    env = {**os.environ, "PYTHONPATH": SRC}
    proc = subprocess.Popen([sys.executable, "-c", script], stderr=slave, env=env)
    os.close(slave)
    chunks = []
    while True:
        try:
            data = os.read(master, 4096)
        except OSError:
            break
        if not data:
            break
        chunks.append(data)
    proc.wait(timeout=30)
    os.close(master)
    return b"".join(chunks).decode(errors="replace")


def test_progress_bar_on_a_terminal_only_and_quiet_silences_it():
    shown = _stderr_on_terminal(_BAR_SCRIPT.format(quiet=False))
    assert "crunching numbers" in shown and "3/3" in shown and "info line" in shown
    assert _stderr_on_terminal(_BAR_SCRIPT.format(quiet=True)).strip() == ""
    env = {**os.environ, "PYTHONPATH": SRC}
    piped = subprocess.run(
        [sys.executable, "-c", _BAR_SCRIPT.format(quiet=False)],
        capture_output=True,
        text=True,
        env=env,
    )
    assert piped.stderr == "info line\n"  # no bar when stderr is not a terminal


def test_feedback_callback_is_a_no_op_without_a_terminal(capsys):
    fb = Feedback("x")
    with fb.step("work", total=10) as progress:
        progress(5)
        progress(10, 10)
    assert capsys.readouterr().err == ""


# -------------------------------------------------------------- lazy imports


def _modules_after(code: str) -> set[str]:
    env = {**os.environ, "PYTHONPATH": SRC}
    out = subprocess.run(
        [sys.executable, "-c", code + "\nimport sys, json; print(json.dumps(sorted(sys.modules)))"],
        capture_output=True,
        text=True,
        env=env,
        check=True,
    )
    return set(json.loads(out.stdout.strip().splitlines()[-1]))


def test_help_imports_no_subcommand_and_no_numpy():
    mods = _modules_after(
        "from beatsync.cli import main\ntry:\n    main(['--help'])\nexcept SystemExit:\n    pass"
    )
    assert "numpy" not in mods
    assert not any(m.startswith("beatsync.commands.") and m != "beatsync.commands._common"
                   for m in mods)  # fmt: skip


def test_only_the_chosen_subcommand_is_imported():
    mods = _modules_after(
        "from beatsync.cli import main\ntry:\n    main(['data', '--help'])\n"
        "except SystemExit:\n    pass"
    )
    loaded = {m for m in mods if m.startswith("beatsync.commands.")}
    assert loaded == {"beatsync.commands.data", "beatsync.commands._common"}


def test_dataset_command_scores_only_in_its_workers_and_skips_mir_eval(tmp_path):
    """mir_eval (with scipy.stats) took 1.6 s of ``evaluate beats``' start-up in a process
    that scores nothing: the annotations are read and the scheduler reached without it."""
    real = Path(__file__).resolve().parents[1] / "data" / "audio" / "real_dev"
    audio, notes = tmp_path / "audio", tmp_path / "notes"
    audio.mkdir()
    notes.mkdir()
    shutil.copy(real / "hainsworth_001.flac", audio)
    shutil.copy(real / "hainsworth_001.beats", notes)
    args = ["evaluate", "beats", "--audio", str(audio), "--annotations", str(notes)]
    args += ["--out", str(tmp_path / "out"), "--scheduler", "foo://127.0.0.1:1"]
    mods = _modules_after(
        f"from beatsync.cli import main\ntry:\n    main({args!r})\nexcept SystemExit:\n    pass"
    )
    assert "beatsync.study.beat_dataset" in mods and "dask.distributed" in mods
    assert "mir_eval" not in mods and "scipy.stats" not in mods


def test_the_dataset_task_a_worker_runs_imports_no_pandas():
    """A worker unpickles the task by its module: pandas took 0.6 s of its first track."""
    from beatsync.study import beat_dataset

    module = beat_dataset.evaluate_track.__module__
    mods = _modules_after(f"import distributed\nimport {module}")
    assert module in mods and "pandas" not in mods


def test_listed_help_matches_each_subcommand():
    parser = build_parser()
    action = next(a for a in parser._actions if a.dest == "command")
    shown = {a.dest: a.help for a in action._choices_actions}
    assert set(shown) == set(COMMAND_MODULES)
    assert shown == {name: COMMAND_HELP[name] for name in COMMAND_MODULES}


def test_a_swallowed_signal_still_stops_the_command(tmp_path, capsys):
    """Code called back from C (soundfile's writer) can swallow the signal's exception."""
    import io as stdio

    from beatsync.commands._common import Interrupted, error_report, signals_as_exceptions

    out = tmp_path / "a.txt"
    with signals_as_exceptions():
        with pytest.raises(Interrupted):
            with Outputs() as outs:
                outs.add(out)
                try:
                    os.kill(os.getpid(), signal.SIGTERM)
                    time.sleep(0.5)
                except BaseException:  # what a C callback does with it
                    pass
                outs.path(out).write_text("finished anyway")
        # and the error the lost exception causes later is reported as the signal
        stream = stdio.StringIO()
        code = error_report(
            RuntimeError("Error writing file"), "sync", as_json=False, stream=stream
        )
    assert code == 143 and "interrupted by SIGTERM" in stream.getvalue()
    assert _listing(tmp_path) == []
