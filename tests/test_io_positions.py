"""Joint-position motion files: Dance-with-Melody JSON, (n, J, 3) arrays, C3D."""

import json
import warnings

import numpy as np
import pytest

from beatsync import io
from beatsync.errors import ParameterError
from beatsync.io.positions import detect_units, detect_up, from_canonical, to_canonical

FPS = 25.0


def _body(n=60):
    """A 7-joint standing figure [m, z up]: feet, pelvis, neck, head, hands; it sways."""
    t = np.arange(n) / FPS
    sway = 0.05 * np.sin(2 * np.pi * t)
    swing = 0.2 * np.sin(2 * np.pi * 0.8 * t)
    pts = [
        (0.0, 0.0, 0.05),
        (0.3, 0.0, 0.05),
        (0.15, 0.0, 0.95),
        (0.15, 0.0, 1.5),
        (0.15, 0.0, 1.72),
        (-0.15, 0.0, 1.0),
        (0.45, 0.0, 1.0),
    ]
    pos = np.repeat(np.array(pts)[None], n, axis=0)
    pos[:, 2:, 0] += sway[:, None]
    pos[:, 5, 1] += swing
    pos[:, 6, 1] -= swing
    pos[:, :, 0] += 0.4 * t[:, None]  # travels along x
    return pos


def _dwm_json(path, pos_m, *, units="cm", up="y", extra=None):
    """Write the Dance-with-Melody layout: skeletons relative to a centre track."""
    file_pos = from_canonical(pos_m, units=units, up=up)
    center = file_pos[:, 2].copy()  # the pelvis as root
    doc = {
        "length": len(pos_m),
        "center": center.tolist(),
        "skeletons": (file_pos - center[:, None]).tolist(),
    }
    doc.update(extra or {})
    path.write_text(json.dumps(doc))
    return path


# --------------------------------------------------------------------------- JSON


def test_json_read_detects_cm_y_up_and_round_trips(tmp_path):
    pos = _body()
    src = _dwm_json(tmp_path / "skeletons.json", pos)
    m = io.read_motion(src, fps=FPS)
    assert m.is_positional and m.skeleton is None and m.fps == FPS
    assert m.name == tmp_path.name  # a file named skeletons.json is named by its folder
    np.testing.assert_allclose(m.positions(), pos, atol=1e-12)  # absolute, metres, z up
    info = m.position_info
    assert (info.layout, info.units, info.up) == ("json", "cm", "y")
    assert (info.units_source, info.up_source) == ("detected", "detected")
    assert "cm (detected), y up (detected)" in info.describe()
    out = io.write_motion(tmp_path / "out.json", m)
    a, b = json.loads(out.read_text()), json.loads(src.read_text())
    assert list(a) == list(b) == ["length", "center", "skeletons"]
    np.testing.assert_allclose(a["skeletons"], b["skeletons"], atol=1e-9)
    np.testing.assert_allclose(a["center"], b["center"], atol=1e-9)


def test_json_resampled_motion_is_written_with_a_new_centre(tmp_path):
    m = io.read_motion(_dwm_json(tmp_path / "a.json", _body()), fps=FPS)
    shorter = m.with_values(m.values[::2], fps=FPS / 2)  # centre track no longer matches
    back = io.read_motion(io.write_motion(tmp_path / "b.json", shorter), fps=FPS / 2)
    np.testing.assert_allclose(back.positions(), shorter.positions(), atol=1e-12)


def test_given_units_and_up_are_stated(tmp_path):
    pos = _body()
    src = _dwm_json(tmp_path / "mm.json", pos, units="mm", up="z")
    m = io.read_motion(src, fps=FPS, units="mm", up="z")
    np.testing.assert_allclose(m.positions(), pos, atol=1e-12)
    assert m.position_info.describe().startswith("json file in mm (given), z up (given)")


def test_json_nan_short_gap_filled(tmp_path):
    doc = json.loads(_dwm_json(tmp_path / "a.json", _body()).read_text())
    for f in (10, 11):
        doc["skeletons"][f][4] = [None, None, None]
    (tmp_path / "gap.json").write_text(json.dumps(doc))
    m = io.read_motion(tmp_path / "gap.json", fps=FPS)
    assert np.isfinite(m.values).all()
    np.testing.assert_allclose(m.positions()[10:12, 4], _body()[10:12, 4], atol=0.02)


