import json
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from beatsync import datasets, io
from beatsync.errors import BeatsyncWarning, ParameterError
from beatsync.motion import Motion


def test_bvh_round_trip_exact(tmp_path, chain_motion):
    p = io.write_bvh(tmp_path / "a.bvh", chain_motion)
    back = io.read_bvh(p)
    np.testing.assert_array_equal(back.values, chain_motion.values)
    assert back.fps == chain_motion.fps
    assert back.channels == chain_motion.channels
    assert back.skeleton.joints == chain_motion.skeleton.joints


def test_real_bvh_read_write_read(tmp_path):
    m = datasets.load_salsa("60_01")
    assert m.values.shape == (2242, 132)
    assert m.fps == 60.0  # header says 120; bundled loader overrides
    header = io.read_bvh(datasets.path("motion/cmu_salsa/60_01_scaled.bvh"))
    assert header.fps == pytest.approx(120.0, rel=1e-3)
    m2 = io.read_bvh(io.write_bvh(tmp_path / "s.bvh", m))
    m3 = io.read_bvh(io.write_bvh(tmp_path / "s2.bvh", m2))
    np.testing.assert_array_equal(m2.values, m.values)
    np.testing.assert_array_equal(m3.values, m.values)
    assert m2.skeleton.joints == m.skeleton.joints


def _write(tmp_path: Path, text: str) -> Path:
    p = tmp_path / "bad.bvh"
    p.write_text(text)
    return p


GOOD = """HIERARCHY
ROOT hip
{
 OFFSET 0 0 0
 CHANNELS 6 Xposition Yposition Zposition Zrotation Xrotation Yrotation
 JOINT knee
 {
  OFFSET 0 -1 0
  CHANNELS 3 Zrotation Xrotation Yrotation
  End Site
  {
   OFFSET 0 -1 0
  }
 }
}
MOTION
Frames: 2
Frame Time: 0.04
0 1 0 0 0 0 0 10 0
0 1 0 0 0 0 0 20 0
"""


def test_minimal_bvh(tmp_path):
    m = io.read_bvh(_write(tmp_path, GOOD))
    assert m.fps == 25.0
    assert m.channels[-2] == "knee_Xrotation"
    assert m.positions().shape == (2, 3, 3)


@pytest.mark.parametrize(
    "text, match",
    [
        (GOOD.split("MOTION")[0][:80], "line 5: CHANNELS 6"),
        (GOOD.replace("0 1 0 0 0 0 0 20 0\n", ""), r"\b2 frames but has 1 frame"),
        (GOOD.replace("0 1 0 0 0 0 0 20 0", "0 1 0 0 0 0 0 20"), "frame line 2 has 8 values"),
        (
            GOOD.replace("0 1 0 0 0 0 0 20 0", "0 1 0 0 0 0 0 nan 0"),
            r"frame 2 of 2, channel 'knee_Xrotation' is nan \(NaN",
        ),
        (GOOD.replace("0 1 0 0 0 0 0 20 0", "0 1 0 0 0 0 0 x 0"), "line 20: .*'x'"),
        (GOOD.replace("Frame Time: 0.04", "Frame Time: 0"), "Frame Time 0.0"),
        (GOOD.replace("HIERARCHY", "HIERARCY"), "'HIERARCY'"),
        (GOOD.replace("CHANNELS 3 Zrotation", "CHANNELS 3 Wrotation"), "line 9: .*'Wrotation'"),
        ("not a bvh at all", "line 1: .*'not'"),
    ],
)
def test_malformed_bvh(tmp_path, text, match):
    with pytest.raises(ParameterError, match=match):
        io.read_bvh(_write(tmp_path, text))


def test_text_renamed_mp3_is_not_said_to_be_missing(tmp_path):
    import soundfile as sf

    if "MP3" not in sf.available_formats():
        pytest.skip("this libsndfile has no MP3")
    p = tmp_path / "notes.mp3"
    p.write_text("not audio at all\n" * 500)
    # libsndfile says "File does not exist or is not a regular file" of such a file
    with pytest.raises(ParameterError, match=r"notes\.mp3") as info:
        io.read_audio(p)
    assert "does not exist" not in str(info.value)


def test_missing_and_empty_files(tmp_path):
    with pytest.raises(ParameterError, match=r"nope\.bvh"):
        io.read_motion(tmp_path / "nope.bvh")
    (tmp_path / "e.wav").write_bytes(b"")
    with pytest.raises(ParameterError, match=r"e\.wav"):
        io.read_audio(tmp_path / "e.wav")
    (tmp_path / "junk.wav").write_bytes(b"RIFF garbage not audio" * 10)
    with pytest.raises(ParameterError, match=r"junk\.wav"):
        io.read_audio(tmp_path / "junk.wav")
    with pytest.raises(ParameterError, match=r"x\.txt"):
        io.read_motion(_write(tmp_path, GOOD).rename(tmp_path / "x.txt"))


