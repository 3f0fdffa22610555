"""TqdmCallback's real total and live rate; SB3's own progress bar and tensorboard log."""

from __future__ import annotations

import io
import time

import gymnasium as gym
import pytest

import motion_envs  # noqa: F401  (registers the ids)

pytest.importorskip("stable_baselines3")

from stable_baselines3 import PPO, SAC
from stable_baselines3.common.vec_env import VecMonitor

from baselines.sb3 import GymnasiumVecEnv, TqdmCallback

ENV_ID = "MotionEnvs/PositionReach-v0"


def _env(n: int) -> VecMonitor:
    venv = gym.make_vec(
        ENV_ID, num_envs=n, vectorization_mode="vector_entry_point", shapes=["GShape"]
    )
    return VecMonitor(GymnasiumVecEnv(venv))


@pytest.mark.parametrize(
    ("requested", "n_envs", "n_steps", "expected"),
    [(50, 2, 16, 64), (64, 2, 16, 64), (65, 3, 8, 72)],
)
def test_bar_total_is_what_ppo_really_runs(requested, n_envs, n_steps, expected):
    model = PPO(
        "MlpPolicy",
        _env(n_envs),
        n_steps=n_steps,
        batch_size=n_steps,
        n_epochs=1,
        seed=0,
        device="cpu",
    )
    cb = TqdmCallback(desc="ppo", refresh_seconds=0, file=io.StringIO())
    model.learn(requested, callback=cb)
    assert model.num_timesteps == expected  # PPO rounds up to whole rollouts ...
    assert cb.bar.total == expected  # ... and the bar says so
    assert cb.bar.n == expected


def test_bar_total_of_an_off_policy_algorithm():
    model = SAC(
        "MlpPolicy", _env(3), learning_starts=5, batch_size=8, buffer_size=200, seed=0, device="cpu"
    )
    cb = TqdmCallback(desc="sac", refresh_seconds=0, file=io.StringIO())
    model.learn(10, callback=cb)
    assert cb.bar.total == model.num_timesteps == 12


class _SlowPPO(PPO):
    """PPO whose update phase takes a known wall-clock time."""

    def train(self) -> None:
        time.sleep(0.6)


def test_rate_and_elapsed_keep_moving_during_updates():
    out = io.StringIO()
    model = _SlowPPO("MlpPolicy", _env(2), n_steps=8, batch_size=8, seed=0, device="cpu")
    cb = TqdmCallback(desc="slow", refresh_seconds=0.1, file=out)
    t0 = time.perf_counter()
    model.learn(32, callback=cb)  # two rollouts, two 0.6 s updates
    wall = time.perf_counter() - t0
    text = out.getvalue()
    # the bar was redrawn during the updates, saying so
    assert text.count("phase=updating") >= 4, text[-500:]
    # the rate shown is the run's average (updates included), not the collection speed
    assert cb.bar.smoothing == 0
    rate = cb.bar.format_dict["n"] / cb.bar.format_dict["elapsed"]
    assert rate < 32 / 1.0  # at least 1.2 s of updates in the elapsed time
    assert cb.bar.format_dict["elapsed"] >= 1.2 and cb.bar.format_dict["elapsed"] <= wall + 0.1
    assert cb._thread is None  # the refresh thread stopped


# SB3's own bar is tqdm.rich, which tqdm flags as experimental on every use
@pytest.mark.filterwarnings("ignore::tqdm.TqdmExperimentalWarning")
def test_sb3_progress_bar_and_tensorboard_log(tmp_path, capsys):
    """The rl extra's rich and tensorboard make SB3's own options work."""
    pytest.importorskip("rich", reason="the rl extra installs rich")
    pytest.importorskip("tensorboard", reason="the rl extra installs tensorboard")
    model = PPO(
        "MlpPolicy",
        _env(2),
        n_steps=16,
        batch_size=16,
        n_epochs=1,
        seed=0,
        device="cpu",
        tensorboard_log=str(tmp_path),
    )
    model.learn(32, progress_bar=True, tb_log_name="tiny")
    events = list(tmp_path.rglob("events.out.tfevents.*"))
    assert events and events[0].stat().st_size > 0
    assert events[0].parent.name.startswith("tiny")