@pytest.mark.parametrize(
    ("edit", "match"),
    [
        (
            lambda d: {"frames": d["skeletons"]},
            r"\['frames'\]",
        ),
        (lambda d: d["skeletons"], r"bad\.json.*\(list\)"),
        (
            lambda d: {
                **d,
                "skeletons": d["skeletons"][:2] + [d["skeletons"][2][:4]] + d["skeletons"][3:],
            },
            r"'skeletons' .*frame 2 has 4 joints, frame 0 has 7",
        ),
        (
            lambda d: {**d, "skeletons": [f[:1] for f in d["skeletons"]]},
            r"bad\.json' has 1 joint",
        ),
        (
            lambda d: {**d, "skeletons": [[p[:2] for p in f] for f in d["skeletons"]]},
            r"frame 0 joint 0 has 2 coordinates",
        ),
        (
            lambda d: {
                **d,
                "skeletons": [
                    [[None] * 3 if (j == 3 and 5 <= i < 25) else p for j, p in enumerate(f)]
                    for i, f in enumerate(d["skeletons"])
                ],
            },
            r"'j3' is missing \(NaN\) for 20 frames \(0\.80 s, frames 5-24\)",
        ),
        (lambda d: {**d, "length": 99}, r"length=99 but 'skeletons' has 60 frames"),
        (lambda d: {**d, "center": d["center"][:-1]}, r"'center' has shape \(59, 3\)"),
    ],
)
def test_json_bad_input(tmp_path, edit, match):
    doc = json.loads(_dwm_json(tmp_path / "a.json", _body()).read_text())
    bad = tmp_path / "bad.json"
    bad.write_text(json.dumps(edit(doc)))
    with pytest.raises(ParameterError, match=match):
        io.read_motion(bad, fps=FPS)


def test_json_needs_fps(tmp_path):
    src = _dwm_json(tmp_path / "a.json", _body())
    with pytest.raises(ParameterError, match=r"a\.json.*fps="):
        io.read_motion(src)


@pytest.mark.parametrize(
    ("kw", "match"),
    [({"up": "x"}, r"up='x'"), ({"units": "in"}, r"units='in'")],
)
def test_bad_up_or_units(tmp_path, kw, match):
    src = _dwm_json(tmp_path / "a.json", _body())
    with pytest.raises(ParameterError, match=match):
        io.read_motion(src, fps=FPS, **kw)


def test_wrong_given_unit_refused(tmp_path):
    src = _dwm_json(tmp_path / "a.json", _body())  # centimetres
    with pytest.raises(ParameterError, match=r"units='m' .*167 m"):
        io.read_motion(src, fps=FPS, units="m")


def test_detection_refuses_ambiguous_bodies():
    cube = np.random.default_rng(0).uniform(0, 1, size=(20, 8, 3))
    cube[..., 2] = cube[..., 1]  # as tall as deep
    with pytest.raises(ParameterError, match=r"0\.734 along y and 0\.734 along z"):
        detect_up(cube)
    with pytest.raises(ParameterError, match=r"16\.7 file units"):
        detect_units(_body() * 10.0, "z")  # 17 units tall: not m, cm or mm
    np.testing.assert_allclose(
        from_canonical(to_canonical(_body(), units="cm", up="y"), units="cm", up="y"), _body()
    )


# --------------------------------------------------------------------------- arrays


def test_npy_positions_round_trip_and_tables_unchanged(tmp_path):
    pos = _body()
    np.save(tmp_path / "kp.npy", from_canonical(pos, units="mm", up="y"))
    m = io.read_motion(tmp_path / "kp.npy", fps=30.0)
    assert (m.position_info.units, m.position_info.up) == ("mm", "y")
    np.testing.assert_allclose(m.positions(), pos, atol=1e-12)
    out = io.write_motion(tmp_path / "out.npy", m)
    np.testing.assert_allclose(np.load(out), np.load(tmp_path / "kp.npy"), atol=1e-9)
    # a 2-D .npy is still an angle table, and up/units do not apply to it
    np.save(tmp_path / "table.npy", np.zeros((10, 4)))
    assert not io.read_motion(tmp_path / "table.npy", fps=30.0).is_positional
    with pytest.raises(ParameterError, match=r"up='y'.*table\.npy"):
        io.read_motion(tmp_path / "table.npy", fps=30.0, up="y")


def test_npz_key_found_named_and_fps_stored(tmp_path):
    pos_cm = from_canonical(_body(), units="cm", up="y")
    np.savez(tmp_path / "aist.npz", keypoints3d=pos_cm, other=pos_cm[:, :3], fps=60.0)
    m = io.read_motion(tmp_path / "aist.npz")
    assert m.fps == 60.0 and m.position_info.key == "keypoints3d"
    m2 = io.read_motion(tmp_path / "aist.npz", variable="other", fps=60.0)
    assert m2.joint_names == ["j0", "j1", "j2"]
    with pytest.raises(ParameterError, match=r"fps=25\.0 .*\(60 Hz\)"):
        io.read_motion(tmp_path / "aist.npz", fps=25.0)
    with pytest.raises(ParameterError, match=r"'pose'"):
        io.read_motion(tmp_path / "aist.npz", variable="pose")
    np.savez(tmp_path / "two.npz", a=pos_cm, b=pos_cm)
    with pytest.raises(ParameterError, match=r"two\.npz.*\['a', 'b'\]"):
        io.read_motion(tmp_path / "two.npz", fps=FPS)
    back = io.read_motion(io.write_motion(tmp_path / "out.npz", m))
    assert back.fps == 60.0 and back.position_info.key == "keypoints3d"
    np.testing.assert_allclose(back.positions(), m.positions(), atol=1e-12)


