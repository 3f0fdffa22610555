"""The core of the reaching environments: one kind object per data kind, one step.

A reaching environment replays one precomputed trajectory of a task per episode on the
:data:`N_STEPS`-point grid (``task.steps`` and ``task.obs``); the agent sets the state of
each grid point as the nominal's plus a correction. What differs between the data kinds
(orientations, positions, ...) is held by a :class:`ReachKind` object, defined in the
kind's own module (:mod:`~motion_envs.envs.orientation_reach`,
:mod:`~motion_envs.envs.position_reach`):

* the step row layout (:meth:`ReachKind.row_layout`: named slices of a ``task.steps``
  row) and the observation layout (:class:`ObsLayout`, the same for every kind: start,
  goal, current state, ``tau``, nominal, one-hot task);
* the info keys: :attr:`ReachKind.step_keys` every step (before ``tau``) and
  :attr:`ReachKind.end_keys`, the running maxima reported at the episode's end;
* the reward weight names (:attr:`ReachKind.weight_keys`, in the kernels' order);
* the step kernels, one per backend: :meth:`ReachKind.scalar_step` (a single
  environment: Python floats), :meth:`ReachKind.batch_step` (numpy arrays of
  sub-environments) and :attr:`ReachKind.fused_physics` (compiled by numba into the
  vector environments' loop, :mod:`motion_envs.envs._fused`); all three evaluate the
  kernels of :mod:`motion_envs.envs._kernels`, so they agree bit for bit;
* task building and the criterion (:attr:`ReachKind.load_task`,
  :attr:`ReachKind.max_errors`).

:class:`ReachEnv` (single environment) and
:class:`~motion_envs.envs._reach_vector.ReachVectorEnv` (native vector environment) are
written once over a kind: argument checks, drawing the trajectory at reset, the step
(action check and clipping, the kind's kernel, info, running maxima, the next
observation), the render guard, ``close`` and pickling.
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from typing import Any, ClassVar

import gymnasium as gym
import numpy as np
from numpy.typing import NDArray

from motion_envs.envs._calibration import CalibrationDraws, check_calibration
from motion_envs.envs._common import (
    N_STEPS,
    JsonSpecMixin,
    LazyRendererMixin,
    as_action,
    check_fraction,
    check_render,
    check_reward_weights,
    check_scale,
    check_seed,
    draw_trajectory,
    has_render_mode,
)

__all__ = [
    "ObsLayout",
    "ReachEnv",
    "ReachKind",
    "ReachTask",
    "TrajectoryLabelsMixin",
    "checked_prediction",
    "observation_table",
    "reset_labels",
    "step_table",
    "with_timing",
    "zero_action_errors",
]


@dataclass(frozen=True)
class ObsLayout:
    """Named parts of a reaching observation for a state of ``dim`` values.

    ``start``, ``goal``, ``current`` (the last state set) and ``nominal`` (the nominal's
    state at the next grid point) hold ``dim`` values each, ``tau`` one, ``task`` the
    one-hot task (to the end, or to the v1 timing entries).
    """

    start: slice
    goal: slice
    current: slice
    tau: int
    nominal: slice
    task: slice

    @classmethod
    def for_dim(cls, dim: int) -> ObsLayout:
        return cls(
            start=slice(0, dim),
            goal=slice(dim, 2 * dim),
            current=slice(2 * dim, 3 * dim),
            tau=3 * dim,
            nominal=slice(3 * dim + 1, 4 * dim + 1),
            task=slice(4 * dim + 1, None),
        )

    def size(self, n_tasks: int) -> int:
        """Observation size (without the v1 timing entries)."""
        return int(self.task.start) + n_tasks


def observation_table(
    layout: ObsLayout,
    starts: NDArray[np.float64],
    goals: NDArray[np.float64],
    tau: NDArray[np.float64],
    nominal: NDArray[np.float64],
    task_index: NDArray[np.int64],
    n_tasks: int,
    low: Any,
    high: Any,
) -> NDArray[np.float32]:
    """``obs[l, j]``: the observation before the step that sets grid point ``j`` of
    trajectory ``l`` (``j = n``: after the last step), the current state left at 0,
    clipped to ``[low, high]``. ``starts``, ``goals`` ``(L, dim)``, ``nominal`` ``(L, n,
    dim)``, ``tau`` the grid, ``task_index`` ``(L,)`` into the sorted task names."""
    L, n = nominal.shape[:2]
    obs = np.zeros((L, n + 1, layout.size(n_tasks)), dtype=np.float32)
    obs[:, :, layout.start] = starts[:, None]
    obs[:, :, layout.goal] = goals[:, None]
    obs[:, :n, layout.tau] = tau
    obs[:, n, layout.tau] = 1.0
    obs[:, :n, layout.nominal] = nominal
    obs[:, n, layout.nominal] = nominal[:, -1]
    obs[np.arange(L), :, layout.task.start + task_index] = 1.0
    np.clip(obs, low, high, out=obs)
    return obs


def with_timing(
    obs: NDArray[np.float32], layout: ObsLayout, durations: NDArray[np.float64]
) -> NDArray[np.float32]:
    """``obs`` with the v1 timing entries appended: the movement's duration ``T`` and the
    elapsed time ``tau T`` (s), ``durations`` ``(L,)`` per trajectory."""
    elapsed = durations[:, None] * obs[:, :, layout.tau].astype(np.float64)
    timing = np.stack([np.broadcast_to(durations[:, None], elapsed.shape), elapsed], axis=2)
    return np.concatenate([obs, timing.astype(np.float32)], axis=2)


def reset_labels(task: Any) -> dict[str, NDArray[np.object_]]:
    """The text entries of a single environment's reset ``info``, for every trajectory.

    ``trajectory_id`` and ``task`` (and ``subject`` when the task has subjects) ->
    ``(L,)`` object array of ``str``; the native vector environments batch these exactly
    as ``SyncVectorEnv`` batches the single environments' reset infos.
    """
    fields = {"trajectory_id": "trajectory_ids", "task": "tasks", "subject": "subjects"}
    return {
        key: np.asarray(getattr(task, attr)).astype(str).astype(object)
        for key, attr in fields.items()
        if hasattr(task, attr)
    }


class TrajectoryLabelsMixin:
    """A vector environment whose infos carry only ``trajectory_index``: the text of the
    single environment's reset info is looked up here."""

    _labels: dict[str, NDArray[np.object_]]

    @property
    def trajectory_labels(self) -> dict[str, NDArray[np.object_]]:
        """The text of the single environment's reset info by trajectory:
        ``trajectory_labels["trajectory_id"][infos["trajectory_index"][i]]`` (also
        ``"task"``, and ``"subject"`` for orientation). Every value in the vector infos is
        numeric, so array converters such as Gymnasium's ``NumpyToTorch`` take them."""
        return dict(self._labels)


