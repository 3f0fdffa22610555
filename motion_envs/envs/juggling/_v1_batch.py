"""Juggling-v1's step for a batch of episodes: the ONE home of its controller's commands
between events, its sensor, reward, observation and episode end.

:class:`V1Batch` steps the episodes of ``parts`` (Juggling-v1 single environments: each
its world, controller, sensor and generators) together: the single environment is the
batch of one (its rows are its world's own arrays), the native vector environment
(:class:`~motion_envs.envs.juggling.JugglingV1VectorEnv`) the batch of ``N``; Juggling-v2's
single environment is a batch of one too (``V2Batch``: no ball sensor, every command by
its controller in Python, its camera and the rest of its observation beside). A step:

* the command (:func:`~motion_envs.envs.juggling._v1_step.v1_command`): between the
  plan's events (a release, a catch, a reached end point, decided as the controller
  decides them) an index into the plan on the control grid; at an event the episode's
  own controller runs in Python, its new plan copied back (always, for controllers other
  than ``juggler`` and ``juggler_latency_aware``); the eq. 10 corrections found due made
  in the arrays with the controller's numbers (the catch's rows shared by the catches of
  its duration, :func:`~motion_envs.models.juggling.eq10_rows`; the products stacked,
  :func:`~motion_envs.models.juggling.eq10_many`), the controller given them at its next
  event or reset (:meth:`V1Batch.sync`);
* the worlds' one control period (:class:`~motion_envs.envs.juggling._batch.WorldBatch`);
* the rest (:func:`~motion_envs.envs.juggling._v1_step.v1_finish`): the release scatter
  and the sensor's noise (drawn ahead in blocks from the world's and the sensor's own
  generators: the same sequences), the human-likeness, the reward, the episode's end, the
  observation.

When the worlds' periods run in the caller's thread (always for a single environment),
the three are one call (:func:`~motion_envs.envs.juggling._v1_step.v1_step`) unless a
world needs Python (an event or a correction): then the commands are completed in Python
and the period and the rest are one call (``v1_rest``). With threads the period runs
between two calls.

``backend="numba"`` runs the kernels compiled (:mod:`~motion_envs.envs.juggling._compiled_v1`),
``"python"`` as plain Python (bit-identical).
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np
from numpy.typing import NDArray

from motion_envs.datasets.juggling import PHASES, JugglingState
from motion_envs.envs.juggling import _v1_step
from motion_envs.envs.juggling._batch import NOISE_BLOCK as _NOISE_BLOCK
from motion_envs.envs.juggling._batch import WorldBatch
from motion_envs.envs.juggling._v1_correct import Eq10Corrections
from motion_envs.envs.juggling._v1_step import OUT_COLUMNS
from motion_envs.models.juggling import (
    LIKENESS_TAU,
    ControlOptions,
)

__all__ = ["V1Batch", "v1_info"]

_TOSS, _CATCH = PHASES.index("toss"), PHASES.index("catch")
_FAST_CONTROLLERS = ("juggler", "juggler_latency_aware")
#: Measurement-noise rows drawn from a sensor's generator at a time.
#: A step's per-episode values by info key (the stepped episodes along the first axis).
Columns = dict[str, NDArray[Any]]


class V1Batch(Eq10Corrections, WorldBatch):
    """Juggling-v1's episodes of ``parts`` stepped together (see the module docstring).

    ``parts``: ``JugglingV1Env`` instances with the same arguments; ``backend``:
    ``"numba"`` or ``"python"``; ``threads``: threads stepping the worlds (numba)."""

    LINKED = (*WorldBatch.LINKED, "_kernels", "_trees", "_scratch")
    #: The controllers whose commands between events are made in the arrays (the others'
    #: every command runs in Python).
    FAST: tuple[str, ...] = _FAST_CONTROLLERS

    def __init__(self, parts: Sequence[Any], backend: str, threads: int = 1) -> None:
        super().__init__(parts, backend, threads)
        n, first = self.n, self.parts[0]
        task = first.task
        self._dt, self._gravity = task.dt, task.gravity
        # the true state after the last period
        self._true = np.zeros((n, 8))  # hand x, z, vx, vz, ball x, z, vx, vz
        self._t_flags = np.zeros((n, 3), dtype=np.bool_)  # held, left, dropped
        # what the controller was last shown (the measured state)
        self._values = np.zeros((n, 5))  # time, ball x, z, vx, vz
        self._m_flags = np.zeros((n, 3), dtype=np.bool_)  # held, released, caught
        # the sensor's delay line (a ring shared by all episodes: a reset fills every
        # slot of its own), the observation's measurement history, the noise drawn ahead
        self._ring = np.zeros((first.delay_steps + 1, n, 5))
        self._slot = 0
        self._history = np.zeros((n, first.history, 4))
        self.setup_draws(first)
        # the controller's plan
        self._fast = first.controller_name in self.FAST
        self._latency = first.delay_steps * task.dt
        self._ahead = first.controller_name == "juggler_latency_aware" and self._latency > 0
        self._phase = np.zeros(n, dtype=np.int64)
        self._pk = np.zeros(n, dtype=np.int64)
        self._end_k = np.zeros(n, dtype=np.int64)
        self._grid = np.zeros((n, 1, 2))
        self._glen = np.ones(n, dtype=np.int64)
        self._last = np.zeros((n, 2, 2))
        self._t_start = np.zeros(n)
        self._duration = np.zeros(n)
        self._end = np.zeros((n, 2))
        self._next = np.zeros((n, 2))  # nominal_next, for the slow controllers
        # the current catch's eq. 10 rows (eq10_rows) and coefficients, by grid step;
        # corrections made here reach the controller at its next event (sync)
        self._stale = np.zeros(n, dtype=np.bool_)
        self._pending: list[list[tuple[float, float]]] = [[] for _ in range(n)]
        self._coef = np.zeros((n, 1, 2))
        self._c_basis = np.zeros((n, 1, 1))
        self._c_derivative = np.zeros((n, 1, 1))
        self._c_a = np.zeros((n, 1, 3, 1))
        self._c_pinv = np.zeros((n, 1, 1, 3))
        w = first.reward_weights
        self._bounds = np.stack([first._low, first._high])
        self._residual = (float(first.residual_scale), first.residual_acts.copy())
        self._options: ControlOptions | None = None
        if self._fast:
            self._use_options(first.controller.juggler.options)
        else:
            self._ctl = np.zeros(7)
            self._flags_ctl = (False, False, False)
        scalars = [task.dt, LIKENESS_TAU, w["catch"], w["drop"], w["likeness"], w["action"]]
        scalars += [first.max_catches, first._time_limit, float(self._noisy)]
        self._scalars = np.array(scalars)

    def link(self) -> None:
        """The worlds' links, the kernels, the likeness's k-d trees (again when unpickled)."""
        super().link()
        self.link_steps("motion_envs.envs.juggling._compiled_v1", _v1_step)
        #: per step size ``m``: ``a_out (m, 3)``, ``status (m,)``, ``predicted (m, 2)``
        self._scratch: dict[int, tuple[Any, ...]] = {}

    def _use_options(self, options: ControlOptions) -> None:
        """The juggler's options as the command reads them."""
        self._options = options
        task = self.parts[0].task
        self._flags_ctl = (True, bool(options.correction), self._ahead)
        self._ctl = np.array(
            [task.dt, task.gravity, self._latency, options.correction_tolerance, _TOSS, _CATCH,
             options.release_after]
        )  # fmt: skip

    # -- a reset ---------------------------------------------------------------------------
    def load(self, i: int) -> None:
        """Copy episode ``i``'s state after its reset (world, sensor, controller) into
        the arrays; draw its noise ahead."""
        if not self._linked:
            self.link()
        env = self.parts[i]
        self.load_world(i)
        q, v = env.data.qpos, env.data.qvel
        self._true[i] = (q[0], q[1], v[0], v[1], q[2], q[3], v[2], v[3])
        self._t_flags[i] = (self._holder[i, 0] >= 0, self._left[i, 0], self._dropped[i, 0])
        state = env._state
        self._values[i] = (state.time, *state.ball_pos, *state.ball_vel)
        self._m_flags[i] = (state.held, state.released, state.caught)
        self._ring[:, i, :4] = self._true[i, 4:]  # BallSensor.reset: the held ball
        self._ring[:, i, 4] = 1.0
        self._history[i] = self._values[i, 1:]
        self._counts[i] = 0
        self._stale[i] = False
        self._pending[i].clear()
        self._noise_at[i] = self._rel_at[i] = _NOISE_BLOCK
        self._draw(i)
        self._load_plan(i)

    def _draw(self, i: int) -> None:
        """Draw episode ``i``'s used-up noise ahead: a block of rows from the sensor's own
        generator (the sequence of as many ``standard_normal(4)`` calls), from the world's
        for the releases (of ``standard_normal(2)`` calls)."""
        if self._noisy and self._noise_at[i] == _NOISE_BLOCK:
            self._noise[i] = self.parts[i].sensor._rng.standard_normal((_NOISE_BLOCK, 4))
            self._noise_at[i] = 0
        if self._scatter and self._rel_at[i] == _NOISE_BLOCK:
            self._rel_noise[i] = self.parts[i].world._rng.standard_normal((_NOISE_BLOCK, 2))
            self._rel_at[i] = 0

    def _plan(self) -> tuple[Any, ...]:
        """The plans as :func:`~motion_envs.envs.juggling._v1_step.v1_finish` reads them."""
        return (
            self._phase, self._pk, self._duration, self._end, self._grid, self._glen,
            self._next, self._fast, self._history,
        )  # fmt: skip

    def observation(self, i: int) -> NDArray[np.float32]:
        """Episode ``i``'s observation now (at its reset)."""
        obs = np.empty(self._bounds.shape[1], dtype=np.float32)
        true = (self._true, self._t_flags)
        self._kernels.v1_observe(i, obs, true, self._plan(), self._bounds, self._dt)
        return obs

    def _load_plan(self, i: int) -> None:
        """Copy episode ``i``'s controller state into the arrays."""
        c = self.parts[i].controller
        if not self._fast:
            self._phase[i] = PHASES.index(c.phase)
            self._pk[i] = self._episode(i).k
            self._duration[i] = c.duration
            self._end[i] = c.plan_end
            self._next[i] = c.nominal_next()
            return
        ep = self._episode(i)
        self._phase[i] = PHASES.index(ep.phase)
        self._pk[i] = ep.k
        self._end_k[i] = ep.end_k
        grid = ep.grid
        if grid.shape[0] > self._grid.shape[1]:
            wider = np.zeros((self.n, grid.shape[0], 2))
            wider[:, : self._grid.shape[1]] = self._grid
            self._grid = wider
        self._grid[i, : grid.shape[0]] = grid
        self._glen[i] = grid.shape[0]
        self._last[i, 0], self._last[i, 1] = ep._last[0], ep._last[1]
        self._t_start[i] = ep.t_start
        self._duration[i] = ep.duration
        self._end[i] = ep.end
        if ep.phase == "catch":
            self._load_rows(i, ep)

    # -- the step -------------------------------------------------------------------------
    def step(self, envs: NDArray[np.int64], actions: NDArray[np.float64]) -> tuple[
        NDArray[np.float32], NDArray[np.float64]
    ]:  # fmt: skip
        """Step episodes ``envs`` with ``actions (m, 2)`` (as given: clipped here, NaN
        counts as 0); returns their observations and their rows of
        :data:`~motion_envs.envs.juggling._v1_step.OUT_COLUMNS` (reward, its terms, the
        infos, the episode's end)."""
        if not self._linked:
            self.link()
        kernels, entry = self._kernels, self.entry
        plan = (
            self._phase, self._pk, self._end_k, self._t_start, self._duration, self._end,
            self._grid, self._glen, self._last,
        )  # fmt: skip
        measured = (self._values, self._m_flags)
        n = envs.size
        scratch = self._scratch.get(n)
        if scratch is None:  # per step size: the actions clipped, the commands' status
            scratch = self._scratch[n] = (np.empty((n, 3)), np.empty(n, np.int64), np.empty((n, 2)))
        a_out, status, predicted = scratch
        command = (
            plan, measured, self._ctl, self._flags_ctl, self._residual,
            (self._target, self._armed), a_out, status, predicted,
        )  # fmt: skip
        if self._fast:
            options = self._episode(int(envs[0])).options
            if options is not self._options:  # the juggler's options were replaced
                self._use_options(options)
        self._slot = (self._slot + 1) % self._ring.shape[0]
        obs = np.empty((n, self._bounds.shape[1]), dtype=np.float32)
        out = np.empty((n, len(OUT_COLUMNS)))
        finish = (a_out, obs, out)
        if self.blocks(n) <= 1:  # the whole step in one call unless a world needs Python
            args: tuple[Any, ...] = (
                envs, actions, command, self.period_args(), self._finish_args(*finish),
            )  # fmt: skip
            used = entry(kernels.v1_step, *args)(*args)
            if used < 0:
                self._commands(envs, status, predicted, plan, a_out)
                # (the plans' arrays read again: a new plan may have widened the grid)
                args = (envs, self.period_args(), self._finish_args(*finish))
                used = entry(kernels.v1_rest, *args)(*args)
        else:  # the periods in threads
            args = (envs, actions, *command)
            if entry(kernels.v1_command, *args)(*args):
                self._commands(envs, status, predicted, plan, a_out)
            self.world_periods(envs)
            args = (envs, *self._finish_args(*finish))
            used = entry(kernels.v1_finish, *args)(*args)
        if used:
            for i in envs.tolist():
                self._draw(i)
        if n == 1:
            self._datas[int(envs[0])].time = out[0, 6]
        else:
            for i, t in zip(envs.tolist(), out[:, 6].tolist(), strict=True):
                self._datas[i].time = t
        return obs, out

    def _finish_args(self, a_out: Any, obs: Any, out: Any) -> tuple[Any, ...]:
        """:func:`~motion_envs.envs.juggling._v1_step.v1_finish`'s arguments after
        ``envs``, the step's clipped actions ``a_out`` and its outputs ``obs``, ``out``."""
        return (
            (self._worlds[2], self._worlds[3]),
            (self._holder, self._left, self._dropped, self._k, self._caught, self._released),
            (self._true, self._t_flags),
            (self._ring, self._slot, self._noise, self._noise_at, self._noise_std),
            (self._rel_noise, self._rel_at, self._rel_std),
            self._counts,
            self._plan(),
            (self._trees, self._stack),
            self._scalars,
            self._bounds,
            a_out,
            (self._values, self._m_flags),
            obs,
            out,
        )

    def columns(self, out: NDArray[np.float64]) -> Columns:
        """The infos of step rows ``out`` as columns (``phase``: its index in PHASES)."""
        catches, tosses = out[:, 8].astype(np.int64), out[:, 9].astype(np.int64)
        return {
            "reward_catch": out[:, 1],
            "reward_drop": out[:, 2],
            "reward_likeness": out[:, 3],
            "reward_action": out[:, 4],
            "likeness": out[:, 5],
            "caught": out[:, 7] > 0.0,
            "catches": catches,
            "tosses": tosses,
            "cycles": tosses.copy(),
            "phase": out[:, 10].astype(np.int64),
            "held": out[:, 11] > 0.0,
            "time": out[:, 6],
            "hand": out[:, 13:15],
            "ball": out[:, 15:17],
            "action_invalid": out[:, 12] > 0.0,
        }

    def _commands(
        self,
        envs: NDArray[np.int64],
        status: NDArray[np.int64],
        predicted: NDArray[np.float64],
        plan: tuple[Any, ...],
        a_out: NDArray[np.float64],
    ) -> None:
        """The commands ``v1_command`` left: the eq. 10 corrections due (status 2), then
        their commands; the controllers in Python at their events (status 1)."""
        world, kernels, entry = (self._target, self._armed), self._kernels, self.entry
        one = envs.size == 1  # the batch of one: its rows as they are
        for code in (2, 1):
            hit = (status[0] == code) if one else (status == code)
            if not hit.any():
                continue
            rows, a = (envs, a_out) if one else (envs[hit], a_out[hit])
            if code == 2:
                self._correct(rows, predicted if one else predicted[hit])
                args: tuple[Any, ...] = (rows, plan, self._ctl, a, self._residual, world)
                entry(kernels.v1_advance, *args)(*args)
            else:
                target, armed = self._python_commands(rows)
                args = (rows, target, armed, a, self._phase, self._residual, world)
                entry(kernels.v1_aim, *args)(*args)

    def _python_commands(
        self, envs: NDArray[np.int64]
    ) -> tuple[NDArray[np.float64], NDArray[np.bool_]]:
        """The controllers of ``envs`` run in Python on the measured state; their plans
        are copied back into the arrays."""
        target = np.empty((envs.size, 2))
        armed = np.empty(envs.size, dtype=np.bool_)
        for j, i in enumerate(envs.tolist()):
            self.sync(i)
            t, a = self.parts[i].controller.command(self.shown(i))
            target[j], armed[j] = t, a
            self._load_plan(i)
        return target, armed

    def shown(self, i: int) -> JugglingState:
        """What episode ``i``'s controller is shown: the true hand, the measured ball."""
        held, released, caught = self._m_flags[i].tolist()
        return JugglingState(
            time=float(self._values[i, 0]),
            hand_pos=self._true[i, 0:2].copy(),
            hand_vel=self._true[i, 2:4].copy(),
            ball_pos=self._values[i, 1:3].copy(),
            ball_vel=self._values[i, 3:5].copy(),
            held=held,
            released=released,
            caught=caught,
            dropped=bool(self._t_flags[i, 2]),
        )


def v1_info(out: NDArray[np.float64]) -> dict[str, Any]:
    """The single environment's step ``info`` from its row ``out (1, len(OUT_COLUMNS))``
    of :meth:`V1Batch.step` (:meth:`V1Batch.columns`' keys, plain values)."""
    r = out[0].tolist()
    return {
        "reward_catch": r[1],
        "reward_drop": r[2],
        "reward_likeness": r[3],
        "reward_action": r[4],
        "likeness": r[5],
        "caught": r[7] > 0.0,
        "catches": int(r[8]),
        "tosses": int(r[9]),
        "cycles": int(r[9]),
        "phase": PHASES[int(r[10])],
        "held": r[11] > 0.0,
        "time": r[6],
        "hand": out[0, 13:15].copy(),
        "ball": out[0, 15:17].copy(),
        "action_invalid": r[12] > 0.0,
    }