# --------------------------------------------------------------------------- C3D


def test_c3d_round_trip_rate_labels_units(tmp_path):
    m = io.read_motion(_dwm_json(tmp_path / "a.json", _body()), fps=FPS)
    named = m.rename("clip")
    out = io.write_motion(tmp_path / "clip.c3d", named)
    back = io.read_motion(out)
    assert back.fps == FPS and back.joint_names == m.joint_names
    assert back.position_info.units_source == "file"  # POINT:UNITS
    np.testing.assert_allclose(back.positions(), m.positions(), atol=1e-5)  # float32
    with pytest.raises(ParameterError, match=r"fps=30 .*\(25 Hz\)"):
        io.read_motion(out, fps=30)
    assert io.read_motion(out, fps=FPS).fps == FPS  # agreeing is fine


def test_c3d_cut_short_is_refused(tmp_path):
    # the c3d package stops at the end of the data with a warning (which the reader
    # ignores): two thirds of a file read as the whole motion
    m = io.read_motion(_dwm_json(tmp_path / "a.json", _body()), fps=FPS)
    whole = io.write_motion(tmp_path / "whole.c3d", m).read_bytes()
    cut = tmp_path / "cut.c3d"
    cut.write_bytes(whole[: len(whole) * 2 // 3])
    with pytest.raises(ParameterError, match=rf"cut\.c3d.*{m.n_frames} frames"):
        io.read_motion(cut)


def test_c3d_without_points_refused(tmp_path):
    import c3d

    w = c3d.Writer(point_rate=50.0, analog_rate=100.0)
    w.set_analog_labels(["emg"])
    w.add_frames([(np.zeros((0, 5), np.float32), np.ones((1, 2), np.float32))] * 3)
    with open(tmp_path / "analog.c3d", "wb") as fh, warnings.catch_warnings():
        warnings.simplefilter("ignore")
        w.write(fh)
    with pytest.raises(ParameterError, match=r"analog\.c3d"):
        io.read_motion(tmp_path / "analog.c3d")


def test_c3d_invalid_points_are_gaps(tmp_path):
    m = io.read_motion(_dwm_json(tmp_path / "a.json", _body()), fps=FPS)
    io.write_motion(tmp_path / "c.c3d", m)
    import c3d

    with open(tmp_path / "c.c3d", "rb") as fh, warnings.catch_warnings():
        warnings.simplefilter("ignore")
        reader = c3d.Reader(fh)
        writer = c3d.Writer(point_rate=FPS, point_units="cm  ")
        writer.set_point_labels(list(m.joint_names))
        frames = []
        for i, points, _ in reader.read_frames():
            pts = points.copy()
            if 20 <= i < 40:
                pts[5, 3] = -1.0  # 'not seen' for 20 frames
            frames.append((pts, np.zeros((0, 0), np.float32)))
        writer.add_frames(frames)
    with open(tmp_path / "gap.c3d", "wb") as fh, warnings.catch_warnings():
        warnings.simplefilter("ignore")
        writer.write(fh)
    with pytest.raises(ParameterError, match=r"'j5' is missing \(NaN\) for 20 frames"):
        io.read_motion(tmp_path / "gap.c3d")
    assert np.isfinite(io.read_motion(tmp_path / "gap.c3d", max_gap=1.0).values).all()


# --------------------------------------------------------------------------- writing


def test_bvh_output_of_positions_refused_with_alternative(tmp_path):
    m = io.read_motion(_dwm_json(tmp_path / "a.json", _body()), fps=FPS)
    with pytest.raises(
        ParameterError,
        match=r"out\.bvh.*write \.json, \.npy or \.c3d",
    ):
        io.write_motion(tmp_path / "out.bvh", m)
    assert not (tmp_path / "out.bvh").exists()


def test_write_motion_tables_and_bvh(tmp_path, chain_motion):
    out = io.write_motion(tmp_path / "c.bvh", chain_motion)
    assert io.read_motion(out).skeleton.same_structure(chain_motion.skeleton)
    csv = io.write_motion(tmp_path / "c.csv", chain_motion)
    assert io.read_motion(csv, fps=chain_motion.fps).n_channels == chain_motion.n_channels
    with pytest.raises(ParameterError, match=r"'chain' .*\.json"):
        io.write_motion(tmp_path / "c.json", chain_motion)
    with pytest.raises(ParameterError, match=r"c\.txt"):
        io.write_motion(tmp_path / "c.txt", chain_motion)
