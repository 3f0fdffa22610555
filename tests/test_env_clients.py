"""Clients nobody here wrote, unchanged: SB3 subprocesses, Gymnasium's checkers, a CleanRL loop."""

from __future__ import annotations

import os
import subprocess
import sys
import textwrap

import gymnasium as gym
import numpy as np
import pytest
from gymnasium.vector import AutoresetMode

import motion_envs
from motion_envs.envs.orientation_reach import OrientationReachEnv
from motion_envs.envs.position_reach import PositionReachEnv

ORIENTATION = "MotionEnvs/OrientationReach-v0"
POSITION = "MotionEnvs/PositionReach-v0"
SHAPES = ["Angle", "CShape", "GShape"]


def test_sb3_subprocvecenv_with_spawn_from_a_process_that_never_imported_the_package():
    """``python -c`` (like a notebook) never imports motion_envs by name: the
    ``motion_envs:`` prefix makes every spawned worker import it before looking up the id."""
    pytest.importorskip("stable_baselines3")
    code = textwrap.dedent(
        """
        import sys
        from stable_baselines3.common.env_util import make_vec_env
        from stable_baselines3.common.vec_env import SubprocVecEnv

        assert "motion_envs" not in sys.modules
        venv = make_vec_env(
            "motion_envs:MotionEnvs/PositionReach-v0",
            n_envs=2,
            seed=0,
            vec_env_cls=SubprocVecEnv,
            vec_env_kwargs={"start_method": "spawn"},
            env_kwargs={"shapes": ["Angle", "CShape"]},
        )
        obs = venv.reset()
        for _ in range(60):
            obs, rewards, dones, infos = venv.step([venv.action_space.sample()] * 2)
        assert "motion_envs" not in sys.modules  # only the workers imported it
        venv.close()
        print("ok", obs.shape, int(dones.sum()))
        """
    )
    env = {**os.environ, "PYTHONPATH": os.pathsep.join(sys.path)}
    out = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, env=env, timeout=600
    )
    assert out.returncode == 0, out.stderr[-3000:]
    assert out.stdout.startswith("ok (2, 11)")


@pytest.mark.parametrize(
    ("env_id", "cls", "kwargs"),
    [
        (ORIENTATION, OrientationReachEnv, {"nominal": "bezier-task"}),
        (POSITION, PositionReachEnv, {"shapes": SHAPES}),
    ],
)
def test_gym_make_matches_the_entry_point_class(env_id, cls, kwargs):
    from gymnasium.utils.env_match import check_environments_match

    for seed in (0, 1):
        made, bare = gym.make(env_id, **kwargs), cls(**kwargs)
        check_environments_match(made, bare, 49, seed=seed)
        # the 50th step ends the episode; the registration's TimeLimit (50 steps) also
        # marks it truncated, as the docstring says
        action = np.zeros(made.action_space.shape, np.float32)
        out_made, out_bare = made.step(action), bare.step(action)
        np.testing.assert_array_equal(out_made[0], out_bare[0])
        assert out_made[1:3] == out_bare[1:3] and out_bare[2]
        assert out_made[3] and not out_bare[3]


def _cleanrl_ppo(envs: gym.vector.VectorEnv, iterations: int, n_steps: int) -> list[float]:
    """The rollout/update loop of CleanRL's ``ppo_continuous_action.py`` (Gymnasium 1.x,
    ``AutoresetMode.SAME_STEP``), shrunk: returns the episode returns it logged from
    ``infos["episode"]`` (vector ``RecordEpisodeStatistics``)."""
    import torch
    from torch import nn

    torch.manual_seed(0)
    n_obs = int(np.prod(envs.single_observation_space.shape))
    n_act = int(np.prod(envs.single_action_space.shape))
    actor = nn.Sequential(nn.Linear(n_obs, 32), nn.Tanh(), nn.Linear(32, n_act))
    critic = nn.Sequential(nn.Linear(n_obs, 32), nn.Tanh(), nn.Linear(32, 1))
    log_std = nn.Parameter(torch.full((n_act,), -1.0))
    params = [*actor.parameters(), *critic.parameters(), log_std]
    optimizer = torch.optim.Adam(params, lr=3e-4)
    N = envs.num_envs
    obs_buf = torch.zeros((n_steps, N, n_obs))
    act_buf = torch.zeros((n_steps, N, n_act))
    logp_buf = torch.zeros((n_steps, N))
    rew_buf = torch.zeros((n_steps, N))
    done_buf = torch.zeros((n_steps, N))
    val_buf = torch.zeros((n_steps, N))
    returns_logged: list[float] = []
    next_obs = torch.as_tensor(envs.reset(seed=1)[0])
    next_done = torch.zeros(N)
    for _ in range(iterations):
        for step in range(n_steps):
            obs_buf[step], done_buf[step] = next_obs, next_done
            with torch.no_grad():
                dist = torch.distributions.Normal(actor(next_obs), log_std.exp())
                action = dist.sample()
                logp_buf[step] = dist.log_prob(action).sum(1)
                val_buf[step] = critic(next_obs).squeeze(1)
            act_buf[step] = action
            obs, reward, terminations, truncations, infos = envs.step(action.numpy())
            rew_buf[step] = torch.as_tensor(reward, dtype=torch.float32)
            next_obs = torch.as_tensor(obs)
            next_done = torch.as_tensor(
                np.logical_or(terminations, truncations), dtype=torch.float32
            )
            if "episode" in infos:
                mask = infos["_episode"]
                returns_logged.extend(infos["episode"]["r"][mask].tolist())
                assert "final_obs" in infos and np.array_equal(infos["_final_obs"], mask)
        with torch.no_grad():  # GAE
            adv = torch.zeros_like(rew_buf)
            last = torch.zeros(N)
            next_value = critic(next_obs).squeeze(1)
            for t in reversed(range(n_steps)):
                nonterminal = 1.0 - (next_done if t == n_steps - 1 else done_buf[t + 1])
                nv = next_value if t == n_steps - 1 else val_buf[t + 1]
                delta = rew_buf[t] + 0.99 * nv * nonterminal - val_buf[t]
                adv[t] = last = delta + 0.99 * 0.95 * nonterminal * last
            ret = adv + val_buf
        dist = torch.distributions.Normal(actor(obs_buf.reshape(-1, n_obs)), log_std.exp())
        ratio = (dist.log_prob(act_buf.reshape(-1, n_act)).sum(1) - logp_buf.reshape(-1)).exp()
        a = adv.reshape(-1)
        a = (a - a.mean()) / (a.std() + 1e-8)
        pg = torch.max(-a * ratio, -a * ratio.clamp(0.8, 1.2)).mean()
        v_loss = (
            0.5 * ((critic(obs_buf.reshape(-1, n_obs)).squeeze(1) - ret.reshape(-1)) ** 2).mean()
        )
        optimizer.zero_grad()
        (pg + 0.5 * v_loss).backward()
        optimizer.step()
    return returns_logged


