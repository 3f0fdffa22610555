"""The reaching core (motion_envs.envs._reach): kinds, the single step, the vector env's
keyword arguments, and a new kind written as one module (here: in this file)."""

from __future__ import annotations

import pickle

import gymnasium as gym
import numpy as np
import pytest

import motion_envs  # noqa: F401  (registers the ids)
from motion_envs.envs import _kernels as K
from motion_envs.envs._reach import ObsLayout, step_table
from motion_envs.envs.orientation_reach import (
    ORIENTATION,
    OrientationReachEnv,
    OrientationReachVectorEnv,
)
from motion_envs.envs.position_reach import (
    POSITION,
    PositionKind,
    PositionReachEnv,
    PositionReachVectorEnv,
)

SHAPES = ["Angle", "GShape"]
BACKENDS = [b for b in K.VECTOR_BACKENDS if b != "numba" or K.numba_available()]


def _episode(env, seed: int = 0):
    env.reset(seed=seed)
    rng = np.random.default_rng(seed)
    infos = []
    terminated = False
    while not terminated:
        a = rng.uniform(-1.5, 1.5, env.action_space.shape).astype(np.float32)
        *_, terminated, _, info = env.step(a)
        infos.append(info)
    return infos


@pytest.mark.parametrize(
    ("env", "kind"),
    [
        (lambda: OrientationReachEnv(split="test"), ORIENTATION),
        (lambda: PositionReachEnv(shapes=SHAPES), POSITION),
    ],
)
def test_info_keys_and_end_maxima_follow_the_kind(env, kind):
    infos = _episode(env())
    for info in infos[:-1]:
        assert list(info) == [*kind.step_keys, "tau"]
    last = infos[-1]
    assert list(last) == [*kind.step_keys, "tau", *(key for key, _ in kind.end_keys)]
    for key, src in kind.end_keys:  # the running maximum, an entry of the episode
        assert last[key] == max(info[src] for info in infos)


def test_row_and_observation_layouts_name_the_task_arrays():
    env = OrientationReachEnv(split="test")
    row = ORIENTATION.row_layout(4)
    g, steps = env.task.grids, env.task.steps
    np.testing.assert_array_equal(steps[..., row["nominal"]], g.nominal)
    np.testing.assert_array_equal(steps[..., row["human"]], g.human)
    np.testing.assert_array_equal(steps[..., row["residual"]], g.residuals)
    obs, _ = env.reset(seed=3, options={"trajectory": 2})
    layout = ObsLayout.for_dim(4)
    np.testing.assert_array_equal(obs[layout.current], g.starts[2].astype(np.float32))
    np.testing.assert_array_equal(obs[layout.goal], g.goals[2].astype(np.float32))
    assert obs[layout.tau] == 0.0
    assert obs[layout.task].sum() == 1.0
    penv = PositionReachEnv(shapes=SHAPES)
    prow = POSITION.row_layout(2)
    np.testing.assert_array_equal(penv.task.steps[..., prow["human"]], penv.task.grids.human)


def test_step_table_rejects_parts_that_do_not_follow_the_layout():
    layout = {"a": slice(0, 2), "b": slice(2, 3)}
    ok = step_table(layout, {"a": np.zeros((1, 2, 2)), "b": np.ones((1, 2, 1))})
    assert ok.shape == (1, 2, 3)
    with pytest.raises(ValueError, match="width"):
        step_table(layout, {"a": np.zeros((1, 2, 3)), "b": np.ones((1, 2, 1))})
    with pytest.raises(ValueError, match="layout"):
        step_table(layout, {"b": np.ones((1, 2, 1)), "a": np.zeros((1, 2, 2))})


