"""The juggling ids' native vector environments: bit-identical to SyncVectorEnv.

Juggling-v1's and Cascade-v0's (both batched with numba, and their ``backend="python"``)
against ``gymnasium.vector.SyncVectorEnv`` of ``gym.make`` copies, in the three autoreset
modes, with the zero action (long episodes: catches, corrections, releases) and random
actions (drops, resets); the cascade's contact sensors against MuJoCo's contact list; the
compiled ``math.hypot``; the arguments' errors.
"""

from __future__ import annotations

import math
from typing import Any

import gymnasium as gym
import numpy as np
import pytest
from gymnasium.vector import AutoresetMode
from hypothesis import given, settings
from hypothesis import strategies as st

import motion_envs  # noqa: F401  (registers the ids)
from motion_envs.envs._kernels import numba_available
from motion_envs.envs.juggling import CascadeVectorEnv, JugglingV1VectorEnv
from motion_envs.envs.juggling._vector import PHASE_NAMES, numeric_info

V1 = "MotionEnvs/Juggling-v1"
CASCADE = "MotionEnvs/Cascade-v0"
MODES = (AutoresetMode.NEXT_STEP, AutoresetMode.SAME_STEP, AutoresetMode.DISABLED)
needs_numba = pytest.mark.skipif(not numba_available(), reason="numba is not installed")


def _equal(x: Any, y: Any) -> bool:
    if isinstance(x, np.ndarray) and x.dtype == object:
        return all(_equal(p, q) for p, q in zip(x, y, strict=True))
    return bool(np.array_equal(x, y))


def _as_codes(column: Any) -> Any:
    """A SyncVectorEnv's batched text info column as the native env's numbers: names of
    ``PHASE_NAMES`` -> their indices; tuples (a value per hand) -> rows."""
    if not (isinstance(column, np.ndarray) and column.dtype == object):
        return column
    first = next((v for v in column if v is not None), None)
    if isinstance(first, str):
        return np.array([PHASE_NAMES.index(v) if v else 0 for v in column], dtype=np.int64)
    if isinstance(first, tuple):
        width = len(first)
        rows = [v if v is not None else (first[0],) * width for v in column]
        if isinstance(first[0], str):
            return np.array([[PHASE_NAMES.index(p) for p in r] for r in rows], dtype=np.int64)
        return np.array(rows, dtype=bool)
    return column


def _same_infos(a: dict[str, Any], b: dict[str, Any], where: str) -> None:
    """``a`` (SyncVectorEnv's, text as the single env's) equal to ``b`` (native: the same
    text as numbers)."""
    assert set(a) == set(b), f"{where}: keys {set(a) ^ set(b)}"
    for key in a:
        if key.startswith("_"):
            assert np.array_equal(a[key], b[key]), f"{where}: mask {key}"
    for key, value in a.items():
        if key.startswith("_"):
            continue
        mask = a["_" + key]
        if isinstance(value, dict):
            _same_infos(value, b[key], f"{where} {key}")
        elif key == "final_info":  # an object array of the single envs' dicts
            for j in np.flatnonzero(mask):
                got = numeric_info(value[j])
                assert set(got) == set(b[key][j]), f"{where}: {key}[{j}]"
                for k, v in got.items():
                    assert np.array_equal(v, b[key][j][k]), f"{where}: {key}[{j}][{k}]"
        else:
            want = _as_codes(value)
            if key != "final_obs":  # Gymnasium's SAME_STEP convention: an object array
                assert b[key].dtype != object, f"{where}: {key} is not numeric"
            assert _equal(want[mask], b[key][mask]), f"{where}: {key}"


