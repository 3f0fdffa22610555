"""An agent's memory: a frame stack of its last ``k`` observations (``frame_stack`` key).

Training wraps every sub-environment in Gymnasium's ``FrameStackObservation(k)`` (oldest
first, the reset observation repeated as padding) and ``FlattenObservation``
(:func:`stack_env`), so the policy is SB3's ``MlpPolicy`` on ``k * obs_dim`` inputs and
``VecNormalize`` keeps per-entry statistics. The scorers play raw, unwrapped
environments (:func:`baselines.agents.juggling_score.play_until_ended`); there the
policy stacks for itself (:class:`StackedPolicy`): a fresh one per batch of episodes,
which all start together, gives the policy exactly the wrapper's observations (tested
against the wrapper). ``k = 1`` is no memory (the raw observation).
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np
from numpy.typing import NDArray

__all__ = ["StackedPolicy", "stack_env", "stacked_policy"]

#: Raw observations ``(N, obs_dim)`` to actions.
RawPolicy = Callable[[NDArray[np.float32]], NDArray[np.floating]]


def stack_env(env: Any, k: int) -> Any:
    """``env`` observing its last ``k`` observations, flattened (oldest first); ``env``
    itself when ``k == 1``."""
    if k == 1:
        return env
    from gymnasium.wrappers import FlattenObservation, FrameStackObservation

    return FlattenObservation(FrameStackObservation(env, k))


class StackedPolicy:
    """``inner`` fed the last ``k`` raw observations of each row, flattened, oldest first,
    as :func:`stack_env` would give them: the first call fills each row's stack with its
    (reset) observation. One object per batch of episodes that start together."""

    def __init__(self, inner: RawPolicy, k: int) -> None:
        if isinstance(k, bool) or not isinstance(k, int) or k < 1:
            raise ValueError(f"frame_stack must be an integer >= 1; got {k!r}")
        self.inner, self.k = inner, k
        self._stack: NDArray[np.float32] | None = None

    def __call__(self, obs: NDArray[np.float32]) -> NDArray[np.floating]:
        obs = np.asarray(obs, dtype=np.float32)
        if self._stack is None:
            self._stack = np.repeat(obs[:, None, :], self.k, axis=1)
        else:
            self._stack = np.concatenate([self._stack[:, 1:], obs[:, None, :]], axis=1)
        return self.inner(self._stack.reshape(len(obs), -1))


def stacked_policy(inner: RawPolicy, k: int) -> RawPolicy:
    """``inner`` itself when ``k == 1``, else a fresh :class:`StackedPolicy`."""
    return inner if k == 1 else StackedPolicy(inner, k)