class ReachTask:
    """Properties of the precomputed episodes of a split (the kinds' task dataclasses)."""

    steps: NDArray[np.float64]  # (L, n, row width)
    obs: NDArray[np.float32]  # (L, n + 1, obs_dim)

    @property
    def n_trajectories(self) -> int:
        return int(self.steps.shape[0])

    @property
    def obs_dim(self) -> int:
        return int(self.obs.shape[2])


class ReachKind:
    """One data kind of reaching environment (see the module docstring).

    A kind module subclasses this, sets the class attributes and implements the
    methods; one instance serves every environment of the kind.
    """

    #: Short name (also names the compiled vector loop of the kind).
    name: ClassVar[str]
    #: Info keys of every step, in the order of the kernels' values, before ``tau``;
    #: the first is ``"error"``, the paper's per-step error.
    step_keys: ClassVar[tuple[str, ...]]
    #: ``(key, step key)``: ``info[key]`` at the episode's end is the running maximum of
    #: ``info[step key]`` over the episode.
    end_keys: ClassVar[tuple[tuple[str, str], ...]]
    #: Reward weight names, in the order the kernels take them.
    weight_keys: ClassVar[tuple[str, ...]]
    #: Default reward weights (the environment's ``reward_weights=None``).
    default_weights: ClassVar[Mapping[str, float]]
    #: Largest accepted ``residual_scale``.
    max_residual_scale: ClassVar[float]
    #: ``load_task(...)``: build (or reuse) the precomputed episodes of a split (the
    #: kind's ``load_*_task``).
    load_task: ClassVar[Callable[..., Any]]
    #: ``max_errors(task, predicted)``: ``(L,)`` per-episode max error of a predicted
    #: trajectory per episode of ``task``, scored by the step kernel with a zero action
    #: (the kind's criterion, ``*_max_errors``).
    max_errors: ClassVar[Callable[..., NDArray[np.float64]]]

    #: ``fused_physics(row, a, scale, w, q) -> (reward, values)``: one step of one
    #: sub-environment on float64 arrays (``row`` a ``task.steps`` row, ``a`` the clipped
    #: action, ``w`` the weights), writing the new state into ``q`` and returning the
    #: reward and the :attr:`step_keys` values (a tuple); plain Python that numba
    #: compiles unchanged and inlines into the vector loop, with the functions it calls
    #: by global name (:func:`motion_envs.envs._fused.batch_step_of`).
    fused_physics: ClassVar[Callable[..., tuple[float, tuple[float, ...]]]]

    def state_dim(self, task: Any) -> int:
        """Number of values of the state the agent sets (4 for a quaternion)."""
        raise NotImplementedError

    def action_dim(self, task: Any) -> int:
        """Number of action values (3 for a rotation vector)."""
        raise NotImplementedError

    def row_layout(self, dim: int) -> dict[str, slice]:
        """Named slices of a ``task.steps`` row for a state of ``dim`` values."""
        raise NotImplementedError

    def scalar_step(
        self, row: list[float], a: list[float], scale: float, w: tuple[float, ...]
    ) -> tuple[tuple[float, ...], float, dict[str, float]]:
        """One step of a single environment: ``(state, reward, info)``, ``info`` holding
        :attr:`step_keys` in order (Python floats; ``a`` clipped)."""
        raise NotImplementedError

    def batch_step(
        self, rows: NDArray[np.float64], a: NDArray[np.float64], scale: float, w: tuple[float, ...]
    ) -> tuple[NDArray[np.float64], Any, list[Any]]:
        """One step of ``N`` sub-environments: ``rows`` ``(width, N)`` (a ``task.steps``
        row per column), ``a`` ``(N, d)`` clipped; returns the states ``(N, dim)``, the
        rewards and the :attr:`step_keys` values (``(N,)`` arrays)."""
        raise NotImplementedError

    def __reduce__(self) -> str:
        return self.instance_name  # pickled by reference: the module's instance

    #: Name of the kind's instance in its module (pickling by reference).
    instance_name: ClassVar[str]