def run_both(
    env_id: str, vec: gym.vector.VectorEnv, n: int, mode: Any, steps: int, policy: str, **kw: Any
) -> int:
    """Step ``vec`` and a SyncVectorEnv of ``gym.make(env_id, **kw)`` together; assert
    every output equal; return the number of episode ends seen."""
    sync = gym.vector.SyncVectorEnv(
        [lambda: gym.make(env_id, **kw) for _ in range(n)], autoreset_mode=mode
    )
    o1, i1 = sync.reset(seed=5)
    o2, i2 = vec.reset(seed=5)
    assert np.array_equal(o1, o2)
    _same_infos(i1, i2, "reset")
    rng = np.random.default_rng(0)
    shape = (n, *sync.single_action_space.shape)
    ends = 0
    for t in range(steps):
        if policy == "zero":
            a = np.zeros(shape, dtype=np.float32)
        else:
            a = rng.uniform(-1.5, 1.5, shape).astype(np.float32)
            if t % 50 == 3:
                a[0, 0] = np.nan  # counted as 0, reported in action_invalid
        r1, r2 = sync.step(a), vec.step(a)
        for k in range(4):
            assert np.array_equal(r1[k], r2[k]), f"step {t}, output {k}"
        assert r2[0].dtype == np.float32 and r2[1].dtype == np.float64
        _same_infos(r1[4], r2[4], f"step {t}")
        done = r1[2] | r1[3]
        ends += int(done.sum())
        if mode == AutoresetMode.DISABLED and done.any():
            o1, _ = sync.reset(options={"reset_mask": done.copy()})
            o2, _ = vec.reset(options={"reset_mask": done.copy()})
            assert np.array_equal(o1, o2)
    sync.close()
    vec.close()
    return ends


@needs_numba
@pytest.mark.parametrize("mode", MODES, ids=lambda m: m.value)
@pytest.mark.parametrize(
    ("level", "controller"),
    [("medium", "juggler"), ("hard", "juggler_latency_aware"), ("easy", "fixed_point")],
)
def test_v1_random_actions_equal_sync(mode: Any, level: str, controller: str) -> None:
    kw = {"level": level, "controller": controller}
    vec = JugglingV1VectorEnv(4, autoreset_mode=mode, **kw)
    assert vec.backend == "numba"
    ends = run_both(V1, vec, 4, mode, 400, "random", **kw)
    assert ends >= 4  # episodes ended and restarted


@needs_numba
@pytest.mark.parametrize("mode", MODES[:2], ids=lambda m: m.value)
@pytest.mark.parametrize(
    ("level", "controller"),
    [("medium", "juggler"), ("hard", "juggler_latency_aware"), ("medium", "commanded_intercept")],
)
def test_v1_zero_action_equal_sync(mode: Any, level: str, controller: str) -> None:
    """Long episodes: releases, catches, eq. 10 corrections, truncation."""
    kw = {"level": level, "controller": controller, "max_catches": 3}
    vec = gym.make_vec(V1, 3, autoreset_mode=mode, **kw)
    assert isinstance(vec, JugglingV1VectorEnv)
    assert run_both(V1, vec, 3, mode, 1200, "zero", **kw) >= 3


@needs_numba
@pytest.mark.parametrize(
    ("env_id", "cls"), [(V1, JugglingV1VectorEnv), (CASCADE, CascadeVectorEnv)]
)
def test_threaded_periods_equal_sync(env_id: str, cls: Any) -> None:
    """The worlds' periods in three threads (blocks of 8 sub-environments, fewer while
    some reset) give SyncVectorEnv's episodes bit for bit."""
    kw = {"level": "hard"}
    vec = cls(24, threads=3, **kw)
    assert vec.threads == 3
    ends = run_both(env_id, vec, 24, AutoresetMode.NEXT_STEP, 300, "random", **kw)
    assert ends >= 12  # some sub-environments reset while the others stepped
    assert vec._pool is None  # closed with the env
    with pytest.raises(ValueError, match="threads"):
        cls(2, threads=0)


