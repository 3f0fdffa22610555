"""Quaternion geometry against scipy's Rotation/Slerp and hand-worked cases."""

from __future__ import annotations

import functools

import numpy as np
import pytest
from hypothesis import assume, given, settings
from hypothesis import strategies as st
from hypothesis.extra.numpy import arrays
from scipy.spatial.transform import Rotation, Slerp

from motion_envs.geometry import quaternion as quat

finite = st.floats(-1e3, 1e3, allow_nan=False, allow_infinity=False)


@st.composite
def unit_quaternions(draw, shape=()):
    raw = draw(arrays(np.float64, (*shape, 4), elements=st.floats(-1, 1, allow_nan=False)))
    norms = np.linalg.norm(raw, axis=-1)
    assume(np.all(norms > 1e-3))
    return raw / norms[..., None]


def same_rotation(p: np.ndarray, q: np.ndarray, atol: float = 1e-12) -> bool:
    """True where p and q are the same orientation (q or -q)."""
    return np.allclose(np.abs(np.einsum("...i,...i->...", p, q)), 1.0, atol=atol)


def to_scipy(q: np.ndarray) -> Rotation:
    return Rotation.from_quat(q.reshape(-1, 4)[:, [1, 2, 3, 0]])


@pytest.fixture
def rng() -> np.random.Generator:
    return np.random.default_rng(12345)


@pytest.fixture
def batch(rng):
    r = Rotation.random(500, random_state=7)
    return quat.from_rotation(r), r


# --- oracle comparisons ---------------------------------------------------------------


def test_multiply_matches_scipy_composition(batch):
    q, r = batch
    p_rot = Rotation.random(500, random_state=8)
    p = quat.from_rotation(p_rot)
    ours = quat.multiply(q, p)
    ref = quat.from_rotation(r * p_rot)
    assert same_rotation(ours, ref)


def test_multiply_hand_worked():
    i = np.array([0.0, 1, 0, 0])
    j = np.array([0.0, 0, 1, 0])
    k = np.array([0.0, 0, 0, 1])
    np.testing.assert_array_equal(quat.multiply(i, j), k)
    np.testing.assert_array_equal(quat.multiply(j, i), -k)
    np.testing.assert_array_equal(quat.multiply(i, i), [-1.0, 0, 0, 0])


def test_multiply_broadcasts():
    q = quat.from_rotation(Rotation.random(6, random_state=1)).reshape(2, 3, 4)
    p = quat.from_rotation(Rotation.random(1, random_state=2))[0]
    out = quat.multiply(q, p)
    assert out.shape == (2, 3, 4)
    np.testing.assert_allclose(out[1, 2], quat.multiply(q[1, 2], p))


def test_conjugate_is_inverse(batch):
    q, _ = batch
    prod = quat.multiply(q, quat.conjugate(q))
    np.testing.assert_allclose(prod, np.broadcast_to(quat.IDENTITY, prod.shape), atol=1e-15)


def test_expmap_matches_from_rotvec(rng):
    v = rng.normal(size=(1000, 3)) * rng.uniform(0, np.pi, size=(1000, 1))
    ours = quat.expmap(v)
    ref = quat.from_rotation(Rotation.from_rotvec(v))
    assert same_rotation(ours, ref)
    np.testing.assert_allclose(np.linalg.norm(ours, axis=-1), 1.0, atol=1e-15)


def test_logmap_matches_as_rotvec(batch):
    q, r = batch
    np.testing.assert_allclose(quat.logmap(q), r.as_rotvec(), atol=1e-12)


def test_to_from_rotation_roundtrip(batch):
    q, r = batch
    back = quat.from_rotation(quat.to_rotation(q))
    np.testing.assert_allclose(back, q, atol=1e-15)
    np.testing.assert_allclose(quat.to_rotation(q).as_matrix(), r.as_matrix(), atol=1e-14)


def test_angle_matches_scipy_magnitude(batch):
    q, r = batch
    p_rot = Rotation.random(500, random_state=9)
    ours = quat.angle(q, quat.from_rotation(p_rot))
    ref = (r.inv() * p_rot).magnitude()
    np.testing.assert_allclose(ours, ref, atol=1e-12)


def test_slerp_matches_scipy_slerp(rng):
    keys = Rotation.random(2, random_state=3)
    times = rng.uniform(0, 1, size=200)
    ref = Slerp([0.0, 1.0], keys)(times)
    q = quat.from_rotation(keys)
    ours = quat.slerp(q[0], q[1], times)
    assert same_rotation(ours, quat.from_rotation(ref))