def _finite_clipped(acts: list[float]) -> list[float]:
    """``acts`` clipped to ``[-1, 1]``; ``ValueError`` if any is NaN or infinite."""
    for v in acts:
        if not math.isfinite(v):
            raise ValueError(f"action must be finite; got {acts}")
    return [-1.0 if v < -1.0 else (1.0 if v > 1.0 else v) for v in acts]


class FrameAfterResetMixin:
    """A single environment whose episode is one trajectory of its task: drawn at reset
    (:meth:`_draw_episode`) and drawn by ``render()`` (the frame of
    :meth:`_render_frame`, None without a render mode, ``RuntimeError`` before the first
    reset, ``_index < 0``)."""

    render_mode: str | None
    task: Any
    _index: int

    def _draw_episode(self, options: dict[str, Any] | None, rng: np.random.Generator) -> int:
        """At ``reset``: the episode's trajectory (:func:`draw_trajectory` over the task's),
        kept as ``_index``."""
        self._index = draw_trajectory(options, self.task.n_trajectories, rng)
        return self._index

    def render(self) -> NDArray[np.uint8] | None:
        if not has_render_mode(self.render_mode):
            return None
        if self._index < 0:
            raise RuntimeError("call reset() before render()")
        return self._render_frame()

    def _render_frame(self) -> NDArray[np.uint8]:
        raise NotImplementedError