@pytest.mark.parametrize("cls", [JugglingV1VectorEnv, CascadeVectorEnv])
def test_pickled_vector_env_continues_as_the_original(cls: Any) -> None:
    import pickle

    vec = cls(16, level="medium", threads=2)  # two blocks of 8: the pool is made
    vec.reset(seed=1)
    rng = np.random.default_rng(0)
    shape = (16, *vec.single_action_space.shape)
    for _ in range(150):
        vec.step((0.2 * rng.standard_normal(shape)).astype(np.float32))
    copy = pickle.loads(pickle.dumps(vec))
    for _ in range(300):
        a = (0.2 * rng.standard_normal(shape)).astype(np.float32)
        r1, r2 = vec.step(a), copy.step(a)
        for k in range(4):
            assert np.array_equal(r1[k], r2[k])


@pytest.mark.parametrize(
    ("backend", "controller"),
    [
        pytest.param("numba", "juggler", marks=needs_numba),
        pytest.param("numba", "commanded_intercept", marks=needs_numba),
        ("python", "juggler"),
    ],
)
def test_v1_residual_phases_equal_sync(backend: str, controller: str) -> None:
    """``residual_phases``: the residual acts in the catch only, on both backends and with
    the compiled and the Python controllers (random actions: drops and resets)."""
    kw = {
        "level": "medium",
        "controller": controller,
        "residual_phases": ["catch"],
        "residual_scale": 0.2,
    }
    mode = AutoresetMode.NEXT_STEP
    vec = JugglingV1VectorEnv(3, autoreset_mode=mode, backend=backend, **kw)
    assert vec.backend == backend
    assert run_both(V1, vec, 3, mode, 400, "random", **kw) >= 3


def test_v1_python_backend_equal_sync() -> None:
    vec = JugglingV1VectorEnv(3, backend="python", level="medium")
    assert vec.backend == "python"
    run_both(V1, vec, 3, AutoresetMode.NEXT_STEP, 150, "random", level="medium")


@needs_numba
@pytest.mark.parametrize("mode", MODES, ids=lambda m: m.value)
@pytest.mark.parametrize(
    ("level", "controller"),
    [("medium", "juggler"), ("hard", "juggler_latency_aware"), ("easy", "fixed_point")],
)
def test_cascade_random_actions_equal_sync(mode: Any, level: str, controller: str) -> None:
    kw = {"level": level, "controller": controller}
    vec = gym.make_vec(CASCADE, 3, autoreset_mode=mode, **kw)
    assert isinstance(vec, CascadeVectorEnv)
    assert vec.backend == "numba"
    assert run_both(CASCADE, vec, 3, mode, 500, "random", **kw) >= 3


@needs_numba
@pytest.mark.parametrize("mode", MODES[:2], ids=lambda m: m.value)
@pytest.mark.parametrize(
    ("level", "controller"),
    [
        ("medium", "juggler"),
        ("hard", "juggler_latency_aware"),
        ("medium", "juggler_latency_aware"),
        ("hard", "commanded_intercept"),
    ],
)
def test_cascade_zero_action_equal_sync(mode: Any, level: str, controller: str) -> None:
    """Long episodes: releases in turn, catches (early ones too), re-aimed catches, eq. 10
    corrections, truncation."""
    kw = {"level": level, "controller": controller, "max_catches": 4}
    vec = CascadeVectorEnv(3, autoreset_mode=mode, **kw)
    assert run_both(CASCADE, vec, 3, mode, 1200, "zero", **kw) >= 3


def test_cascade_python_backend_equal_sync() -> None:
    vec = CascadeVectorEnv(3, backend="python", level="medium")
    assert vec.backend == "python"
    run_both(CASCADE, vec, 3, AutoresetMode.NEXT_STEP, 200, "random", level="medium")


@pytest.mark.parametrize("mode", MODES, ids=lambda m: m.value)
def test_cascade_frame_skip_equals_sync(mode: Any) -> None:
    """``frame_skip=3``: the periods of each sub-environment until its episode ends (drops
    and resets mid-step with random actions; the numba backend when installed)."""
    kw = {"level": "medium", "frame_skip": 3}
    vec = gym.make_vec(CASCADE, 3, autoreset_mode=mode, **kw)
    assert isinstance(vec, CascadeVectorEnv)
    assert run_both(CASCADE, vec, 3, mode, 200, "random", **kw) >= 3


