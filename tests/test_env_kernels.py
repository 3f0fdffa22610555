"""The environments' step kernels against the quaternion library (the oracle) and scipy."""

from __future__ import annotations

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st
from hypothesis.extra.numpy import arrays
from scipy.spatial.transform import Rotation

from motion_envs.envs import _kernels as K
from motion_envs.geometry import quaternion as quat


def _random_inputs(rng: np.random.Generator, n: int):
    def unit(size):
        q = rng.normal(size=(size, 4))
        return q / np.linalg.norm(q, axis=1, keepdims=True)

    scales = rng.choice([1e-9, 1e-5, 1e-3, 0.3, 2.0, 3.1], size=(n, 1))
    e = quat.expmap(rng.normal(size=(n, 3)) * scales)
    nominal = unit(n)
    human = unit(n)
    human[:50] = nominal[:50]  # geodesic error exactly at 0
    r = rng.normal(size=(n, 3)) * 0.3
    a = rng.uniform(-1, 1, size=(n, 3))
    a[:100] = 0.0
    a[100:200] *= 1e-6  # small-angle series of expmap
    return e, nominal, human, r, a


def test_scalar_batch_and_generic_kernels_are_bit_identical():
    rng = np.random.default_rng(0)
    e, nominal, human, r, a = _random_inputs(rng, 5000)
    qb, eb, gb = K.orientation_step(
        K.BATCH, tuple(e.T), tuple(nominal.T), tuple(human.T), *r.T, *a.T, 0.3
    )
    rows = np.concatenate([e, nominal, human, r], axis=1)
    for i in range(rows.shape[0]):
        q, err, geo = K.orientation_step_scalar(rows[i].tolist(), *a[i].tolist(), 0.3)
        q2, err2, geo2 = K.orientation_step(
            K.SCALAR, tuple(e[i]), tuple(nominal[i]), tuple(human[i]), *r[i], *a[i], 0.3
        )
        assert q == q2 == tuple(float(c[i]) for c in qb)
        assert err == err2 == eb[i]
        assert geo == geo2 == gb[i]


def test_kernel_matches_quaternion_library_and_scipy():
    rng = np.random.default_rng(1)
    e, nominal, human, r, a = _random_inputs(rng, 3000)
    qb, eb, gb = K.orientation_step(
        K.BATCH, tuple(e.T), tuple(nominal.T), tuple(human.T), *r.T, *a.T, 0.3
    )
    d = quat.expmap(0.3 * a)
    np.testing.assert_allclose(np.stack(qb, 1), quat.multiply(nominal, d), atol=1e-15)
    expected = np.linalg.norm(quat.logmap(quat.multiply(e, d)) - r, axis=1)
    np.testing.assert_allclose(eb, expected, atol=1e-14)
    # geodesic angle against scipy's magnitude of the relative rotation
    rel = quat.to_rotation(human).inv() * quat.to_rotation(quat.multiply(nominal, d))
    np.testing.assert_allclose(gb, rel.magnitude(), atol=1e-7)
    np.testing.assert_allclose(gb, quat.angle(np.stack(qb, 1), human), atol=1e-14)


def test_expmap_kernel_equals_scipy_rotvec():
    rng = np.random.default_rng(2)
    v = rng.normal(size=(1000, 3)) * rng.choice([1e-8, 1e-4, 1.0, 3.0], size=(1000, 1))
    w, x, y, z = K.expmap(K.BATCH, *v.T)
    xyzw = Rotation.from_rotvec(v).as_quat()
    np.testing.assert_allclose(np.stack([x, y, z, w], 1), xyzw, atol=1e-15)


@settings(max_examples=200, deadline=None)
@given(
    v=arrays(
        np.float64,
        (20, 4),
        elements=st.floats(-1, 1, allow_subnormal=False, allow_nan=False),
    ).filter(lambda a: np.all(np.linalg.norm(a, axis=1) > 1e-3))
)
def test_half_angle_matches_numpy_arctan2(v):
    # unit up to 1e-9, as a near-linear slerp may return
    q = v / np.linalg.norm(v, axis=1, keepdims=True) * (1.0 - 1e-9)
    s = np.linalg.norm(q[:, 1:], axis=1)
    w = np.abs(q[:, 0])
    got = K.half_angle(K.BATCH, s, w)
    np.testing.assert_allclose(got, np.arctan2(s, w), rtol=0, atol=1e-15)
    for i in range(3):
        assert K.half_angle(K.SCALAR, float(s[i]), float(w[i])) == got[i]


def test_half_angle_hand_worked_values():
    # (s, w) = (sin h, cos h) for h = 0, pi/6, pi/4, pi/3, pi/2
    h = np.array([0.0, np.pi / 6, np.pi / 4, np.pi / 3, np.pi / 2])
    got = K.half_angle(K.BATCH, np.sin(h), np.cos(h))
    np.testing.assert_allclose(got, h, rtol=0, atol=4e-16)