def test_cleanrl_style_ppo_loop_with_same_step_autoreset_logs_episode_returns():
    pytest.importorskip("torch")
    from gymnasium.wrappers import vector as vw

    def native():
        return vw.RecordEpisodeStatistics(
            vw.ClipAction(
                gym.make_vec(POSITION, 4, autoreset_mode=AutoresetMode.SAME_STEP, shapes=SHAPES)
            )
        )

    def sync():
        return vw.RecordEpisodeStatistics(
            vw.ClipAction(
                gym.make_vec(
                    POSITION,
                    4,
                    vectorization_mode="sync",
                    vector_kwargs={"autoreset_mode": AutoresetMode.SAME_STEP},
                    shapes=SHAPES,
                )
            )
        )

    # 3 iterations x 64 steps x 4 environments = 768 steps: 12 episodes of 50 steps
    logged = _cleanrl_ppo(native(), iterations=3, n_steps=64)
    assert len(logged) == 12
    assert all(np.isfinite(r) and r < 0 for r in logged)
    # the same loop over SyncVectorEnv of single environments logs the same returns
    assert _cleanrl_ppo(sync(), iterations=3, n_steps=64) == logged


#: A smaller instance where building the default one takes long.
_SMALL = {
    "MotionEnvs/PositionReach-v0": {"shapes": SHAPES},
    "MotionEnvs/PositionReach-v1": {"shapes": SHAPES},
}


@pytest.mark.parametrize("env_id", motion_envs.ENV_IDS)
def test_numpy_to_torch_converts_every_info_of_every_id(env_id):
    """Gymnasium's ``NumpyToTorch`` vector wrapper (DLPack: numbers only) on
    ``gym.make_vec(id, 2, max_episode_steps=3)``: a reset and steps through an autoreset
    (the episodes truncated at 3 steps, so the 4th step resets them). Every value of
    every info converts to a tensor; the text of the single environments' infos is the
    envs' lookups (``trajectory_labels``, ``phase_names``)."""
    torch = pytest.importorskip("torch")
    pytest.importorskip("array_api_compat")
    from gymnasium.wrappers.vector import NumpyToTorch

    venv = NumpyToTorch(
        gym.make_vec(env_id, num_envs=2, max_episode_steps=3, **_SMALL.get(env_id, {}))
    )

    def tensors(info, where):
        for key, value in info.items():
            if isinstance(value, dict):
                tensors(value, f"{where}[{key!r}]")
            else:
                assert isinstance(value, torch.Tensor), f"{where}[{key!r}]: {type(value)}"

    obs, info = venv.reset(seed=0)
    assert isinstance(obs, torch.Tensor)
    tensors(info, "reset")
    resets = 0
    action = torch.zeros(venv.action_space.shape)
    for t in range(5):
        obs, _, _, truncated, info = venv.step(action)
        tensors(info, f"step {t}")
        if t == 2 and "Coefficients" not in env_id and env_id != "MotionEnvs/Juggling-v0":
            assert bool(truncated.all()), "max_episode_steps=3 did not truncate"
        resets += int(any(k in info for k in ("trajectory_index", "seed")))
    assert resets >= 1, "no autoreset seen"
    base = venv.unwrapped
    if "phase" in info:
        names = getattr(base, "phase_names", None) or base.get_attr("phase_names")[0]
        assert names[int(info["phase"][0])] in names
    if "trajectory_index" in info:
        labels = base.trajectory_labels
        assert len(labels["trajectory_id"]) > int(info["trajectory_index"].max())
    venv.close()