def test_slerp_batched_matches_scipy(rng):
    r0 = Rotation.random(300, random_state=4)
    r1 = Rotation.random(300, random_state=5)
    a = rng.uniform(0, 1, size=300)
    ref = r0 * Rotation.from_rotvec((r0.inv() * r1).as_rotvec() * a[:, None])
    ours = quat.slerp(quat.from_rotation(r0), quat.from_rotation(r1), a)
    assert same_rotation(ours, quat.from_rotation(ref), atol=1e-11)


def test_slerp_broadcasts_over_time_grid():
    q0 = quat.from_rotation(Rotation.random(4, random_state=1))
    q1 = quat.from_rotation(Rotation.random(4, random_state=2))
    grid = np.linspace(0, 1, 7)
    out = quat.slerp(q0[:, None], q1[:, None], grid[None, :])
    assert out.shape == (4, 7, 4)
    np.testing.assert_allclose(out[2, 3], quat.slerp(q0[2], q1[2], grid[3]))


# --- hand-worked cases ----------------------------------------------------------------


def test_expmap_hand_worked():
    # 90 degrees about z: (cos 45, 0, 0, sin 45)
    np.testing.assert_allclose(
        quat.expmap([0.0, 0.0, np.pi / 2]), [np.sqrt(0.5), 0, 0, np.sqrt(0.5)], atol=1e-16
    )
    np.testing.assert_array_equal(quat.expmap(np.zeros(3)), quat.IDENTITY)


def test_slerp_halfway_hand_worked():
    q1 = quat.expmap([np.pi / 2, 0.0, 0.0])
    mid = quat.slerp(quat.IDENTITY, q1, 0.5)
    np.testing.assert_allclose(mid, quat.expmap([np.pi / 4, 0.0, 0.0]), atol=1e-15)


def test_slerp_takes_short_arc_for_flipped_end():
    q1 = quat.expmap([0.0, 0.4, 0.0])
    out_pos = quat.slerp(quat.IDENTITY, q1, 0.3)
    out_neg = quat.slerp(quat.IDENTITY, -q1, 0.3)
    assert same_rotation(out_pos, out_neg)
    np.testing.assert_allclose(quat.logmap(out_neg), [0.0, 0.12, 0.0], atol=1e-15)


def test_make_continuous_flips_antipodal_jumps():
    traj = quat.slerp(quat.IDENTITY, quat.expmap([0, 0, 1.0]), np.linspace(0, 1, 9))
    signs = np.array([1, 1, -1, -1, 1, -1, 1, 1, -1.0])
    jumbled = traj * signs[:, None]
    fixed = quat.make_continuous(jumbled)
    np.testing.assert_allclose(fixed, traj, atol=1e-16)
    # batched, time axis -2
    both = quat.make_continuous(np.stack([jumbled, -jumbled]))
    np.testing.assert_allclose(both[0], traj, atol=1e-16)
    np.testing.assert_allclose(both[1], -traj, atol=1e-16)


# --- properties -----------------------------------------------------------------------


@settings(max_examples=200, deadline=None)
@given(unit_quaternions())
def test_exp_log_roundtrip_up_to_sign(q):
    assert same_rotation(quat.expmap(quat.logmap(q)), q)


@settings(max_examples=200, deadline=None)
@given(arrays(np.float64, (3,), elements=st.floats(-1, 1, allow_nan=False)), st.floats(0, 3.1))
def test_log_exp_roundtrip_for_angles_below_pi(direction, theta):
    n = np.linalg.norm(direction)
    assume(n > 1e-3)
    v = direction / n * theta
    np.testing.assert_allclose(quat.logmap(quat.expmap(v)), v, atol=1e-12)


@settings(max_examples=200, deadline=None)
@given(unit_quaternions())
def test_distance_to_negation_is_zero(q):
    assert quat.angle(q, -q) == pytest.approx(0.0, abs=1e-12)
    assert quat.angle(q, q) == pytest.approx(0.0, abs=1e-12)


@settings(max_examples=100, deadline=None)
@given(unit_quaternions(), unit_quaternions())
def test_slerp_hits_ends_with_constant_angular_speed(q0, q1):
    alphas = np.linspace(0, 1, 11)
    path = quat.slerp(q0, q1, alphas)
    assert same_rotation(path[0], q0, atol=1e-12)
    assert same_rotation(path[-1], q1, atol=1e-12)
    total = quat.angle(q0, q1)
    steps = quat.angle(path[:-1], path[1:])
    np.testing.assert_allclose(steps, total / 10, atol=1e-9)
    np.testing.assert_allclose(np.linalg.norm(path, axis=-1), 1.0, atol=1e-12)


