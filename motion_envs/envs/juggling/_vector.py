"""The juggling ids' native vector environments: ``N`` episodes in one object.

:class:`JugglingVectorEnv` holds ``N`` single environments (each its own MuJoCo model and
data, controller, sensor and generators), resets them with the single environment's own
``reset`` and keeps the episode bookkeeping of :class:`gymnasium.vector.SyncVectorEnv`:
seeds (``seed + i``), the three autoreset modes and the infos, batched as
``SyncVectorEnv`` batches them (``VectorEnv._add_info``). A subclass steps the episodes
together (:meth:`JugglingVectorEnv._step_batch`); this class's own step runs each single
environment's ``step`` (the reference, and the path without numba).

Autoreset (``autoreset_mode=``, as ``SyncVectorEnv``):

* ``NEXT_STEP`` (default): the step after an episode's end resets that sub-environment,
  ignores its action and returns reward 0, not terminated/truncated, and the reset's
  infos;
* ``SAME_STEP``: the step that ends an episode returns the next one's first observation;
  the last observation and infos are in ``infos["final_obs"]`` and
  ``infos["final_info"]``;
* ``DISABLED``: no autoreset; reset ended sub-environments with
  ``reset(options={"reset_mask": mask})`` before stepping them again (stepping an ended
  one raises ``RuntimeError``).

Infos: ``infos[key]`` is an ``(N, ...)`` array and ``infos["_" + key]`` marks the
sub-environments it applies to; entries outside the mask are unspecified. Every value is
numeric (array converters such as Gymnasium's ``NumpyToTorch`` take them): the single
environment's text ``phase`` is its index in :data:`PHASE_NAMES` (int64), Cascade-v0's
``phases`` an ``(N, 2)`` int64 array of such indices and its ``held`` an ``(N, 2)`` bool
array (:func:`numeric_info`); ``venv.phase_names`` is the lookup.

Episode length (``max_episode_steps=K``, as ``gym.make_vec(id, N, max_episode_steps=K)``
passes it): a sub-environment's episode is also truncated at its ``K``-th step, as
``TimeLimit`` truncates a single environment made with ``max_episode_steps=K``; ``None``
(the registration's) keeps only the environment's own end (``max_catches``, time limit).

Threads (``threads=``, numba backend): the worlds' control periods run in up to
``threads`` threads (:mod:`~motion_envs.envs.juggling._batch`); the episodes do not
depend on it (tested bit for bit).
"""

from __future__ import annotations

import os
from collections.abc import Sequence
from concurrent.futures import ThreadPoolExecutor
from typing import Any, ClassVar, SupportsFloat

import gymnasium as gym
import numpy as np
from gymnasium.vector import AutoresetMode
from numpy.typing import NDArray

from motion_envs.datasets.juggling import PHASES
from motion_envs.envs._common import check_autoreset_mode, check_num_envs
from motion_envs.envs._kernels import numba_available
from motion_envs.envs._native_vector import SAME_STEP, NativeVectorEnv, StepResult

__all__ = [
    "PHASE_NAMES",
    "Columns",
    "JugglingVectorEnv",
    "NumericInfo",
    "numeric_info",
]

#: The lookup of the vector infos' phase codes: ``infos["phase"] == PHASE_NAMES.index(name)``.
PHASE_NAMES: tuple[str, ...] = PHASES
_PHASE_CODE = {name: code for code, name in enumerate(PHASE_NAMES)}

_BACKENDS = ("auto", "numba", "python")

#: A step's per-sub-environment values by info key: arrays with the stepped
#: sub-environments along the first axis.
Columns = dict[str, NDArray[Any]]


