import numpy as np
import pytest

from beatsync import datasets
from beatsync.errors import ParameterError
from beatsync.motion import (
    Motion,
    PositionInfo,
    bone_lengths,
    fill_gaps,
    fill_joint_gaps,
    infer_bones,
    marker_angles,
    segmentation_view,
)


def test_forward_kinematics_chain(chain_motion):
    m = chain_motion.with_values(np.zeros_like(chain_motion.values))
    pos = m.positions()
    # rest pose: hip at origin, thigh +x 0.1, shin below, end site below
    np.testing.assert_allclose(pos[0, 1], [0.1, 0.0, 0.0])
    np.testing.assert_allclose(pos[0, 3], [0.1, -0.8, 0.0])
    values = np.zeros_like(chain_motion.values)
    values[:, 7] = 90.0  # thigh Xrotation +90 deg: the leg swings to +z
    pos = chain_motion.with_values(values).positions()
    np.testing.assert_allclose(pos[0, 2], [0.1, 0.0, -0.4], atol=1e-12)


def test_segment_lengths_preserved(chain_motion):
    pos = chain_motion.positions()
    lengths = np.linalg.norm(pos[:, 3] - pos[:, 2], axis=1)
    np.testing.assert_allclose(lengths, 0.4)


def test_salsa_kinematics_plausible():
    m = datasets.load_salsa("60_01")
    pos = m.positions()
    assert pos.shape == (2242, len(m.joint_names), 3)
    head = pos[:, m.skeleton.index("head"), 1]
    foot = pos[:, m.skeleton.index("lFoot"), 1]
    # metres, y up: the head joint (base of the skull) about 1 m above the ankle joint
    # (this conversion's rig is scaled a little small); not centimetres or inches
    assert 0.8 < np.median(head - foot) < 2.0
    root_speed = np.linalg.norm(np.diff(pos[:, 0], axis=0), axis=1) * m.fps
    assert 0.05 < np.median(root_speed) < 1.0  # at 60 fps: about 0.3 m/s


def test_rotation_triples(chain_motion):
    trip = chain_motion.rotation_triples()
    assert trip[0] == ("hip", (3, 4, 5), "ZXY")
    assert [t[0] for t in trip] == ["hip", "thigh", "shin"]


def test_shape_errors():
    with pytest.raises(ParameterError, match="5 value columns but 3 channel"):
        Motion(np.zeros((3, 5)), 30.0, ("a", "b", "c"))
    with pytest.raises(ParameterError, match="fps=0.0"):
        Motion(np.zeros((3, 1)), 0.0, ("a",))
    with pytest.raises(ParameterError, match="0:10 is outside 0:3"):
        Motion(np.zeros((3, 1)), 30.0, ("a",)).slice_frames(0, 10)
    with pytest.raises(ParameterError, match="'tab'"):
        Motion(np.zeros((3, 1)), 30.0, ("a",), name="tab").positions()


def test_marker_angles_dance2():
    a = marker_angles(datasets.load_mocap_toolbox("dance2"))
    assert a.fps == 60.0 and a.n_frames == 1500
    knee = a.values[:, a.channel_index("knee_L_angle")]
    assert 90 < knee.mean() < 180 and knee.std() > 1.0


def test_fill_gaps():
    v = np.array([[0.0], [np.nan], [2.0], [np.nan]])
    out = fill_gaps(Motion(v, 10.0, ("a",)))
    np.testing.assert_allclose(out.values[:, 0], [0, 1, 2, 2])
    walk = datasets.load_mocap_toolbox("walk1")
    assert np.isnan(walk.values).any()
    assert np.isfinite(marker_angles(walk).values).all()


# -- position-only motion ------------------------------------------------------------


def _chain_positions(n=200, fps=25.0):
    """A planar 5-joint figure (bones 0-1, 1-2, 2-3, 1-4) bending and travelling."""
    t = np.arange(n) / fps
    a1 = 0.6 * np.sin(2 * np.pi * 1.0 * t)
    a2 = 0.9 * np.sin(2 * np.pi * 0.7 * t + 1.0)
    a4 = 1.2 * np.sin(2 * np.pi * 0.45 * t + 2.0)
    p0 = np.stack([0.3 * t, np.zeros(n), np.ones(n)], axis=1)
    p1 = p0 + 0.5 * np.stack([np.sin(a1), np.zeros(n), np.cos(a1)], axis=1)
    p2 = p1 + 0.4 * np.stack([np.sin(a1 + a2), np.zeros(n), np.cos(a1 + a2)], axis=1)
    p3 = p2 + 0.3 * np.stack([np.sin(a2), np.zeros(n), np.cos(a2)], axis=1)
    p4 = p1 + 0.45 * np.stack([np.sin(a4), 0.3 * np.ones(n), -np.cos(a4)], axis=1)
    return np.stack([p0, p1, p2, p3, p4], axis=1)