def test_cascade_frame_skip_zero_action_and_python_backend_equal_sync() -> None:
    """Long zero-action episodes with ``frame_skip=4`` (catches, truncation mid-step) on
    both backends."""
    kw = {"level": "easy", "max_catches": 3, "frame_skip": 4}
    mode = AutoresetMode.SAME_STEP
    for backend in ("auto", "python"):
        vec = CascadeVectorEnv(3, autoreset_mode=mode, backend=backend, **kw)
        assert run_both(CASCADE, vec, 3, mode, 300, "zero", **kw) >= 3
    with pytest.raises(ValueError, match="frame_skip"):
        CascadeVectorEnv(2, frame_skip=0)


@pytest.mark.parametrize("backend", ["auto", "python"])
def test_cascade_residual_phases_equal_sync(backend: str) -> None:
    """``residual_phases``: the residual acts in the named phases only, on both backends
    (random actions with ``frame_skip=2``: phases change within a step)."""
    kw = {"level": "medium", "residual_phases": ["catch"], "residual_scale": 0.4, "frame_skip": 2}
    mode = AutoresetMode.NEXT_STEP
    vec = CascadeVectorEnv(3, autoreset_mode=mode, backend=backend, **kw)
    assert run_both(CASCADE, vec, 3, mode, 300, "random", **kw) >= 3


@needs_numba
def test_v1_disabled_mode_refuses_an_ended_episode() -> None:
    vec = JugglingV1VectorEnv(2, autoreset_mode="Disabled", level="hard")
    vec.reset(seed=0)
    a = np.full((2, 2), 1.0, dtype=np.float32)
    for _ in range(400):
        _, _, term, trunc, _ = vec.step(a)
        if (term | trunc).any():
            break
    else:
        pytest.fail("no episode ended")
    with pytest.raises(RuntimeError, match="reset_mask"):
        vec.step(a)


def test_vector_arguments_are_checked() -> None:
    with pytest.raises(ValueError, match="backend"):
        JugglingV1VectorEnv(2, backend="gpu")
    with pytest.raises(ValueError, match="backend"):
        CascadeVectorEnv(2, backend="gpu")
    with pytest.raises(ValueError, match="num_envs"):
        JugglingV1VectorEnv(0)
    with pytest.raises(ValueError, match="autoreset_mode"):
        gym.make_vec(V1, 2, autoreset_mode="Sometimes")
    with pytest.raises(ValueError, match="level"):
        gym.make_vec(CASCADE, 2, level="impossible")
    vec = JugglingV1VectorEnv(2)
    with pytest.raises(RuntimeError, match="reset"):
        vec.step(np.zeros((2, 2)))
    vec.reset(seed=0)
    with pytest.raises(ValueError, match="actions"):
        vec.step(np.zeros((3, 2)))
    with pytest.raises(ValueError, match="seed"):
        vec.reset(seed=[1, 2, 3])
    with pytest.raises(ValueError, match="reset_mask"):
        vec.reset(options={"reset_mask": np.zeros(2, dtype=bool)})


@needs_numba
def test_v1_seeded_resets_repeat() -> None:
    vec = JugglingV1VectorEnv(3, level="hard")
    a = np.full((3, 2), 0.3, dtype=np.float32)
    runs = []
    for _ in range(2):
        obs, _ = vec.reset(seed=42)
        out = [obs]
        for _ in range(60):
            out.append(vec.step(a)[0])
        runs.append(np.stack(out))
    assert np.array_equal(runs[0], runs[1])
    assert not np.array_equal(runs[0][:, 0], runs[0][:, 1])  # seed + i differ


