import numpy as np
import pytest

from beatsync.errors import ParameterError
from beatsync.motion import Motion
from beatsync.rotations import blend_values, euler_to_rotation, rotation_to_euler, sample_motion

CH = ("root_Xposition", "j_Zrotation", "j_Xrotation", "j_Yrotation")


def test_sampling_at_frame_times_is_identity(chain_motion):
    out = sample_motion(chain_motion, chain_motion.times)
    np.testing.assert_allclose(out, chain_motion.values, atol=1e-9)


def test_slerp_across_wrap_takes_short_way():
    m = Motion(np.array([[0.0, 170.0, 0, 0], [1.0, -170.0, 0, 0]]), 1.0, CH)
    out = sample_motion(m, np.linspace(0, 1, 5))
    # linear Euler interpolation would pass through 0 deg; slerp goes through 180
    z = out[:, 1]
    assert np.all(np.abs(np.abs(z) - 180) <= 10 + 1e-9)
    np.testing.assert_allclose(out[:, 0], np.linspace(0, 1, 5))
    np.testing.assert_allclose(abs(out[2, 1]), 180.0, atol=1e-6)


def test_sampled_rotation_matches_geodesic(rng):
    a = rng.uniform(-180, 180, (20, 3)) * np.array([1, 0.45, 1])
    b = rng.uniform(-180, 180, (20, 3)) * np.array([1, 0.45, 1])
    m = Motion(np.zeros((2, 4)), 1.0, CH)
    va = np.c_[np.zeros(20), a]
    vb = np.c_[np.zeros(20), b]
    out = blend_values(m, va, vb, np.full(20, 0.5))
    ra, rb = euler_to_rotation(a, "ZXY"), euler_to_rotation(b, "ZXY")
    mid = euler_to_rotation(out[:, 1:], "ZXY")
    # the midpoint is equidistant from both ends, at half their angle
    d_a = (ra.inv() * mid).magnitude()
    d_b = (rb.inv() * mid).magnitude()
    d_ab = (ra.inv() * rb).magnitude()
    np.testing.assert_allclose(d_a, d_b, atol=1e-9)
    np.testing.assert_allclose(d_a, d_ab / 2, atol=1e-9)


def test_blend_endpoints_and_errors(chain_motion):
    a = chain_motion.values[:10]
    b = chain_motion.values[10:20]
    np.testing.assert_allclose(blend_values(chain_motion, a, b, np.zeros(10)), a, atol=1e-9)
    np.testing.assert_allclose(blend_values(chain_motion, a, b, np.ones(10)), b, atol=1e-9)
    with pytest.raises(ParameterError, match=r"\(5, 12\)"):
        blend_values(chain_motion, a, b[:5], np.zeros(10))
    with pytest.raises(ParameterError, match="got 2 to 2"):
        blend_values(chain_motion, a, b, np.full(10, 2.0))
    with pytest.raises(ParameterError, match=r"times .*index \(0,\)"):
        sample_motion(chain_motion, np.array([np.nan]))


@pytest.mark.parametrize(
    "channels, v0, v1, expected",
    [
        (("knee_Zrotation",), [179.0], [-179.0], [180.0]),
        (("elbow_Zrotation", "elbow_Xrotation"), [170.0, 10.0], [-170.0, 30.0], [180.0, 20.0]),
    ],
)
def test_one_and_two_axis_joints_interpolate_the_short_way(channels, v0, v1, expected):
    m = Motion(np.array([v0, v1]), 10.0, channels)
    out = sample_motion(m, np.array([0.05]))[0]
    np.testing.assert_allclose(np.abs(out), np.abs(expected), atol=1e-9)


def test_continuous_euler_removes_flips():
    from beatsync.rotations import continuous_euler, nearest_euler

    e = np.array([[170.0, 10.0, 0.0], [-175.0, 10.0, 0.0], [-10.0, 170.0, 180.0]])
    out = continuous_euler(e)
    np.testing.assert_allclose(out[1], [185.0, 10.0, 0.0])
    # the third row is the alternative triple of (170, 10, 0): it maps back next to it
    np.testing.assert_allclose(out[2], [170.0, 10.0, 0.0], atol=1e-9)
    r = euler_to_rotation(e, "ZXY")
    np.testing.assert_allclose(
        (euler_to_rotation(out, "ZXY").inv() * r).magnitude(), 0.0, atol=1e-9
    )
    np.testing.assert_allclose(nearest_euler(e[:1], e[:1]), e[:1])


@pytest.mark.parametrize("axes", ["ZXY", "XYZ", "ZYX", "YXZ", "ZX", "Y", "ZXZ", "zxy"])
def test_quaternions_match_scipy(axes):
    from scipy.spatial.transform import Rotation

    from beatsync.quaternions import quat_from_euler, quat_multiply, quat_rotate

    rng = np.random.default_rng(3)
    a = rng.uniform(-400, 400, (200, len(axes)))
    ref = Rotation.from_euler(axes.upper(), a, degrees=True)
    q = quat_from_euler(a, axes)
    assert np.allclose(Rotation.from_quat(q).as_matrix(), ref.as_matrix(), atol=1e-12)
    v = rng.normal(size=(200, 3))
    assert np.allclose(quat_rotate(q, v), ref.apply(v), atol=1e-12)
    b = Rotation.random(200, random_state=4)
    prod = quat_multiply(q, b.as_quat())
    assert np.allclose(Rotation.from_quat(prod).as_matrix(), (ref * b).as_matrix(), atol=1e-12)


@pytest.mark.parametrize(
    "axes, shape", [("ZXW", (3, 3)), ("", (3, 0)), ("ZXYZ", (3, 4)), ("ZXY", (3, 2))]
)
def test_quat_from_euler_refuses_bad_axes_or_shapes(axes, shape):
    from beatsync.quaternions import quat_from_euler

    with pytest.raises(ParameterError, match=f"'{axes}'"):
        quat_from_euler(np.zeros(shape), axes)


def test_euler_at_gimbal_lock_is_silent_and_exact():
    import warnings

    angles = np.array([[30.0, 90.0, 20.0], [10.0, -90.0, 45.0], [5.0, 20.0, 7.0]])
    rot = euler_to_rotation(angles, "ZXY")
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # scipy's "Gimbal lock detected" was printed per frame
        back = rotation_to_euler(rot, "ZXY", reference=angles)
    assert np.allclose((euler_to_rotation(back, "ZXY") * rot.inv()).magnitude(), 0.0, atol=1e-6)