class ReachEnv(JsonSpecMixin, FrameAfterResetMixin, LazyRendererMixin, gym.Env):
    """A single reaching environment over a :class:`ReachKind`.

    A subclass sets ``kind`` (class attribute), checks its arguments with
    :meth:`_check_arguments`, sets ``task`` and ``observation_space`` and calls
    :meth:`_setup` in ``__init__`` (and :meth:`_setup_calibration` for ``calibration=K``,
    which extends the observation space), and implements :meth:`_render_frame`.
    """

    metadata = {"render_modes": ["rgb_array"], "render_fps": 25}  # noqa: RUF012 (gymnasium's)
    kind: ClassVar[ReachKind]
    task: Any
    _starts: NDArray[np.float64]
    _cur: slice
    _cur_bounds: tuple[tuple[float, ...], tuple[float, ...]] | None = None
    #: ``calibration = K``: the draws of the person's other reaches (None for ``K = 0``).
    _calibration: CalibrationDraws | None = None
    calibration: int = 0

    def _check_arguments(
        self,
        render_mode: str | None,
        width: int,
        height: int,
        residual_scale: float,
        reward_weights: Mapping[str, float] | None,
        test_fraction: float = 0.25,
        split_seed: int = 0,
    ) -> None:
        """Check and store the arguments every reaching environment takes; no episode yet.

        ``residual_scale`` must lie in ``(0, kind.max_residual_scale]``, ``test_fraction``
        in ``(0, 1)``, ``split_seed`` be an integer ``>= 0``, ``width`` and ``height``
        integers in ``[16, MAX_FRAME_SIZE]`` (:func:`check_render`), reward weights in
        ``[0, MAX_REWARD_WEIGHT]``.
        """
        check_render(render_mode, self.metadata["render_modes"], width, height)
        self.residual_scale = check_scale(residual_scale, self.kind.max_residual_scale)
        check_fraction(test_fraction)
        check_seed(split_seed)
        self.reward_weights = check_reward_weights(reward_weights, self.kind.default_weights)
        self.render_mode = render_mode
        self.width, self.height = int(width), int(height)
        self._renderer: Any = None
        self._index = -1
        self._k = N_STEPS
        self._history: list[tuple[float, ...]] = []

    def _setup(
        self,
        starts: NDArray[np.float64],
        cur_bounds: tuple[tuple[float, ...], tuple[float, ...]] | None = None,
    ) -> None:
        """After ``task``: the action space, ``starts`` ``(L, dim)`` (the state at reset)
        and, if the observation clips the current state, its ``(low, high)`` per value."""
        kind = self.kind
        dim = kind.state_dim(self.task)
        d = kind.action_dim(self.task)
        self.action_space = gym.spaces.Box(-1.0, 1.0, (d,), dtype=np.float32)
        self._action_shape = (d,)
        self._starts = starts
        self._cur = ObsLayout.for_dim(dim).current
        self._cur_bounds = cur_bounds
        self._weights = tuple(self.reward_weights[key] for key in kind.weight_keys)
        self._kind_step = kind.scalar_step  # bound once (hot path)
        self._labels = reset_labels(self.task)
        # the running maxima: (position in _running, step key), (end key, position)
        self._max_of = tuple((j, src) for j, (_, src) in enumerate(kind.end_keys))
        self._end_of = tuple((key, j) for j, (key, _) in enumerate(kind.end_keys))
        self._running = [0.0] * len(kind.end_keys)

    def _setup_calibration(
        self, calibration: Any, subjects: Any, features: Callable[[], NDArray[np.float64]]
    ) -> None:
        """``calibration = K > 0``: every observation of an episode ends with the summary
        of ``K`` other reaches of its person (:mod:`motion_envs.envs._calibration`;
        ``features()`` computed only then); ``K = 0`` changes nothing."""
        self.calibration = check_calibration(calibration)
        if self.calibration:
            self._calibration = CalibrationDraws(self.calibration, subjects, features())
            self.observation_space = self._calibration.extend(self.observation_space)  # type: ignore[arg-type]

    # -- episode --------------------------------------------------------------------
    def reset(
        self, *, seed: int | None = None, options: dict[str, Any] | None = None
    ) -> tuple[NDArray[np.float32], dict[str, Any]]:
        super().reset(seed=seed)
        index = self._draw_episode(options, self.np_random)
        self._k = 0
        self._steps = self.task.steps[index].tolist()
        self._obs = self.task.obs[index]
        info: dict[str, Any] = {"trajectory_index": index}
        if self._calibration is not None:  # the summary, the same for every step
            summary, drawn = self._calibration.draw(self.np_random, index)
            tail = np.broadcast_to(summary.astype(np.float32), (self._obs.shape[0], summary.size))
            self._obs = np.concatenate([self._obs, tail], axis=1)
            info["calibration_trajectories"] = drawn
        start = tuple(self._starts[index].tolist())
        self._history = [start]
        self._running = [0.0] * len(self._running)
        obs = self._obs[0].copy()
        obs[self._cur] = start
        for key, labels in self._labels.items():
            info[key] = str(labels[index])
        return obs, info

    def step(self, action: Any) -> tuple[NDArray[np.float32], float, bool, bool, dict[str, Any]]:
        k = self._k
        if k >= N_STEPS:
            raise RuntimeError("the episode has ended (or never started); call reset() first")
        acts = as_action(action, self._action_shape).tolist()
        for v in acts:
            if not -1.0 <= v <= 1.0:  # out of range, NaN or infinite (else: as it is)
                acts = _finite_clipped(acts)
                break
        q, reward, info = self._kind_step(self._steps[k], acts, self.residual_scale, self._weights)
        self._k = k + 1
        self._history.append(q)
        running = self._running
        for j, src in self._max_of:
            v = info[src]
            if v > running[j]:
                running[j] = v
        obs = self._obs[k + 1].copy()
        if self._cur_bounds is None:
            obs[self._cur] = q
        else:
            lo, hi = self._cur_bounds
            obs[self._cur] = [min(max(v, a), b) for v, a, b in zip(q, lo, hi, strict=True)]
        info["tau"] = k / (N_STEPS - 1)
        terminated = k + 1 == N_STEPS
        if terminated:
            for key, j in self._end_of:
                info[key] = running[j]
        return obs, reward, terminated, False, info