def test_fps_override_and_bad_fps(tmp_path):
    p = _write(tmp_path, GOOD)
    assert io.read_bvh(p, fps=60).fps == 60.0
    with pytest.raises(ParameterError, match="fps=0"):
        io.read_bvh(p, fps=0)


def test_atomic_write_leaves_nothing_on_error(tmp_path):
    dest = tmp_path / "out.txt"
    dest.write_text("original")
    with pytest.raises(RuntimeError):
        with io.atomic_write(dest) as fh:
            fh.write("partial")
            raise RuntimeError("boom")
    assert dest.read_text() == "original"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["out.txt"]


def test_write_bvh_without_skeleton_refused(tmp_path):
    m = Motion(np.zeros((3, 2)), 30.0, ("a", "b"))
    with pytest.raises(ParameterError, match=r"x\.bvh"):
        io.write_bvh(tmp_path / "x.bvh", m)
    assert not (tmp_path / "x.bvh").exists()


def test_tables(tmp_path):
    m = Motion(np.arange(12.0).reshape(6, 2), 25.0, ("knee", "hip"))
    p = io.write_table(tmp_path / "t.csv", m)
    back = io.read_motion(p, fps=25)
    np.testing.assert_array_equal(back.values, m.values)
    assert back.channels == ("knee", "hip")
    with pytest.raises(ParameterError, match=r"t\.csv.*--fps"):
        io.read_motion(p)
    np.save(tmp_path / "t.npy", m.values)
    assert io.read_motion(tmp_path / "t.npy", fps=25).n_channels == 2
    np.save(tmp_path / "bad.npy", np.zeros(5))
    with pytest.raises(ParameterError, match=r"shape \(5,\)"):
        io.read_motion(tmp_path / "bad.npy", fps=25)
    (tmp_path / "s.csv").write_text("a,b\n1,x\n2,y\n")
    with pytest.raises(ParameterError, match=r"\['b'\]"):
        io.read_motion(tmp_path / "s.csv", fps=25)


def test_mocap_mat():
    d = datasets.load_mocap_toolbox("dance2")
    assert d.values.shape == (1500, 84) and d.fps == 60.0
    assert d.channels[:3] == ("Head_FL_x", "Head_FL_y", "Head_FL_z")
    # metres, z up: head markers are above 1 m
    assert 1.0 < np.nanmean(d.values[:, 2]) < 2.2
    with pytest.raises(ParameterError, match=r"\['dance1', 'dance2'"):
        io.read_mocap_mat(datasets.path("motion/mocaptoolbox/mcdemodata.mat"))


def test_audio_round_trip_and_mp3(tmp_path):
    y, sr = datasets.load_click_808()
    assert sr == 44100 and y.ndim == 1 and 9.5 < y.size / sr < 10.5
    p = io.write_audio(tmp_path / "a.wav", y[:4410], sr)
    y2, sr2 = io.read_audio(p)
    assert sr2 == sr and np.allclose(y2, y[:4410], atol=1e-4)
    y3, sr3 = io.read_audio(p, sr=22050)
    assert sr3 == 22050 and abs(y3.size - 2205) <= 1