@needs_numba
@settings(max_examples=300, deadline=None)
@given(
    st.floats(allow_nan=True, allow_infinity=True, width=64),
    st.floats(allow_nan=True, allow_infinity=True, width=64),
)
def test_compiled_hypot_is_python_hypot(x: float, y: float) -> None:
    from motion_envs.envs.juggling._compiled import hypot_rows, py_hypot

    expected = math.hypot(x, y)
    got = py_hypot(x, y)
    assert (math.isnan(expected) and math.isnan(got)) or got == expected
    row = hypot_rows(np.array([x]), np.array([y]))[0]
    assert (math.isnan(expected) and math.isnan(row)) or row == expected


@needs_numba
def test_compiled_hypot_on_many_random_pairs() -> None:
    """The C library's hypot differs from CPython's on ~0.3 % of pairs; ours never."""
    from motion_envs.envs.juggling._compiled import hypot_rows

    rng = np.random.default_rng(7)
    x = rng.standard_normal(200_000) * 10.0 ** rng.uniform(-6, 3, 200_000)
    y = rng.standard_normal(200_000) * 10.0 ** rng.uniform(-6, 3, 200_000)
    expected = np.array([math.hypot(a, b) for a, b in zip(x.tolist(), y.tolist(), strict=True)])
    assert np.count_nonzero(np.hypot(x, y) != expected) > 100  # the trap is real
    assert np.array_equal(hypot_rows(x, y), expected)


def _catching_episodes(count: int) -> list[Any]:
    """Juggler episodes (Juggling-v1's world and controller, medium's release scatter,
    the ball seen exactly) stopped in catch phases whose eq. 10 rows exist (after their
    first correction), one per seed: the controller run in Python on its own (the
    environment's batch makes the corrections in its arrays)."""
    import copy

    out = []
    seed = 0
    while len(out) < count:
        env = gym.make(V1, level="medium", latency=0.0, position_std=0.0, velocity_std=0.0)
        env = env.unwrapped
        env.reset(seed=seed)
        seed += 1
        state = env._state
        for _ in range(600):
            target, armed = env.controller.command(state)
            state = env.world.step(target, armed)
            ep = env.controller.juggler.episode
            if ep.phase == "catch" and ep._eq10 is not None and ep.k >= ep._eq10.k0 + 2:
                out.append(copy.deepcopy(ep))
                break
            if state.dropped:
                break
        assert seed < 50, "no catch with eq. 10 rows in 50 episodes"
    return out


def test_replan_many_is_replan_of_each() -> None:
    """The stacked eq. 10 products give each episode its own scalar numbers."""
    import copy

    from motion_envs.models.juggling import replan_many

    episodes = _catching_episodes(3)
    shifts = np.array([[0.01, -0.02], [-0.03, 0.005], [0.0, 0.04]])
    predicted = np.stack([ep.end for ep in episodes]) + shifts
    times = [ep.t_start + ep.k * ep.task.dt for ep in episodes]
    before = [ep.grid.copy() for ep in episodes]
    alone = [copy.deepcopy(ep) for ep in episodes]
    for ep, t, p in zip(alone, times, predicted, strict=True):
        ep.replan(t, p.copy())
    replan_many(episodes, times, predicted)
    for j, (a, b) in enumerate(zip(alone, episodes, strict=True)):
        assert np.array_equal(a.coefficients, b.coefficients)
        assert np.array_equal(a.grid, b.grid)
        assert np.array_equal(b.end, predicted[j])
        assert a.corrections == b.corrections
        assert np.array_equal(b.grid[: b.k + 1], before[j][: b.k + 1])  # the past is kept
        assert not np.array_equal(b.grid[b.k + 1 :], before[j][b.k + 1 :])  # re-planned