class JugglingVectorEnv(NativeVectorEnv):
    """``num_envs`` copies of ``single_class(**kwargs)`` (see the module docstring).

    Parameters
    ----------
    num_envs : int
        Number of sub-environments, 1 to ``MAX_NUM_ENVS``.
    autoreset_mode : AutoresetMode or str
        ``NEXT_STEP`` (default), ``SAME_STEP`` or ``DISABLED``.
    backend : str
        ``"auto"`` (default: numba when installed and the subclass batches),
        ``"numba"`` or ``"python"`` (each single environment's ``step``).
    threads : int or None
        Threads stepping the worlds' control periods (numba backend): ``None`` (default)
        uses the CPUs this process may run on, ``1`` none but the caller's.
    max_episode_steps : int or None
        Steps after which an episode is also truncated, as ``TimeLimit`` (``None``, the
        default: the environment's own end only).
    **kwargs
        The single environment's keyword arguments (``level``, ``controller``, ...),
        checked by ``single_class``.
    """

    metadata: dict[str, Any] = {  # noqa: RUF012  (Gymnasium's instance attribute)
        "render_modes": ["rgb_array"],
        "autoreset_mode": AutoresetMode.NEXT_STEP,
    }
    single_class: ClassVar[type[gym.Env[Any, Any]]]
    #: Attributes :meth:`_link` makes from the worlds: not pickled, made again.
    _LINKED: ClassVar[tuple[str, ...]] = ()
    #: ``"python"`` (each single environment's ``step``) or ``"numba"`` (batched).
    backend = "python"
    #: Whether the subclass batches the episodes with numba (``_setup_arrays``,
    #: ``_link``, ``_after_reset``, ``_step_batch``).
    _batched: ClassVar[bool] = False
    #: Whether the subclass's batch also runs as plain Python (``backend="python"``).
    _python_batch: ClassVar[bool] = False
    #: The lookup of the infos' ``phase`` (and ``phases``) codes.
    phase_names: ClassVar[tuple[str, ...]] = PHASE_NAMES

    def __init__(
        self,
        num_envs: int = 1,
        autoreset_mode: AutoresetMode | str = AutoresetMode.NEXT_STEP,
        backend: str = "auto",
        threads: int | None = None,
        max_episode_steps: int | None = None,
        **kwargs: Any,
    ) -> None:
        if backend not in _BACKENDS:
            raise ValueError(f"backend must be one of {list(_BACKENDS)}; got {backend!r}")
        if threads is None:
            threads = len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else 1
        elif isinstance(threads, bool) or not isinstance(threads, int) or threads < 1:
            raise ValueError(f"threads must be a positive int or None; got {threads!r}")
        if backend == "numba" and not numba_available():
            raise ValueError("backend='numba' needs numba (pip install 'motion-envs[fast]')")
        check_num_envs(num_envs)  # before making the first environment
        check_autoreset_mode(autoreset_mode)
        first = self.single_class(**kwargs)  # checks the arguments once
        self._setup_batch(first, num_envs, autoreset_mode, max_episode_steps, 2**62, first.metadata)
        n = self.num_envs
        self.envs: list[Any] = [first] + [self.single_class(**kwargs) for _ in range(n - 1)]
        obs_shape = tuple(first.observation_space.shape or ())
        self._obs = np.zeros((n, *obs_shape), dtype=np.float32)
        self._ended = np.zeros(n, dtype=bool)
        self._elapsed = np.zeros(n, dtype=np.int64)  # steps since the reset (TimeLimit's)
        self.threads = threads
        #: The episodes' batch (a :class:`~motion_envs.envs.juggling._batch.WorldBatch`).
        self._batch: Any = None
        batched = backend != "python" and numba_available() and self._batched
        self.backend = "numba" if batched else "python"
        if batched or self._python_batch:
            self._setup_arrays()

    # -- the compiled code's links to the worlds -------------------------------------------
    def _setup_arrays(self) -> None:
        """Hook: the batched state's arrays (a batched subclass)."""

    def _link(self) -> None:
        """Hook: make the ``_LINKED`` attributes (a batched subclass)."""

    def __getstate__(self) -> dict[str, Any]:
        state = self.__dict__.copy()
        for key in self._LINKED:
            state.pop(key, None)
        return state

    def __setstate__(self, state: dict[str, Any]) -> None:
        self.__dict__.update(state)
        if self.backend == "numba":  # the unpickled worlds are copies: link them
            self._link()

    # -- resets -------------------------------------------------------------------------
    def reset(
        self,
        *,
        seed: int | Sequence[int | None] | None = None,
        options: dict[str, Any] | None = None,
    ) -> tuple[NDArray[np.float32], dict[str, Any]]:
        seeds = self._seeds(seed)
        options = dict(options) if options else {}
        envs = self._reset_targets(options)
        options.pop("reset_mask", None)
        infos: dict[str, Any] = {}
        for i in envs.tolist():
            info = self._reset_env(i, seeds[i], options or None)
            infos = self._add_info(infos, info, i)
        self._started = True
        return self._obs.copy(), infos

    def _reset_env(self, i: int, seed: int | None, options: dict[str, Any] | None = None) -> Any:
        """Reset sub-environment ``i`` with the single environment's ``reset``; its
        observation goes to ``self._obs[i]``; returns its info."""
        obs, info = self.envs[i].reset(seed=seed, options=options)
        self._obs[i] = obs
        self._ended[i] = False
        self._elapsed[i] = 0
        self._after_reset(i)
        return numeric_info(info)

    def _after_reset(self, i: int) -> None:
        """Hook: sub-environment ``i`` was reset (a batched step loads its state here)."""

    # -- steps --------------------------------------------------------------------------
    def step(self, actions: Any) -> StepResult:
        a = self._check_actions(actions)
        n = self.num_envs
        rewards = np.zeros(n, dtype=np.float64)
        terminated = np.zeros(n, dtype=bool)
        truncated = np.zeros(n, dtype=bool)
        resetting = self._resetting(self._ended)
        stepped = np.flatnonzero(~resetting)
        infos: dict[str, Any] = {}
        if stepped.size:
            obs, rew, term, trunc, columns = self._step_batch(stepped, a[stepped])
            self._elapsed[stepped] += 1
            trunc = trunc | (self._elapsed[stepped] >= self._max_steps)  # TimeLimit's
            self._obs[stepped] = obs
            rewards[stepped], terminated[stepped], truncated[stepped] = rew, term, trunc
            ended = term | trunc
            self._ended[stepped] = ended
            if self._mode == SAME_STEP and ended.any():
                keep = ~ended
                infos = self._scatter(columns, stepped, keep) if keep.any() else {}
                for j in np.flatnonzero(ended).tolist():
                    i = int(stepped[j])
                    final = {"final_obs": obs[j].copy(), "final_info": _row(columns, j)}
                    infos = self._add_info(infos, final, i)
                    infos = self._add_info(infos, self._reset_env(i, None), i)
            else:
                infos = self._scatter(columns, stepped, np.ones(stepped.size, dtype=bool))
        for i in np.flatnonzero(resetting).tolist():
            infos = self._add_info(infos, self._reset_env(i, None), i)
        return self._obs.copy(), rewards, terminated, truncated, infos

    def _scatter(
        self, columns: Columns, stepped: NDArray[np.int64], keep: NDArray[np.bool_]
    ) -> dict[str, Any]:
        """The step columns of ``stepped[keep]`` as vector infos (``(N, ...)`` arrays
        and masks)."""
        n = self.num_envs
        mask = np.zeros(n, dtype=bool)
        mask[stepped[keep]] = True
        rows = stepped[keep]
        infos: dict[str, Any] = {}
        every = rows.size == n  # all sub-environments, in order: the columns as they are
        for key, column in columns.items():
            if every:
                infos[key] = np.ascontiguousarray(column)  # a copy of a strided view
                infos["_" + key] = mask.copy()
                continue
            if column.dtype == object:
                full = np.full(n, None, dtype=object)
            else:
                full = np.zeros((n, *column.shape[1:]), dtype=column.dtype)
            full[rows] = column[keep]
            infos[key] = full
            infos["_" + key] = mask.copy()  # own masks: _add_info sets them one by one
        return infos

    def _step_batch(self, envs: NDArray[np.int64], actions: NDArray[np.float64]) -> tuple[
        NDArray[np.float32], NDArray[np.float64], NDArray[np.bool_], NDArray[np.bool_], Columns
    ]:  # fmt: skip
        """Step sub-environments ``envs`` with ``actions`` (one row each); returns their
        observations, rewards, terminations, truncations and info columns. This one runs
        each single environment's ``step``."""
        results = [self.envs[i].step(row) for i, row in zip(envs.tolist(), actions, strict=True)]
        obs = np.stack([r[0] for r in results]).astype(np.float32, copy=False)
        rew = np.array([r[1] for r in results], dtype=np.float64)
        term = np.array([r[2] for r in results], dtype=bool)
        trunc = np.array([r[3] for r in results], dtype=bool)
        return obs, rew, term, trunc, _columns([r[4] for r in results])

    # -- the rest -----------------------------------------------------------------------
    def _render_env(self, i: int) -> Any:
        return self.envs[i].render()

    @property
    def _pool(self) -> ThreadPoolExecutor | None:
        """The batch's threads (None: none running)."""
        return None if self._batch is None else self._batch._pool

    def close_extras(self, **kwargs: Any) -> None:
        if self._batch is not None:
            self._batch.close()
        for env in self.envs:
            env.close()