def test_vector_env_takes_the_single_env_keywords_and_its_checks():
    env = PositionReachVectorEnv(num_envs=2, shapes=SHAPES, residual_scale=2.0)
    assert env.single.residual_scale == 2.0
    assert env.task.n_trajectories == PositionReachEnv(shapes=SHAPES).task.n_trajectories
    with pytest.raises(ValueError, match=r"^residual_scale must be"):
        OrientationReachVectorEnv(num_envs=2, residual_scale=0.0)
    with pytest.raises(TypeError, match="no_such_argument"):
        OrientationReachVectorEnv(num_envs=2, no_such_argument=1)


def test_kinds_pickle_by_reference():
    assert pickle.loads(pickle.dumps(ORIENTATION)) is ORIENTATION
    env = PositionReachEnv(shapes=SHAPES)
    env.reset(seed=0)
    copy = pickle.loads(pickle.dumps(env))
    assert copy.kind is POSITION
    a = np.full(2, 0.5, dtype=np.float32)
    assert copy.step(a)[1] == env.step(a)[1]


# -- a new kind in one module: positions scored by the squared distance -----------------
_position_physics = PositionKind.fused_physics  # called by name: numba compiles it too


class SquaredKind(PositionKind):
    """Positions, reward ``-w_distance |y - h|^2 - w_action |a|^2`` (a test kind built on
    the position kind's kernels)."""

    name = "squared"
    instance_name = "SQUARED"
    step_keys = ("error", "squared_error", "reward_action")
    end_keys = (("max_error", "error"), ("max_squared_error", "squared_error"))

    def scalar_step(self, row, a, scale, w):
        q, _, info = POSITION.scalar_step(row, a, scale, w)
        err, r_act = info["error"], info["reward_action"]
        e2 = err * err
        return q, -w[0] * e2 + r_act, {"error": err, "squared_error": e2, "reward_action": r_act}

    def batch_step(self, rows, a, scale, w):
        q, _, (err, _, r_act) = POSITION.batch_step(rows, a, scale, w)
        e2 = err * err
        return q, -w[0] * e2 + r_act, [err, e2, r_act]

    @staticmethod
    def fused_physics(row, a, scale, w, q):
        _, (err, _, r_act) = _position_physics(row, a, scale, w, q)
        e2 = err * err
        return -w[0] * e2 + r_act, (err, e2, r_act)


SQUARED = SquaredKind()


class SquaredReachEnv(PositionReachEnv):
    kind = SQUARED


class SquaredReachVectorEnv(PositionReachVectorEnv):
    single_class = SquaredReachEnv


@pytest.mark.parametrize("backend", BACKENDS)
def test_a_new_kind_runs_single_and_vector_alike(backend):
    kwargs = {"shapes": SHAPES, "reward_weights": {"action": 0.5}}
    n = 3
    venv = SquaredReachVectorEnv(num_envs=n, backend=backend, **kwargs)
    singles = [SquaredReachEnv(**kwargs) for _ in range(n)]
    obs, _ = venv.reset(seed=5)
    for i, env in enumerate(singles):
        np.testing.assert_array_equal(obs[i], env.reset(seed=5 + i)[0])
    rng = np.random.default_rng(1)
    for _ in range(60):  # past an episode's end (NEXT_STEP autoreset)
        a = rng.uniform(-1.5, 1.5, (n, 2)).astype(np.float32)
        obs, reward, term, _, info = venv.step(a)
        for i, env in enumerate(singles):
            if not info.get("_error", np.zeros(n, bool))[i]:  # sub-env i autoresets
                o, _ = env.reset()
                np.testing.assert_array_equal(obs[i], o)
                continue
            o, r, t, _, inf = env.step(a[i])
            np.testing.assert_array_equal(obs[i], o)
            assert reward[i] == r and term[i] == t
            for key in ("error", "squared_error", "reward_action", "tau"):
                assert info[key][i] == inf[key]
            if t:
                assert info["max_squared_error"][i] == inf["max_squared_error"]
                assert inf["max_squared_error"] > 0
    assert gym.spaces.Box.contains(venv.single_observation_space, obs[0])