@settings(max_examples=100, deadline=None)
@given(unit_quaternions(), st.floats(0, 1))
def test_slerp_with_coincident_ends_is_constant(q, a):
    out = quat.slerp(q, q, a)
    assert np.all(np.isfinite(out))
    np.testing.assert_allclose(out, q, atol=1e-15)
    out_neg = quat.slerp(q, -q, a)
    assert same_rotation(out_neg, q)


@pytest.mark.parametrize("eps", [0.0, 1e-8, -1e-8, 1e-12])
def test_angles_near_zero_and_pi(eps):
    axis = np.array([0.3, -0.5, 0.8]) / np.linalg.norm([0.3, -0.5, 0.8])
    for theta in (abs(eps), np.pi - abs(eps)):
        v = axis * theta
        q = quat.expmap(v)
        assert np.all(np.isfinite(q))
        np.testing.assert_allclose(quat.angle(quat.IDENTITY, q), theta, atol=1e-12)
        np.testing.assert_allclose(quat.logmap(q), v, atol=1e-9)
        assert same_rotation(quat.from_rotation(Rotation.from_rotvec(v)), q)


def test_antipodal_and_half_turn_pairs():
    q = quat.expmap([0.2, 0.1, -0.4])
    half_turn = quat.multiply(q, quat.expmap([0, np.pi, 0]))
    assert quat.angle(q, half_turn) == pytest.approx(np.pi, abs=1e-12)
    mid = quat.slerp(q, half_turn, 0.5)
    assert quat.angle(q, mid) == pytest.approx(np.pi / 2, abs=1e-12)
    assert np.all(np.isfinite(quat.slerp(q, -q, np.linspace(0, 1, 5))))


def test_dot_rounded_above_one_never_gives_nan():
    q = np.array([1.0, 1e-9, 0.0, 0.0])
    q = q / np.linalg.norm(q)
    p = q * (1 + 2e-16)  # |q . p| slightly above 1 in floating point
    assert np.all(np.isfinite(quat.angle(q, p)))
    assert np.all(np.isfinite(quat.slerp(q, p, 0.5)))
    assert np.all(np.isfinite(quat.logmap(p)))


# --- bad input ------------------------------------------------------------------------


@pytest.mark.parametrize(
    ("func", "args", "name"),
    [
        (quat.logmap, ([1.0, np.nan, 0, 0],), "q"),
        (quat.angle, ([1.0, 0, 0, 0], [2.0, 0, 0, 0]), "q"),
        (quat.slerp, ([1.0, 0, 0], [1.0, 0, 0, 0], 0.5), "q0"),
        (quat.slerp, ([1.0, 0, 0, 0], [0.5, 0, 0, 0], 0.5), "q1"),
        (quat.normalize, ([0.0, 0, 0, 0],), "q"),
        (quat.normalize, ([np.inf, 0, 0, 0],), "q"),
        (quat.as_unit, ([1.0, 0.1, 0, 0],), "q"),
        (quat.expmap, ([1.0, 0.0],), "v"),
        (quat.make_continuous, (np.ones((3, 5)),), "q"),
    ],
)
def test_bad_input_raises_value_error_naming_argument(func, args, name):
    with pytest.raises(ValueError, match=rf"^{name}\b"):
        func(*args)


def test_slerp_rejects_nan_alpha():
    with pytest.raises(ValueError, match="alpha"):
        quat.slerp(quat.IDENTITY, quat.IDENTITY, np.nan)


def test_normalize_returns_unit():
    out = quat.normalize([[2.0, 0, 0, 0], [1.0, 1.0, 1.0, 1.0]])
    np.testing.assert_allclose(out, [[1.0, 0, 0, 0], [0.5, 0.5, 0.5, 0.5]])


@pytest.mark.parametrize("half", [1e-5, 9e-5, 2e-4])
def test_slerp_of_nearly_coincident_ends_stays_unit(half):
    q0 = quat.expmap([0.3, -0.2, 0.5])
    q1 = quat.multiply(q0, quat.expmap(np.array([0.0, 0.0, 2 * half])))
    a = np.linspace(0, 1, 11)
    out = quat.slerp(q0, q1, a)
    np.testing.assert_allclose(np.linalg.norm(out, axis=-1), 1.0, atol=1e-15)
    ref = quat.multiply(q0, quat.expmap(np.outer(a, [0.0, 0.0, 2 * half])))
    np.testing.assert_allclose(out, ref, atol=1e-15)