def numeric_info(info: dict[str, Any]) -> dict[str, Any]:
    """A single juggling environment's ``info`` with its text as numbers: ``phase`` (a
    name of :data:`PHASE_NAMES`) -> its index; ``phases`` (a name per hand) -> an int64
    array of indices; ``held`` (a flag per hand) -> a bool array. Other values as they
    are."""
    out = dict(info)
    if isinstance(out.get("phase"), str):
        out["phase"] = _PHASE_CODE[out["phase"]]
    if isinstance(out.get("phases"), (tuple, list)):
        out["phases"] = np.array([_PHASE_CODE[p] for p in out["phases"]], dtype=np.int64)
    if isinstance(out.get("held"), (tuple, list)):
        out["held"] = np.array(out["held"], dtype=bool)
    return out


def _columns(infos: list[dict[str, Any]]) -> Columns:
    """Info dicts of single steps (same keys) as columns (their text as numbers,
    :func:`numeric_info`), typed as ``_add_info`` types them (``float`` to float64,
    ``int`` to int64, ``bool`` to bool, arrays stacked, anything else an object array)."""
    infos = [numeric_info(info) for info in infos]
    out: Columns = {}
    for key, first in infos[0].items():
        values = [info[key] for info in infos]
        if type(first) in (int, float, bool) or isinstance(first, np.number):
            out[key] = np.array(values, dtype=type(first))
        elif isinstance(first, np.ndarray):
            out[key] = np.stack(values).astype(first.dtype, copy=False)
        else:
            column = np.empty(len(values), dtype=object)
            column[:] = values
            out[key] = column
    return out


def _row(columns: Columns, j: int) -> dict[str, Any]:
    """Row ``j`` of ``columns`` as a single environment's info dict (Python scalars,
    arrays copied)."""
    row: dict[str, Any] = {}
    for key, column in columns.items():
        value = column[j]
        row[key] = value.copy() if isinstance(value, np.ndarray) else (
            value.item() if isinstance(value, np.generic) else value
        )  # fmt: skip
    return row


class NumericInfo(gym.Wrapper[Any, Any, Any, Any]):
    """A juggling environment whose infos hold numbers only: ``phase`` as its index in
    :data:`PHASE_NAMES` (``phase_names``, the lookup)."""

    phase_names: ClassVar[tuple[str, ...]] = PHASE_NAMES

    def reset(self, **kwargs: Any) -> tuple[Any, dict[str, Any]]:
        obs, info = self.env.reset(**kwargs)
        return obs, numeric_info(info)

    def step(self, action: Any) -> tuple[Any, SupportsFloat, bool, bool, dict[str, Any]]:
        obs, reward, terminated, truncated, info = self.env.step(action)
        return obs, reward, terminated, truncated, numeric_info(info)