def _positional(pos, fps=25.0, **kw):
    names = [f"j{i}" for i in range(pos.shape[1])]
    ch = tuple(f"{j}_{a}" for j in names for a in "xyz")
    return Motion(pos.reshape(len(pos), -1), fps, ch, **kw)


def test_positional_motion_positions_and_bones():
    pos = _chain_positions()
    m = _positional(pos)
    assert m.is_positional
    assert m.joint_names == ["j0", "j1", "j2", "j3", "j4"]
    np.testing.assert_array_equal(m.positions(), pos)  # no kinematics: the data itself
    got = {tuple(sorted(b)) for b in m.bones.tolist()}
    assert got == {(0, 1), (1, 2), (2, 3), (1, 4)}
    given = _positional(pos, position_info=PositionInfo(bones=[[0, 1], [1, 2]]))
    np.testing.assert_array_equal(given.bones, [[0, 1], [1, 2]])
    lengths = bone_lengths(m.positions(), m.bones)
    assert lengths.shape == (200, 4) and np.ptp(lengths, axis=0).max() < 1e-9


def test_is_positional_false_for_bvh_tables_and_partial_triples(chain_motion):
    assert not chain_motion.is_positional
    assert not Motion(np.zeros((3, 2)), 30.0, ("knee_angle", "hip_angle")).is_positional
    assert not Motion(np.zeros((3, 3)), 30.0, ("a_x", "a_y", "b_z")).is_positional
    assert datasets.load_mocap_toolbox("dance2").is_positional


def test_position_info_refused_on_other_channels():
    with pytest.raises(ParameterError, match=r"\['a', 'b'\]"):
        Motion(np.zeros((3, 2)), 30.0, ("a", "b"), position_info=PositionInfo())


@pytest.mark.parametrize(
    ("bones", "match"),
    [
        ([[0, 1, 2]], r"shape \(1, 3\)"),
        ([[0, 5]], r"joint 5 .*0\.\.4"),
        ([[2, 2]], r"\[2, 2\]"),
        ([[0.5, 1]], r"0\.5"),
    ],
)
def test_bad_bones(bones, match):
    with pytest.raises(ParameterError, match=match):
        _positional(_chain_positions(), position_info=PositionInfo(bones=bones))


def test_infer_bones_needs_two_joints():
    with pytest.raises(ParameterError, match="got 1"):
        infer_bones(np.zeros((10, 1, 3)))


def test_fill_joint_gaps_short_filled_long_refused():
    pos = _chain_positions()
    short = pos.copy()
    short[50:53, 2] = np.nan  # 3 frames = 0.12 s at 25 fps
    filled = fill_joint_gaps(short, 25.0, max_gap=0.25)
    assert np.isfinite(filled).all()
    np.testing.assert_allclose(filled[50:53, 2], pos[50:53, 2], atol=0.05)
    long = pos.copy()
    long[50:70, 3, 1] = np.nan  # 20 frames = 0.8 s
    with pytest.raises(ParameterError, match=r"'j3' .*20 frames"):
        fill_joint_gaps(long, 25.0, max_gap=0.25, joint_names=["j0", "j1", "j2", "j3", "j4"])
    names = np.array(["j0", "j1", "j2", "j3", "j4"])  # names as an array too
    with pytest.raises(ParameterError, match=r"'j3' "):
        fill_joint_gaps(long, 25.0, max_gap=0.25, joint_names=names)


def test_segmentation_view_of_keypoints_is_bone_angles():
    m = _positional(_chain_positions())
    view = segmentation_view(m)
    assert "j0-j1-j2_angle" in view.channels and view.n_channels == 4
    a1 = 0.6 * np.sin(2 * np.pi * np.arange(200) / 25.0)
    # the angle at j1 between j0 and j2 is 180 deg - |a2|: independent of travel
    knee = view.values[:, view.channel_index("j0-j1-j2_angle")]
    assert np.all((knee > 90) & (knee <= 180.0 + 1e-9))
    assert np.ptp(a1) > 0  # the figure moves
    # MoCap Toolbox markers keep their named joint angles
    assert "knee_L_angle" in segmentation_view(datasets.load_mocap_toolbox("dance2")).channels


def test_slice_keeps_center_track():
    pos = _chain_positions()
    center = pos[:, 0].copy()
    m = _positional(pos, position_info=PositionInfo(layout="json", center=center))
    part = m.slice_frames(10, 20)
    np.testing.assert_array_equal(part.position_info.center, center[10:20])
    assert part.with_values(part.values).position_info.layout == "json"
