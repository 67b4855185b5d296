import numpy as np
import pytest

from beatsync import datasets
from beatsync.errors import ParameterError
from beatsync.motion import Motion, fill_gaps, marker_angles


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
    with pytest.raises(ParameterError, match="transposed"):
        Motion(np.zeros((3, 5)), 30.0, ("a", "b", "c"))
    with pytest.raises(ParameterError, match="fps"):
        Motion(np.zeros((3, 1)), 0.0, ("a",))
    with pytest.raises(ParameterError, match="frame indices"):
        Motion(np.zeros((3, 1)), 30.0, ("a",)).slice_frames(0, 10)
    with pytest.raises(ParameterError, match="no skeleton"):
        Motion(np.zeros((3, 1)), 30.0, ("a",)).positions()


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
