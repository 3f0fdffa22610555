"""The native vector environments' episode bookkeeping, written once.

:class:`NativeVectorEnv` is the base of every native vector environment of the package
(the reaching ones, :class:`~motion_envs.envs._reach_vector.ReachVectorEnv`, the
coefficient ones, :class:`~motion_envs.envs._coefficients.CoefficientVectorEnv`, and the
juggling ones, :class:`~motion_envs.envs.juggling._vector.JugglingVectorEnv`). It keeps
what :class:`gymnasium.vector.SyncVectorEnv` keeps around its sub-environments, so that a
subclass writes only its batched step:

* the batch's spaces, ``num_envs``, ``render_mode`` and metadata from one checked single
  environment (:meth:`NativeVectorEnv._setup_batch`);
* seeding: ``reset(seed=s)`` seeds sub-environment ``i`` with ``s + i``, a list gives one
  seed each, ``None`` keeps each sub-environment's generator
  (:meth:`NativeVectorEnv._seeds`); a subclass that holds no single environments keeps one
  ``np_random`` generator per sub-environment (:meth:`NativeVectorEnv._seed_rngs`, the
  generator ``gymnasium.utils.seeding.np_random`` gives a single environment);
* ``reset(options={"reset_mask": mask})`` (:meth:`NativeVectorEnv._reset_targets`);
* the three autoreset modes of :class:`gymnasium.vector.AutoresetMode`, as
  ``SyncVectorEnv`` runs them: ``NEXT_STEP`` resets an ended sub-environment on the next
  step (its action ignored, reward 0, not terminated or truncated, the reset's infos),
  ``SAME_STEP`` on the step that ends it (the last observation and infos in
  ``infos["final_obs"]`` and ``infos["final_info"]``), ``DISABLED`` never (stepping an
  ended one raises ``RuntimeError``) (:meth:`NativeVectorEnv._resetting`,
  :meth:`NativeVectorEnv._add_final`);
* infos in Gymnasium's convention: ``infos[key]`` an ``(N, ...)`` array and
  ``infos["_" + key]`` the mask of the sub-environments it applies to.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any, Final

import gymnasium as gym
import numpy as np
from gymnasium.utils import seeding
from gymnasium.vector import AutoresetMode
from gymnasium.vector.utils import batch_space
from numpy.typing import NDArray

from motion_envs.envs._common import (
    as_action,
    check_autoreset_mode,
    check_max_episode_steps,
    check_num_envs,
    env_footprint,
)

__all__ = ["DISABLED", "NEXT_STEP", "SAME_STEP", "NativeVectorEnv", "StepResult"]

#: The autoreset modes as integers (what compiled step loops compare with).
NEXT_STEP: Final = 0
SAME_STEP: Final = 1
DISABLED: Final = 2
_MODES = {AutoresetMode.NEXT_STEP: NEXT_STEP, AutoresetMode.SAME_STEP: SAME_STEP}
_MODES[AutoresetMode.DISABLED] = DISABLED

#: observations, rewards, terminations, truncations, infos
StepResult = tuple[
    NDArray[np.float32], NDArray[np.float64], NDArray[np.bool_], NDArray[np.bool_], dict[str, Any]
]


class NativeVectorEnv(gym.vector.VectorEnv):
    """The bookkeeping of ``num_envs`` episodes stepped together (module docstring).

    A subclass calls :meth:`_setup_batch` in its ``__init__``, checks a step's actions
    with :meth:`_check_actions`, decides which sub-environments reset before stepping with
    :meth:`_resetting`, and adds the ``SAME_STEP`` final observations with
    :meth:`_add_final`; ``render`` renders :meth:`_render_env` of each.
    """

    metadata: dict[str, Any] = {  # noqa: RUF012  (Gymnasium's instance attribute)
        "render_modes": ["rgb_array"],
        "autoreset_mode": AutoresetMode.NEXT_STEP,
    }
    #: Whether every sub-environment has been reset once (the first reset resets all).
    _started = False

    def _setup_batch(
        self,
        single: Any,
        num_envs: Any,
        autoreset_mode: Any,
        max_episode_steps: Any,
        default_steps: int,
        metadata: dict[str, Any],
    ) -> None:
        """``num_envs`` copies of ``single`` (a checked single environment): the counts,
        the autoreset mode (``_mode``, an integer), the episode limit (``_max_steps``,
        ``default_steps`` when ``max_episode_steps`` is ``None``) and the batched spaces;
        the metadata are ``metadata`` with the mode."""
        self.num_envs = n = check_num_envs(num_envs, env_footprint(single))
        self._max_steps = check_max_episode_steps(max_episode_steps, default_steps)
        self.autoreset_mode = check_autoreset_mode(autoreset_mode)
        self._mode = _MODES[self.autoreset_mode]
        self.metadata = {**metadata, "autoreset_mode": self.autoreset_mode}
        self.single_action_space = single.action_space
        self.single_observation_space = single.observation_space
        self.action_space = batch_space(self.single_action_space, n)
        self.observation_space = batch_space(self.single_observation_space, n)
        self.render_mode = single.render_mode
        self._action_shape: tuple[int, ...] = (n, *(single.action_space.shape or ()))
        self._arange = np.arange(n)
        self._rngs: list[np.random.Generator | None] = [None] * n

    # -- seeding and resets -------------------------------------------------------------
    def _seeds(self, seed: int | Sequence[int | None] | None) -> list[int | None]:
        """One seed per sub-environment: ``seed + i`` for an int, the list as given,
        ``None`` for each when ``seed`` is ``None`` (``SyncVectorEnv``'s rule)."""
        n = self.num_envs
        if seed is None:
            return [None] * n
        if isinstance(seed, bool):
            raise ValueError(f"seed must be an int or a list of {n} seeds; got {seed!r}")
        if isinstance(seed, (int, np.integer)):
            return [int(seed) + i for i in range(n)]
        seeds = list(seed)
        if len(seeds) != n:
            raise ValueError(f"seed must be an int or a list of {n} seeds; got {len(seeds)}")
        return seeds

    def _seed_rngs(self, seed: int | Sequence[int | None] | None) -> list[int]:
        """Seed the sub-environments' generators ``self._rngs`` (``np_random`` of each
        seed of :meth:`_seeds`; a ``None`` seed keeps a generator made before); returns
        the sub-environments whose generator is new."""
        rngs, fresh = self._rngs, []
        for i, s in enumerate(self._seeds(seed)):
            if s is not None or rngs[i] is None:
                rngs[i], _ = seeding.np_random(s)
                fresh.append(i)
        return fresh

    def _reset_targets(self, options: dict[str, Any]) -> NDArray[np.int64]:
        """The sub-environments a reset resets: every one, or those of
        ``options["reset_mask"]`` (a bool array with a ``True`` entry; the first reset
        resets every sub-environment)."""
        mask = options.get("reset_mask")
        if mask is None:
            return self._arange
        mask = np.asarray(mask)
        if mask.shape != (self.num_envs,) or mask.dtype != np.bool_:
            raise ValueError(f"options['reset_mask'] must be a bool array ({self.num_envs},)")
        if not mask.any():
            raise ValueError("options['reset_mask'] must be a bool array with a True entry")
        if not self._started and not mask.all():
            raise ValueError("the first reset must reset every sub-environment")
        return np.flatnonzero(mask)

    # -- steps --------------------------------------------------------------------------
    def _check_actions(self, actions: Any) -> NDArray[np.float64]:
        """A step's ``actions`` as a C-contiguous float64 ``(N, ...)`` array (one layout
        for compiled code); ``ValueError`` for a wrong shape or non-numbers,
        ``RuntimeError`` before the first reset."""
        if type(actions) is np.ndarray and actions.dtype.kind == "f":
            a = np.ascontiguousarray(actions, dtype=np.float64)
            if a.shape != self._action_shape:
                raise ValueError(f"actions must have shape {self._action_shape}; got {a.shape}")
        else:  # lists, integers; a dict, string or complex raise ValueError
            a = np.ascontiguousarray(as_action(actions, self._action_shape, "actions"))
        if not self._started:
            raise RuntimeError("call reset() before step()")
        return a

    def _resetting(self, ended: NDArray[Any]) -> NDArray[np.bool_]:
        """The sub-environments this step resets instead of stepping, given which ended
        on the last step (``ended``, nonzero where one did): those under ``NEXT_STEP``,
        none otherwise; under ``DISABLED`` an ended one is an error."""
        if self._mode == DISABLED and ended.any():
            self._raise_ended(int(np.flatnonzero(ended)[0]))
        if self._mode == NEXT_STEP:
            return np.array(ended, dtype=np.bool_)
        return np.zeros(self.num_envs, dtype=bool)

    def _raise_ended(self, i: int) -> None:
        raise RuntimeError(
            f"sub-environment {i} has ended and autoreset_mode is DISABLED; call "
            "reset(options={'reset_mask': mask}) for the ended sub-environments first"
        )

    def _add_final(
        self,
        info: dict[str, Any],
        final_obs: NDArray[Any],
        final_info: dict[str, Any],
        ended: NDArray[np.bool_],
    ) -> None:
        """``SAME_STEP``: add the last observations (rows ``ended`` of ``final_obs``, an
        object array as ``SyncVectorEnv`` gives them) and infos of the ended episodes."""
        rows = np.full(self.num_envs, None, dtype=object)
        for i in np.flatnonzero(ended).tolist():
            rows[i] = final_obs[i].copy()
        info["final_obs"] = rows
        info["_final_obs"] = ended
        info["final_info"] = final_info
        info["_final_info"] = ended

    # -- rendering ----------------------------------------------------------------------
    def render(self) -> tuple[Any, ...] | None:
        if self.render_mode is None:
            gym.logger.warn("render() called without a render_mode")
            return None
        return tuple(self._render_env(i) for i in range(self.num_envs))

    def _render_env(self, i: int) -> Any:
        """The frame of sub-environment ``i``."""
        raise NotImplementedError