@needs_numba
def test_v1_controllers_get_the_corrections_at_their_events() -> None:
    """The batch's eq. 10 corrections reach each episode's controller at its next event:
    after ``sync`` a vector sub-environment's controller holds the single environment's
    (its batch of one, synced too) plan and corrections, and the world its time."""
    n, steps = 3, 400
    vec = JugglingV1VectorEnv(n, level="medium")
    singles = [gym.make(V1, level="medium").unwrapped for _ in range(n)]
    vec.reset(seed=5)
    for i, env in enumerate(singles):
        env.reset(seed=5 + i)
    corrected = 0
    for _ in range(steps):
        _, _, term, trunc, _ = vec.step(np.zeros((n, 2), dtype=np.float32))
        for env in singles:
            env.step(np.zeros(2, dtype=np.float32))
        if (term | trunc).any():  # compare before the autoreset
            break
    for i, env in enumerate(singles):
        vec._batch.sync(i)
        env._batch.sync(0)
        a, b = vec._batch._episode(i), env.controller.juggler.episode
        assert a.phase == b.phase
        assert a.corrections == b.corrections
        assert np.array_equal(a.coefficients, b.coefficients)
        assert np.array_equal(a.end, b.end)
        assert np.array_equal(a.grid, b.grid)
        assert vec.envs[i].world.data.time == env.world.data.time
        corrected += len(b.corrections)
    assert corrected > 10  # corrections happened


def test_shared_eq10_rows_are_the_rows_from_any_step() -> None:
    """A catch's eq. 10 rows computed once for every step (shared by the plans of its
    duration) hold, at every step k, the numbers of rows computed from k on: every
    candidate duration of the juggler's catch, several basis sizes."""
    import math

    from motion_envs.geometry import sine_series as ss
    from motion_envs.models.juggling import Eq10Rows, eq10_rows, v1_juggler

    juggler = v1_juggler(9.81)
    lo, hi = juggler.phases_["catch"].duration_range
    dt = juggler.task.dt
    for n_sines, durations in ((4, np.linspace(lo, hi, 201)), (2, [0.3]), (9, [0.2, 0.41])):
        for duration in np.asarray(durations).tolist():
            n = math.ceil(duration / dt - 1e-9)
            tau = np.minimum(np.arange(0, n + 1) * dt / duration, 1.0)
            basis = ss.basis(tau, n_sines)
            shared = eq10_rows(tau, basis, duration, dt)
            assert eq10_rows(tau, basis, duration, dt) is shared
            assert not shared.pinv.flags.writeable
            for k0 in range(n + 1):
                own = Eq10Rows(tau, basis, k0, duration)
                assert np.array_equal(own.derivative, shared.derivative[k0:])
                assert np.array_equal(own.a, shared.a[k0:])
                assert np.array_equal(own.pinv, shared.pinv[k0:])


@pytest.mark.parametrize("env_id", [V1, CASCADE])
def test_vector_frames_equal_sync_frames(env_id: str, mujoco_gl: None) -> None:
    """render() draws each sub-environment's world as SyncVectorEnv's copies draw theirs."""
    kw = {"level": "medium", "render_mode": "rgb_array", "width": 64, "height": 64}
    vec = gym.make_vec(env_id, 2, **kw)
    sync = gym.vector.SyncVectorEnv([lambda: gym.make(env_id, **kw) for _ in range(2)])
    vec.reset(seed=0)
    sync.reset(seed=0)
    a = np.full((2, *sync.single_action_space.shape), 0.1, dtype=np.float32)
    for _ in range(120):
        vec.step(a)
        sync.step(a)
    frames, expected = vec.render(), sync.render()
    assert frames is not None and expected is not None
    assert len(frames) == 2
    for f, e in zip(frames, expected, strict=True):
        assert f.shape == (64, 64, 3) and np.array_equal(f, e)
    assert not np.array_equal(frames[0], frames[1])  # two different worlds


