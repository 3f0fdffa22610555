"""The reaching environments' criterion for agents: one deterministic episode per
trajectory of a data split on the native vector environment, ``info["max_error"]`` of
each (:func:`episode_max_errors`); the criterion is their median (Faraway & Choe's
"median over trajectories of the max over time")."""

from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

__all__ = ["EpisodeErrors", "Policy", "episode_max_errors"]

Policy = Callable[[NDArray[np.float32]], NDArray[np.floating]]


@dataclass(frozen=True)
class EpisodeErrors:
    """Per-episode ``max_error`` of a policy with the episodes' trajectory ids and tasks
    (and ``groups``: the person of each episode, or its task where there are no people)."""

    max_errors: NDArray[np.float64]
    trajectory_ids: NDArray[np.str_]
    tasks: NDArray[np.str_]
    groups: NDArray[np.str_] | None = None

    @property
    def criterion(self) -> float:
        """Median over episodes of the per-episode max error."""
        return float(np.median(self.max_errors))

    @property
    def median_of_task_medians(self) -> float:
        """Median over tasks of the median over the task's episodes (motion-bench position)."""
        return float(
            np.median([np.median(self.max_errors[self.tasks == t]) for t in np.unique(self.tasks)])
        )


def episode_max_errors(
    policy: Policy | None,
    env_id: str,
    env_kwargs: Mapping[str, Any],
    split: str,
    episodes: int | None = None,
) -> EpisodeErrors:
    """``info["max_error"]`` of one deterministic episode per trajectory of ``split``.

    ``policy`` maps a batch of raw observations ``(N, obs_dim)`` to actions; None is the
    zero action (the nominal). ``episodes`` takes the first trajectories only.
    """
    import gymnasium as gym

    import motion_envs  # noqa: F401  (registers the ids, also inside Ray workers)

    kwargs = {k: v for k, v in env_kwargs.items() if k != "split"}
    probe: Any = gym.make(env_id, split=split, **kwargs).unwrapped
    n_traj = probe.task.n_trajectories
    n = n_traj if episodes is None else min(int(episodes), n_traj)
    if n < 1:
        raise ValueError(f"episodes must be >= 1; got {episodes!r}")
    venv = gym.make_vec(
        env_id, num_envs=n, vectorization_mode="vector_entry_point", split=split, **kwargs
    )
    obs, _ = venv.reset(seed=0, options={"trajectory": np.arange(n)})
    shape = (n, *(venv.single_action_space.shape or ()))
    maxima = np.full(n, np.nan)
    done = np.zeros(n, dtype=bool)
    while not done.all():
        actions = np.zeros(shape, dtype=np.float32) if policy is None else policy(obs)
        obs, _, terminated, truncated, info = venv.step(np.asarray(actions, dtype=np.float32))
        ended = (np.asarray(terminated) | np.asarray(truncated)) & ~done
        if "max_error" in info:
            got = ended & info["_max_error"]
            maxima[got] = info["max_error"][got]
        done |= ended
    venv.close()
    if np.isnan(maxima).any():
        raise RuntimeError(f"{env_id}: some episodes ended without info['max_error']")
    people = getattr(probe.task, "subjects", None)
    return EpisodeErrors(
        maxima,
        np.asarray(probe.task.trajectory_ids[:n]).astype(str),
        np.asarray(probe.task.tasks[:n]).astype(str),
        np.asarray((probe.task.tasks if people is None else people)[:n]).astype(str),
    )