def test_malformed_shapes_raise_value_error():
    for func, args, name in (
        (quat.multiply, (np.ones(3), quat.IDENTITY), "p"),
        (quat.multiply, (quat.IDENTITY, np.ones((2, 5))), "q"),
        (quat.logmap, (np.ones(3),), "q"),
    ):
        with pytest.raises(ValueError, match=rf"^{name} must have a last axis of length 4"):
            func(*args)
    with pytest.raises(ValueError, match="q0"):
        quat.slerp(np.ones(3), quat.IDENTITY, 0.5, validate=False)


# --- the one shared input check of expmap / logmap / conjugate / multiply --------------

_Q = quat.IDENTITY
_V = np.zeros(3)
_BAD_QUATERNIONS = {
    "nan": np.array([1.0, np.nan, 0.0, 0.0]),
    "inf": np.array([np.inf, 0.0, 0.0, 0.0]),
    "-inf in a batch": np.vstack([np.tile(_Q, (5, 1)), [[1.0, 0.0, -np.inf, 0.0]]]),
    "nan in a large batch": np.vstack([np.tile(_Q, (5000, 1)), [[1.0, 0.0, np.nan, 0.0]]]),
    "inf in a large batch": np.vstack([[[1.0, 0.0, np.inf, 0.0]], np.tile(_Q, (5000, 1))]),
    "-inf in a large batch": np.vstack([np.tile(_Q, (5000, 1)), [[-np.inf, 0.0, 0.0, 0.0]]]),
    "opposite infinities": np.array([[np.inf, -np.inf, 0.0, 0.0]]),
    "scalar": np.float64(1.0),
    "last axis 3": np.ones(3),
    "last axis 5": np.ones((2, 5)),
    "strings": np.array(["1", "0", "0", "0"]),
    "complex": np.array([1.0 + 1j, 0, 0, 0]),
    "object": np.array([{}, 0, 0, 0], dtype=object),
}
_BAD_VECTORS = {
    "nan": np.array([np.nan, 0.0, 0.0]),
    "inf": np.array([[0.0, np.inf, 0.0]]),
    "scalar": 0.5,
    "last axis 4": np.zeros(4),
    "strings": ["a", "b", "c"],
    "complex": np.array([1j, 0.0, 0.0]),
}


def _calls(kind: str, bad: object):
    if kind == "v":
        return [(quat.expmap, (bad,), "v")]
    return [
        (quat.logmap, (bad,), "q"),
        (functools.partial(quat.logmap, validate=False), (bad,), "q"),
        (quat.conjugate, (bad,), "q"),
        (quat.multiply, (bad, _Q), "p"),
        (quat.multiply, (_Q, bad), "q"),
    ]


@pytest.mark.parametrize(
    ("kind", "case"),
    [("q", c) for c in _BAD_QUATERNIONS] + [("v", c) for c in _BAD_VECTORS],
)
def test_geometry_rejects_nan_inf_and_wrong_shapes(kind, case):
    bad = (_BAD_QUATERNIONS if kind == "q" else _BAD_VECTORS)[case]
    for func, args, name in _calls(kind, bad):
        with pytest.raises(ValueError, match=rf"^{name} (must|contains)"):
            func(*args)


def test_finite_values_whose_sum_overflows_are_accepted():
    # the fast finiteness test sums; a finite input summing beyond float64 must pass
    big = np.array([[1e308, 1e308, 1e308, 1e308]])
    np.testing.assert_array_equal(quat.conjugate(big), [[1e308, -1e308, -1e308, -1e308]])
    many = np.full((5000, 4), 1e308)
    np.testing.assert_array_equal(quat.conjugate(many)[:, 1:], -1e308)


def test_empty_batches_pass_the_check():
    assert quat.conjugate(np.empty((0, 4))).shape == (0, 4)
    assert quat.expmap(np.empty((0, 3))).shape == (0, 4)


def test_integer_and_float32_input_still_accepted():
    np.testing.assert_array_equal(quat.conjugate([1, 0, 0, 0]), [1.0, 0.0, 0.0, 0.0])
    out = quat.multiply(np.float32([1, 0, 0, 0]), _Q)
    assert out.dtype == np.float64