@needs_numba
@pytest.mark.parametrize("leaf", [1, 8, 64, 10_000])
def test_compiled_likeness_is_human_likeness(leaf: int) -> None:
    """The cascade vector env's compiled nearest-sample search gives
    HumanLikeness.distance's numbers, near the demonstrations, far from them and for NaN,
    whatever the tree's leaf size."""
    from motion_envs.datasets.juggling import PHASES
    from motion_envs.envs.juggling._compiled import likeness_tree, nearest_rows
    from motion_envs.models.juggling import LIKENESS_TAU, cascade_likeness

    likeness = cascade_likeness(9.81, "train")
    trees = tuple(likeness_tree(likeness.trees[name].data, leaf) for name in PHASES)
    rng = np.random.default_rng(11)
    n = 4000
    phase = rng.integers(0, len(PHASES), n)
    near = np.stack([likeness.trees[PHASES[p]].data[0] for p in phase])
    state = near + rng.normal(0.0, 0.05, (n, 4)) * rng.uniform(0.0, 4.0, (n, 1))
    state[::37] *= 20.0
    pos, vel = state[:, :2], state[:, 2:] / LIKENESS_TAU
    vel[5, 0] = np.nan
    points = np.concatenate([pos, LIKENESS_TAU * vel], axis=1)  # as distance() forms it
    got = nearest_rows(points, phase, trees)
    for j in range(n):
        assert got[j] == likeness.distance(PHASES[phase[j]], pos[j], vel[j]), j


@pytest.mark.parametrize(("env_id", "dim"), [(V1, 2), (CASCADE, 4)])
def test_sb3_sees_the_episodes_of_dummy_vec_env(env_id: str, dim: int) -> None:
    """What ``motion-bench train`` steps now (the native vector env through
    ``GymnasiumVecEnv``) gives SB3 the episodes DummyVecEnv gave it before: the agents
    trained on DummyVecEnv stay reproducible."""
    pytest.importorskip("stable_baselines3")
    from stable_baselines3.common.vec_env import DummyVecEnv

    from baselines.agents.vec import make_sb3_vec_env
    from baselines.sb3 import GymnasiumVecEnv

    kw = {"level": "hard", "max_catches": 2, "residual_scale": 0.15}
    native = make_sb3_vec_env(env_id, 3, kw)
    assert isinstance(native, GymnasiumVecEnv)
    dummy = DummyVecEnv([lambda: gym.make(env_id, **kw)] * 3)
    native.seed(7)
    dummy.seed(7)
    assert np.array_equal(native.reset(), dummy.reset())
    rng = np.random.default_rng(0)
    ends = 0
    for _ in range(500):
        a = (0.5 * rng.standard_normal((3, dim))).astype(np.float32)
        r1, r2 = native.step(a), dummy.step(a)
        for k in range(3):
            assert np.array_equal(r1[k], r2[k])
        for i in np.flatnonzero(r1[2]).tolist():
            final = r2[3][i]["terminal_observation"]
            assert np.array_equal(r1[3][i]["terminal_observation"], final)
        ends += int(r1[2].sum())
    assert ends >= 3


@pytest.mark.parametrize("mode", MODES[:2], ids=lambda m: m.value)
@pytest.mark.parametrize("env_id", [V1, CASCADE])
def test_make_vec_max_episode_steps_truncates_as_time_limit(env_id: str, mode: Any) -> None:
    """``gym.make_vec(id, N, max_episode_steps=K)`` (as for the other ids) = SyncVectorEnv
    of ``gym.make(id, max_episode_steps=K)`` (``TimeLimit``): truncated at the K-th step,
    then reset, with random actions (drops end some episodes earlier)."""
    vec = gym.make_vec(env_id, num_envs=3, max_episode_steps=7, autoreset_mode=mode)
    ends = run_both(env_id, vec, 3, mode, 30, "random", max_episode_steps=7)
    assert ends >= 9  # every sub-environment at least 3 episodes in 30 steps
    with pytest.raises(ValueError, match="max_episode_steps"):
        gym.make_vec(env_id, num_envs=2, max_episode_steps=0)