def step_table(layout: Mapping[str, slice], parts: Mapping[str, NDArray[np.float64]]) -> Any:
    """``task.steps``: the ``(L, n, width)`` parts concatenated in the order of the
    kind's row ``layout`` (checked against it: the layout is where the kernels read)."""
    for name, part in parts.items():
        s = layout[name]
        if part.shape[2] != s.stop - s.start:
            raise ValueError(f"step part {name!r} has width {part.shape[2]}; layout {s}")
    slices = list(layout.values())
    if list(parts) != list(layout) or any(a.stop != b.start for a, b in itertools.pairwise(slices)):
        raise ValueError(f"step parts {list(parts)} do not follow the layout {layout}")
    return np.concatenate([parts[name] for name in layout], axis=2)


def zero_action_errors(
    kind: ReachKind, task: Any, steps: NDArray[np.float64]
) -> NDArray[np.float64]:
    """``(L,)`` per-episode ``max_k`` of the step error of ``kind``'s kernel
    (:meth:`ReachKind.batch_step`) with a zero action, on a step table ``steps`` laid out
    as ``task.steps`` (the kinds' ``max_errors``: a predicted nominal in its rows)."""
    L, n, width = steps.shape
    # a zero action makes every grid point independent of the others: one batch of L n rows
    zero = np.zeros((L * n, kind.action_dim(task)))
    weights = (0.0,) * len(kind.weight_keys)
    _, _, values = kind.batch_step(steps.reshape(L * n, width).T, zero, 1.0, weights)
    out: NDArray[np.float64] = np.asarray(values[0]).reshape(L, n).max(axis=1)
    return out


def checked_prediction(values: Any, task: Any, width: int, name: str) -> NDArray[np.float64]:
    """``values`` as a float64 ``(L, n, width)`` array of one prediction per episode of
    ``task`` (or of a step table ``(L, n, ...)``); ``ValueError`` naming ``name`` for
    another shape."""
    out = np.asarray(values, dtype=np.float64)
    steps = task if isinstance(task, np.ndarray) else task.steps
    shape = (*steps.shape[:2], width)
    if out.shape != shape:
        raise ValueError(f"{name} must have shape {shape}; got {out.shape}")
    return out