@pytest.mark.parametrize("orig, target", [(44100, 22050), (48000, 22050), (16000, 44100.0)])
def test_resample_audio_keeps_a_tone_and_the_length(orig, target):
    # the samples are those of librosa.resample(res_type="soxr_hq") (checked when it was
    # written); here: ceil(n * ratio) samples, float32, and a 440 Hz tone kept exactly
    n = 12345
    y = np.sin(2 * np.pi * 440.0 * np.arange(n) / orig).astype(np.float32)
    out = io.resample_audio(y, orig, target)
    assert out.dtype == np.float32 and out.size == int(np.ceil(n * target / orig))
    t = np.arange(out.size) / target
    inner = slice(out.size // 10, -out.size // 10)
    np.testing.assert_allclose(out[inner], np.sin(2 * np.pi * 440.0 * t)[inner], atol=2e-3)


def test_loud_audio_resamples_to_the_same_samples_scaled(tmp_path):
    # soxr's float32 filter returned NaN for a peak from about 1e37: read_audio(sr=) gave
    # a NaN signal without a word. It now filters at a level lowered by a power of two.
    import soundfile as sf

    n = 12345
    y = (0.5 * np.sin(2 * np.pi * 440.0 * np.arange(n) / 44100)).astype(np.float32)
    gain = np.float32(2.0**126)  # a peak of 4e37
    want = io.resample_audio(y, 44100, 22050) * gain
    np.testing.assert_array_equal(io.resample_audio(y * gain, 44100, 22050), want)
    path = tmp_path / "loud.wav"
    sf.write(path, y * gain, 44100, subtype="FLOAT")
    got, sr = io.read_audio(path, sr=22050)[:2]
    assert sr == 22050
    np.testing.assert_array_equal(got, want)


@pytest.mark.parametrize(
    "y, orig, target, match",
    [
        (np.zeros((100, 2), np.float32), 44100, 22050, r"shape \(100, 2\)"),
        (np.zeros(0, np.float32), 44100, 22050, "zero samples"),
        (np.array([0.0, np.nan], np.float32), 44100, 22050, "sample 1"),
        (np.zeros(100, np.float32), 0, 22050, "sr=0"),
        (np.zeros(100, np.float32), 44100, -1, "target_sr=-1"),
    ],
)
def test_resample_audio_refuses_bad_input(y, orig, target, match):
    with pytest.raises(ParameterError, match=match):
        io.resample_audio(y, orig, target)


def test_damaged_soundfile_formats_are_refused_without_librosa(tmp_path):
    # a broken .wav fell back to librosa/audioread: 6 s of imports (30 s with a numba
    # compilation on a fresh installation) per process, to fail the same way
    code = """
import sys
from pathlib import Path
from beatsync import io
from beatsync.errors import BeatsyncWarning, ParameterError
d = Path(sys.argv[1])
for name in ("junk.wav", "junk.flac", "junk.mp3"):
    (d / name).write_bytes(b"RIFF garbage not audio" * 10)
    try:
        io.read_audio(d / name)
    except ParameterError as exc:
        print(exc)
y = io.read_audio(io.write_audio(d / "ok.wav", [0.0, 0.5, -0.5, 0.25] * 4410, 44100), sr=22050)[0]
print(y.size, "librosa" in sys.modules)
"""
    out = subprocess.run(
        [sys.executable, "-c", code, str(tmp_path)], capture_output=True, text=True, check=True
    ).stdout.splitlines()
    assert len(out) == 4, out
    for line, fmt in zip(out[:3], ("WAV", "FLAC", "MP3"), strict=True):
        assert f"as {fmt} audio" in line and "is the file complete" in line
    assert out[3] == "8820 False"


@pytest.mark.parametrize(
    "fmt, suffix",
    [("WAV", ".wav"), ("MP3", ".mp3"), ("AIFF", ".aiff"), ("W64", ".w64"), ("RF64", ".rf64"),
     ("AU", ".au")],
)  # fmt: skip
def test_a_file_cut_short_is_refused_naming_both_lengths(tmp_path, fmt, suffix):
    # libsndfile read what was left of a truncated WAV, AIFF, W64, RF64 or AU (it trims
    # the length to the bytes present) or MP3 without a word: 2 s of a 15 s song
    # analysed as the whole song
    import soundfile as sf

    if fmt not in sf.available_formats():
        pytest.skip(f"this libsndfile does not write {fmt}")
    sr = 22050
    t = np.arange(15 * sr) / sr
    y = (0.3 * np.sin(2 * np.pi * 440.0 * t) * (np.sin(2 * np.pi * 2 * t) > 0)).astype(np.float32)
    whole = tmp_path / f"whole{suffix}"
    sf.write(whole, y, sr, format=fmt)
    assert io.read_audio(whole)[0].size == pytest.approx(y.size, rel=0.01)
    cut = tmp_path / f"cut{suffix}"
    cut.write_bytes(whole.read_bytes()[: whole.stat().st_size // 4])
    with pytest.raises(ParameterError, match=r"cut short.*15\.0"):
        io.read_audio(cut)


def _ogg_pages(data: bytes) -> list[int]:
    """Offsets of an Ogg file's pages (by walking their headers)."""
    at, pages = 0, []
    while at < len(data):
        assert data[at : at + 4] == b"OggS"
        pages.append(at)
        n = data[at + 26]
        at += 27 + n + sum(data[at + 27 : at + 27 + n])
    assert at == len(data)
    return pages


def test_an_ogg_file_cut_short_is_refused(tmp_path):
    # libsndfile decodes an Ogg stream until its data ends: a cut file read silently
    import soundfile as sf

    sr = 22050
    t = np.arange(15 * sr) / sr
    y = (0.3 * np.sin(2 * np.pi * 440.0 * t) * (np.sin(2 * np.pi * 2 * t) > 0)).astype(np.float32)
    whole = tmp_path / "whole.ogg"
    sf.write(whole, y, sr, format="OGG", subtype="VORBIS")
    assert io.read_audio(whole)[0].size == y.size
    data = whole.read_bytes()
    pages = _ogg_pages(data)
    assert len(pages) > 4
    for name, size in (("mid_page", len(data) // 3), ("page_boundary", pages[len(pages) // 2])):
        cut = tmp_path / f"{name}.ogg"
        cut.write_bytes(data[:size])
        with pytest.raises(ParameterError, match=rf"{name}\.ogg.*read 3\.2"):
            io.read_audio(cut)
    # bytes after the last page (a tag some tools append) are not a truncation
    trailing = tmp_path / "trailing.ogg"
    trailing.write_bytes(data + b"TAG" + b"\0" * 125)
    assert io.read_audio(trailing)[0].size == y.size


def _mp3_cut(tmp_path, fraction):
    import soundfile as sf

    if "MP3" not in sf.available_formats():
        pytest.skip("this libsndfile does not write MP3")
    y = (0.3 * np.sin(np.arange(10 * 22050) / 5)).astype(np.float32)
    whole = tmp_path / "whole.mp3"
    sf.write(whole, y, 22050, format="MP3")
    cut = tmp_path / f"cut{fraction}.mp3"
    cut.write_bytes(whole.read_bytes()[: int(whole.stat().st_size * fraction)])
    return cut


def test_the_mp3_decoders_own_messages_become_a_warning(tmp_path, capfd):
    # libmpg123 printed "Warning: Xing stream size off..." to the process's stderr,
    # beside (and with --json, inside) the command's own output
    cut = _mp3_cut(tmp_path, 0.985)  # short by less than the cut-short check refuses
    with pytest.warns(BeatsyncWarning, match="libmpg123"):
        y, sr = io.read_audio(cut)
    assert y.size > 9 * sr
    assert "Xing" not in capfd.readouterr().err


def test_a_cut_mp3_gives_only_the_json_error_on_stderr(tmp_path):
    cut = _mp3_cut(tmp_path, 0.66)
    proc = subprocess.run(
        [sys.executable, "-m", "beatsync.cli", "beats", str(cut), "--json"],
        capture_output=True,
        text=True,
    )
    assert proc.returncode == 3
    error = json.loads(proc.stderr)
    assert "is cut short" in error["error"]


@pytest.mark.parametrize("placeholder", [b"\xff\xff\xff\xff", b"\x00\xf0\xff\x7f"])
def test_a_streamed_wav_with_no_data_size_is_read(tmp_path, placeholder):
    # writers that cannot seek leave the data size at 0xFFFFFFFF, SoX at 0x7FFFF000:
    # not a truncation (the SoX one was refused as announcing 134217 s)
    y = (0.1 * np.sin(np.arange(4410) / 5.0)).astype(np.float32)
    path = io.write_audio(tmp_path / "s.wav", y, 22050)
    raw = bytearray(path.read_bytes())
    at = raw.index(b"data")
    raw[at + 4 : at + 8] = placeholder
    path.write_bytes(bytes(raw))
    y, sr = io.read_audio(path)
    assert sr == 22050 and y.size == 4410


@pytest.mark.parametrize("size", [2**63 - 1, 2**64 - 1])
def test_a_streamed_w64_with_no_data_size_is_read(tmp_path, size):
    # ffmpeg writing W64 to a pipe leaves the 64-bit size at 0x7FFF...FF: it was
    # refused as announcing 96 million million seconds
    import struct

    import soundfile as sf

    y = (0.3 * np.sin(np.arange(3 * 8000) / 5)).astype(np.float32)
    path = tmp_path / "s.w64"
    sf.write(path, y, 8000, format="W64", subtype="PCM_16")
    raw = bytearray(path.read_bytes())
    at = raw.index(b"data\xf3\xac\xd3\x11")
    raw[at + 16 : at + 24] = struct.pack("<Q", size)
    path.write_bytes(bytes(raw))
    assert io.read_audio(path)[0].size == y.size
    # a chunk before the data whose size no file can hold: read, not a traceback
    raw = bytearray(path.read_bytes())
    fmt = raw.index(b"fmt \xf3\xac\xd3\x11")
    junk = b"junk\xf3\xac\xd3\x11\x8c\xd1\x00\xc0\x4f\x8e\xdb\x8a" + struct.pack("<Q", 2**64 - 1)
    raw[fmt:fmt] = junk  # (libsndfile skips a chunk of that size; not one of 2**63 - 1)
    path.write_bytes(bytes(raw))
    assert io.read_audio(path)[0].size == y.size


def test_an_aiff_sox_wrote_to_a_pipe_is_read(tmp_path):
    # SoX announces 0x7F000000 bytes of audio (in whole frames) when it cannot seek back
    import math
    import struct

    channels, width, sr = 2, 2, 44100
    frames = 0x7F000000 // (channels * width)
    exponent = math.floor(math.log2(sr))
    rate = struct.pack(">HQ", exponent + 16383, int(sr / 2**exponent * 2**63))
    data = (np.sin(np.arange(3 * sr * channels) / 7) * 3000).astype(">i2").tobytes()
    head = b"FORM" + struct.pack(">I", 46 + frames * channels * width) + b"AIFF"
    head += b"COMM" + struct.pack(">IhIh", 18, channels, frames, 16) + rate
    head += b"SSND" + struct.pack(">III", 8 + frames * channels * width, 0, 0)
    path = tmp_path / "sox.aiff"
    path.write_bytes(head + data)
    y, got_sr = io.read_audio(path)
    assert (y.size, got_sr) == (3 * sr, sr)


def test_beats_files(tmp_path):
    y, sr, beats = datasets.load_madmom_sample()
    np.testing.assert_allclose(beats, [0.0913, 0.7997, 1.4806, 2.1478])
    p = io.write_beats(tmp_path / "b.beats", beats)
    np.testing.assert_allclose(io.read_beats(p), beats)
    (tmp_path / "bad.beats").write_text("1.0\n0.5\n")
    with pytest.raises(ParameterError, match=r"#1 \(0\.5 s\)"):
        io.read_beats(tmp_path / "bad.beats")
    (tmp_path / "ms.beats").write_text("abc\n")
    with pytest.raises(ParameterError, match=r"line 1: 'abc'"):
        io.read_beats(tmp_path / "ms.beats")
    with pytest.raises(ParameterError, match=r"#1 \(1\.0 s\)"):
        io.write_beats(tmp_path / "w.beats", [2.0, 1.0])
    assert not (tmp_path / "w.beats").exists()


def test_csv_without_header_refused(tmp_path):
    np.savetxt(tmp_path / "noheader.csv", np.arange(12.0).reshape(6, 2) + 0.5, delimiter=",")
    with pytest.raises(ParameterError, match=r"noheader\.csv"):
        io.read_motion(tmp_path / "noheader.csv", fps=25)


def test_atomic_write_respects_umask_and_existing_mode(tmp_path):
    import os

    old = os.umask(0o077)
    try:
        p = io.write_beats(tmp_path / "private.beats", [0.5, 1.0])
    finally:
        os.umask(old)
    assert p.stat().st_mode & 0o777 == 0o600
    p.chmod(0o640)
    io.write_beats(p, [0.5, 1.5])
    assert p.stat().st_mode & 0o777 == 0o640


# ------------------------------------------------------------ hardened readers


def _wav_with_header_rate(tmp_path: Path, rate: int) -> Path:
    import struct

    p = io.write_audio(tmp_path / "a.wav", np.full(4410, 0.1, dtype=np.float32), 44100)
    data = bytearray(p.read_bytes())
    assert data[:4] == b"RIFF" and data[12:16] == b"fmt "
    data[24:28] = struct.pack("<I", rate)  # sample rate field of the fmt chunk
    p.write_bytes(bytes(data))
    return p


def test_wav_with_sample_rate_zero_refused(tmp_path):
    p = _wav_with_header_rate(tmp_path, 0)
    with pytest.raises(ParameterError, match=r"a\.wav.*sample rate=0"):
        io.read_audio(p)


def test_wav_with_valid_header_rate_read(tmp_path):
    y, sr = io.read_audio(_wav_with_header_rate(tmp_path, 8000))
    assert sr == 8000 and y.dtype == np.float32 and y.size == 4410


@pytest.mark.parametrize("sr, match", [(0, "sr=0"), (22050.5, r"sr=22050\.5")])
def test_read_and_write_audio_bad_sr(tmp_path, sr, match):
    p = io.write_audio(tmp_path / "a.wav", np.full(4410, 0.1, dtype=np.float32), 44100)
    with pytest.raises(ParameterError, match=match):
        io.read_audio(p, sr=sr)
    with pytest.raises(ParameterError, match=match):
        io.write_audio(tmp_path / "b.wav", np.zeros(10), sr)
    assert not (tmp_path / "b.wav").exists()


def test_npz_renamed_npy_refused(tmp_path):
    np.savez(tmp_path / "m.npz", values=np.zeros((5, 2)))
    p = (tmp_path / "m.npz").rename(tmp_path / "m.npy")
    with pytest.raises(ParameterError, match=r"m\.npy"):
        io.read_motion(p, fps=25)


@pytest.mark.parametrize(
    "array, match",
    [
        (np.array([["a", "b"]] * 4), "holds strings"),
        (np.array([[b"a", b"b"]] * 4), "holds bytes"),
        (np.zeros((4, 2), dtype=[("x", "f8"), ("y", "f8")]), "structured array"),
        (np.zeros(4, dtype=[("x", "f8"), ("y", "f8")]), "structured array"),
        (np.ones((4, 2)) * (1 + 1j), "complex"),
        (np.zeros((4, 2), dtype="datetime64[s]"), "dates"),
        (np.zeros((4, 2), dtype="timedelta64[s]"), "time deltas"),
        (np.ones((4, 2), dtype=bool), "booleans"),
        (np.array([[1.0, None]] * 4, dtype=object), "Python objects"),
        (np.zeros((4, 2, 3, 1)), r"shape \(4, 2, 3, 1\); need 2-D"),
    ],
)
def test_npy_dtype_and_shape_checks(tmp_path, array, match):
    p = tmp_path / "t.npy"
    np.save(p, array, allow_pickle=True)
    with pytest.raises(ParameterError, match=match):
        io.read_motion(p, fps=25)


def test_npy_numeric_kinds_read(tmp_path):
    for dtype in (np.int16, np.float32, np.float16):
        np.save(tmp_path / "t.npy", np.arange(8).reshape(4, 2).astype(dtype))
        m = io.read_motion(tmp_path / "t.npy", fps=25)
        assert m.values.dtype == np.float64 and m.values[3, 1] == 7.0


def test_mat_struct_without_freq_refused(tmp_path):
    import scipy.io

    rec = {"data": np.zeros((10, 3)), "markerName": np.array(["Head"], dtype=object)}
    scipy.io.savemat(tmp_path / "m.mat", {"rec": rec})
    with pytest.raises(ParameterError, match=r"'rec'.*'freq'"):
        io.read_mocap_mat(tmp_path / "m.mat")
    scipy.io.savemat(tmp_path / "m0.mat", {"rec": {**rec, "freq": 0.0}})
    with pytest.raises(ParameterError, match=r"freq=0\.0"):
        io.read_mocap_mat(tmp_path / "m0.mat")
    scipy.io.savemat(tmp_path / "ok.mat", {"rec": {**rec, "freq": 100.0}})
    assert io.read_mocap_mat(tmp_path / "ok.mat").fps == 100.0


# ------------------------------------------------------------ BVH reader hardening

_FRAME1 = "0 1 0 0 0 0 0 10 0"
_FRAME2 = "0 1 0 0 0 0 0 20 0"


@pytest.mark.parametrize(
    "old, new, match",
    [
        # values sliding between frames: 10 + 8 values, the total (18) matches 2 x 9
        (
            f"{_FRAME1}\n{_FRAME2}",
            f"{_FRAME1} 5\n0 1 0 0 0 0 0 20",
            r"line 19: frame line 1 has 10",
        ),
        (
            " OFFSET 0 -1 0\n  CHANNELS",
            " OFFSET nan -1 0\n  CHANNELS",
            r"line 8: OFFSET of joint 'knee' is not finite",
        ),
        (
            "   OFFSET 0 -1 0\n  }",
            "   OFFSET 0 inf 0\n  }",
            r"line 12: OFFSET of End Site of 'knee' is not finite",
        ),
        (
            "CHANNELS 3 Zrotation Xrotation",
            "CHANNELS 3 Zrotation Zrotation",
            r"line 9: channel Zrotation listed twice in joint 'knee'",
        ),
        ("  OFFSET 0 -1 0\n  CHANNELS", "  CHANNELS", r"line 6: joint 'knee'.*OFFSET"),
        ("   OFFSET 0 -1 0\n  }", "  }", r"line 10: End Site of 'knee'.*OFFSET"),
        (
            " CHANNELS 6 Xposition Yposition Zposition Zrotation Xrotation Yrotation\n",
            "",
            r"line 2: joint 'hip' has no CHANNELS line",
        ),
        ("JOINT knee", "JOINT hip", r"line 6: duplicate .*'hip'.*line 2"),
        (
            "OFFSET 0 -1 0\n  CHANNELS",
            "OFFSET 0 -1 0 7\n  CHANNELS",
            r"line 8: OFFSET is followed by '7'",
        ),
        (
            "OFFSET 0 -1 0\n  CHANNELS",
            "OFFSET 0 -1\n  CHANNELS",
            r"line 8: OFFSET needs 3 values on its line, got 2",
        ),
        (
            "CHANNELS 3 Zrotation Xrotation Yrotation",
            "CHANNELS 2 Zrotation Xrotation Yrotation",
            r"line 9: CHANNELS 2 is followed by 'Yrotation'",
        ),
        (
            "OFFSET 0 -1 0\n  CHANNELS",
            "OFFSET 0 -1 0\n  OFFSET 0 -1 0\n  CHANNELS",
            r"line 9: a second OFFSET in joint 'knee'",
        ),
        (_FRAME2, "0 1 0 0 0 0 0 2_0 0", r"line 20: non-numeric value '2_0'"),
        (_FRAME2, "0 1 0 0 0 0 0 \u0662 0", r"line 20: non-numeric value"),
        ("Frames: 2", "Frames: 2.5", r"line 17: Frames=.2.5. must be a whole number"),
        ("Frames: 2", "Frames: -1", r"line 17: Frames=.-1. must be an integer >= 0"),
        ("Frame Time: 0.04", "Frame Time 0.04", r"line 18: .*'Frame Time"),
        ("Frames: 2", "Frames: 1000000000000", r"declares 1000000000000 frames but has 2"),
        ("MOTION", "MOTION extra", r"line 16: .*'extra'"),
        ("  End Site", "  End Sight", r"line 10: .*'End Sight'"),
    ],
)
def test_bvh_malformed_with_line_numbers(tmp_path, old, new, match):
    assert old in GOOD
    with pytest.raises(ParameterError, match=match):
        io.read_bvh(_write(tmp_path, GOOD.replace(old, new, 1)))


def test_bvh_non_utf8_refused(tmp_path):
    p = tmp_path / "latin.bvh"
    p.write_bytes(GOOD.replace("knee", "kn\xe9e").encode("latin-1"))
    with pytest.raises(ParameterError, match="line 6"):
        io.read_bvh(p)


@pytest.mark.parametrize(
    "variant",
    [
        "\ufeff" + GOOD,  # UTF-8 byte-order mark
        GOOD.replace("knee", "MOTIONx"),
        GOOD.replace("knee", "MOTION"),  # a joint may even be called MOTION
        GOOD.replace("Frame Time:", "Frame  Time:"),
        GOOD.replace("Frame Time:", "Frame\tTime:"),
        GOOD.replace("Frames: 2", "Frames:2").replace("Frame Time: ", "FRAME TIME :"),
        GOOD.replace("\n", "\r\n"),
        GOOD.replace(" ", "\t"),
        GOOD.replace("ROOT hip\n{", "ROOT hip {"),
        GOOD + "\n\n",
    ],
)
def test_bvh_valid_variants_read(tmp_path, variant):
    p = tmp_path / "v.bvh"
    p.write_bytes(variant.encode("utf-8"))
    m = io.read_bvh(p)
    ref = io.read_bvh(_write(tmp_path, GOOD))
    np.testing.assert_array_equal(m.values, ref.values)
    assert m.fps == 25.0 and m.n_channels == 9
    assert [j.parent for j in m.skeleton.joints] == [-1, 0, 1]


def _sibling_bvh(n: int, *, same_name: bool = False) -> str:
    body = "{\nOFFSET 0 1 0\nCHANNELS 1 Xrotation\nEnd Site\n{\nOFFSET 0 1 0\n}\n}\n"
    joints = "".join(f"JOINT j{'' if same_name else i}\n{body}" for i in range(n))
    frame = " ".join(["0"] * (n + 3))
    return (
        "HIERARCHY\nROOT hip\n{\nOFFSET 0 0 0\nCHANNELS 3 Xposition Yposition Zposition\n"
        f"{joints}}}\nMOTION\nFrames: 2\nFrame Time: 0.04\n{frame}\n{frame}\n"
    )


def _best_time(fn, repeats=3):
    import time

    best = np.inf
    for _ in range(repeats):
        t0 = time.perf_counter()
        fn()
        best = min(best, time.perf_counter() - t0)
    return best


def test_bvh_parse_is_linear_in_joint_count(tmp_path):
    small, large = tmp_path / "s.bvh", tmp_path / "l.bvh"
    small.write_text(_sibling_bvh(1000))
    large.write_text(_sibling_bvh(4000))
    assert io.read_bvh(large).skeleton.joints[-1].name == "j3999_end"
    ratio = _best_time(lambda: io.read_bvh(large)) / _best_time(lambda: io.read_bvh(small))
    # linear: ~4; quadratic: ~16
    assert ratio < 10, ratio


def test_bvh_duplicate_joint_names_refused_in_linear_time(tmp_path):
    valid, dup = tmp_path / "v.bvh", tmp_path / "d.bvh"
    valid.write_text(_sibling_bvh(5000))
    dup.write_text(_sibling_bvh(5000, same_name=True))

    def read_dup():
        with pytest.raises(ParameterError, match=r"line 15: duplicate .*'j'.*line 6"):
            io.read_bvh(dup)

    # refusing 5,000 same-named siblings costs no more than reading 5,000 distinct ones
    # (a pairwise name count took seconds)
    ratio = _best_time(read_dup, repeats=2) / _best_time(lambda: io.read_bvh(valid), repeats=2)
    assert ratio < 3, ratio


def _chain_bvh(depth: int) -> str:
    lines = [
        "HIERARCHY",
        "ROOT j0",
        "{",
        "OFFSET 0 0 0",
        "CHANNELS 3 Xposition Yposition Zposition",
    ]
    for i in range(1, depth):
        lines += [f"JOINT j{i}", "{", "OFFSET 0 1 0", "CHANNELS 1 Zrotation"]
    lines += ["End Site", "{", "OFFSET 0 1 0", "}"] + ["}"] * depth
    frame = " ".join(str(k % 7) for k in range(depth + 2))
    return "\n".join(lines + ["MOTION", "Frames: 1", "Frame Time: 0.01", frame]) + "\n"


def test_write_bvh_deep_skeleton_round_trip(tmp_path):
    p = tmp_path / "deep.bvh"
    p.write_text(_chain_bvh(2000))
    m = io.read_bvh(p)
    assert len(m.skeleton.joints) == 2001
    back = io.read_bvh(io.write_bvh(tmp_path / "w.bvh", m))
    np.testing.assert_array_equal(back.values, m.values)
    assert back.skeleton.joints == m.skeleton.joints


def test_write_bvh_refuses_nan_offset(tmp_path, chain_motion):
    from dataclasses import replace

    from beatsync.motion import Skeleton

    joints = list(chain_motion.skeleton.joints)
    joints[1] = replace(joints[1], offset=np.array([0.0, np.nan, 0.0]))
    m = Motion(
        chain_motion.values, chain_motion.fps, chain_motion.channels, Skeleton(tuple(joints))
    )
    with pytest.raises(ParameterError, match="OFFSET of joint 'thigh'"):
        io.write_bvh(tmp_path / "x.bvh", m)
    assert not (tmp_path / "x.bvh").exists()


# ------------------------------------------------------------ bit-stable JSON


def test_write_json_float_digits_hides_last_digit_noise(tmp_path):
    a = {"score": 0.1 + 0.2, "arr": np.array([1 / 3, 2.0]), "f32": np.float32(0.25), "n": 3}
    b = {"score": 0.3, "arr": np.array([1 / 3 + 1e-16, 2.0]), "f32": 0.25, "n": 3}
    pa = io.write_json(tmp_path / "a.json", a, float_digits=10)
    pb = io.write_json(tmp_path / "b.json", b, float_digits=10)
    assert pa.read_bytes() == pb.read_bytes()
    import json

    assert json.loads(pa.read_text()) == {
        "score": 0.3,
        "arr": [0.3333333333, 2.0],
        "f32": 0.25,
        "n": 3,
    }
    # default: exact floats
    exact = io.write_json(tmp_path / "e.json", {"score": 0.1 + 0.2})
    assert "0.30000000000000004" in exact.read_text()


@pytest.mark.parametrize("digits", [0, 18, 2.5, True])
def test_write_json_bad_float_digits(tmp_path, digits):
    with pytest.raises(ParameterError, match=rf"float_digits={digits!r}"):
        io.write_json(tmp_path / "x.json", {"a": 1.0}, float_digits=digits)
    assert not (tmp_path / "x.json").exists()


def test_npy_renamed_npz_refused(tmp_path):
    np.save(tmp_path / "a.npy", np.zeros((3, 2)))
    p = (tmp_path / "a.npy").rename(tmp_path / "a.npz")
    with pytest.raises(ParameterError, match=r"a\.npz"):
        io.read_npz(p)
    (tmp_path / "t.npz").write_bytes(b"PK\x03\x04 broken zip")
    with pytest.raises(ParameterError, match=r"t\.npz"):
        io.read_npz(tmp_path / "t.npz")


def test_mat_without_marker_struct_refused(tmp_path):
    import scipy.io

    scipy.io.savemat(tmp_path / "m.mat", {"rec": {"data": np.zeros((10, 3)), "freq": 100.0}})
    with pytest.raises(ParameterError, match=r"\['rec'\]"):
        io.read_mocap_mat(tmp_path / "m.mat")


@pytest.mark.parametrize(
    "text, match",
    [("a,b\n1,2\n3\n", r"line 3: 1 fields, but the header"), ("a,b\n1,2,5\n3,4\n", "line 2: 3")],
)
def test_csv_row_with_wrong_field_count_refused(tmp_path, text, match):
    (tmp_path / "t.csv").write_text(text)
    with pytest.raises(ParameterError, match=match):
        io.read_motion(tmp_path / "t.csv", fps=25)


def test_csv_with_byte_order_mark_read(tmp_path):
    (tmp_path / "t.csv").write_text("a,b\n1,2\n3,4\n", encoding="utf-8-sig")
    assert io.read_motion(tmp_path / "t.csv", fps=25).channels == ("a", "b")


def test_jsonl_append_survives_a_torn_line(tmp_path):
    from beatsync.io import append_jsonl, read_jsonl, write_jsonl

    p = tmp_path / "rows.jsonl"
    assert read_jsonl(p) == []
    append_jsonl(p, {"a": 1, "x": np.float32(0.5)})
    with open(p, "a") as fh:
        fh.write('{"a": 2, "x"')  # a run killed while appending
    append_jsonl(p, {"a": 3}, {"a": 5})  # several rows: one line each, in one write
    assert read_jsonl(p) == [{"a": 1, "x": 0.5}, {"a": 3}, {"a": 5}]
    assert p.read_text().count("\n") == 4  # the torn line stays a line of its own
    write_jsonl(p, [{"a": 4}, {"b": [1, 2]}])
    assert read_jsonl(p) == [{"a": 4}, {"b": [1, 2]}]
    append_jsonl(p, {"c": float("nan")})  # JSON has no NaN: null
    assert read_jsonl(p)[-1] == {"c": None}
