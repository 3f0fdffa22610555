"""Juggling-v1's native vector environment: the ``N`` episodes' control periods batched.

:class:`JugglingV1VectorEnv` is ``gym.make_vec("MotionEnvs/Juggling-v1", N)``. Each
sub-environment is bit-identical to ``JugglingV1Env`` seeded with ``seed + i`` (as under
``SyncVectorEnv``; tested for the three autoreset modes). With numba (the ``fast``
extra, ``backend="numba"``, the default when installed) a step runs:

* the controller's plan in arrays: between the plan's events (a release, a catch, a
  reached end point, all decided as the controller decides them:
  :func:`~motion_envs.envs.juggling._compiled_v1.v1_events`) a command is an index into the
  plan on the control grid (:func:`~motion_envs.envs.juggling._compiled_v1.v1_advance`); at
  an event the sub-environment's own controller runs in Python and its new plan is
  copied back (controllers other than ``juggler`` and ``juggler_latency_aware`` always
  run in Python); with ``residual_phases`` the residual acts where the phase after the
  command is one of them (as in ``JugglingV1Env._advance``);
* the eq. 10 corrections (found due by ``v1_events`` with the controller's test) made in
  the arrays with the controller's numbers: the catch's rows and pseudo-inverses are
  shared by the catches of its duration
  (:func:`~motion_envs.models.juggling.eq10_rows`), the products stacked
  (:func:`~motion_envs.models.juggling.eq10_many`); the controller gets them at its
  next event or reset, as it gets its step count there;
* the world's one control period, compiled (``_compiled.world_periods``, MuJoCo's
  ``mj_step`` called from the loop, in ``threads`` threads over blocks of worlds); the
  release's noise in Python, from the world's generator; the hand's human-likeness by the
  compiled k-d tree search (``_compiled.nearest_rows``);
* the rest of the step compiled too (``_compiled_v1.v1_finish``): the sensor's delay
  line (its noise drawn ahead in blocks from the sensor's own generator), the reward and
  the observation.

``backend="python"`` runs each single environment's ``step`` (no numba needed).
"""

from __future__ import annotations

from typing import Any

import numpy as np
from numpy.typing import NDArray

from motion_envs.datasets.juggling import PHASES
from motion_envs.envs.juggling._v1_env import HISTORY, JugglingV1Env
from motion_envs.envs.juggling._vector import WORLD_LINKS, Columns, JugglingVectorEnv
from motion_envs.models.juggling import (
    LIKENESS_TAU,
    ControlOptions,
    JugglingController,
    eq10_many,
    eq10_rows,
    perturb_release,
)

__all__ = ["JugglingV1VectorEnv"]

_TOSS, _CATCH = PHASES.index("toss"), PHASES.index("catch")
_FAST_CONTROLLERS = ("juggler", "juggler_latency_aware")
#: Attributes made from the worlds by ``_link`` (not pickled: made again).
_LINKED = (*WORLD_LINKS, "_kernels", "_trees", "_m_time", "_m_ball", "_m_ball_vel")
#: Measurement-noise rows drawn from a sensor's generator at a time.
_NOISE_BLOCK = 64


class JugglingV1VectorEnv(JugglingVectorEnv):
    """``num_envs`` Juggling-v1 episodes stepped together (see the module docstring and
    :mod:`motion_envs.envs.juggling._vector`).

    Parameters
    ----------
    num_envs : int
        Number of sub-environments.
    autoreset_mode : AutoresetMode or str
        ``NEXT_STEP`` (default), ``SAME_STEP`` or ``DISABLED``.
    backend : str
        ``"auto"`` (numba when installed), ``"numba"`` or ``"python"``.
    threads : int or None
        Threads stepping the worlds' control periods (numba backend); ``None``: the
        CPUs available. The episodes do not depend on it.
    **kwargs
        :class:`~motion_envs.envs.juggling.JugglingV1Env`'s keyword arguments.
    """

    single_class = JugglingV1Env
    _LINKED = _LINKED
    _batched = True

    # -- state ----------------------------------------------------------------------------
    def _link(self) -> None:
        """The worlds' links, the likeness's compiled k-d trees and the views of the
        measured state (made again after unpickling, which copies the worlds)."""
        from motion_envs.envs.juggling import _compiled_v1

        self._link_worlds()
        self._kernels = _compiled_v1
        likeness = self.envs[0].likeness
        compiled = self._compiled
        self._trees = tuple(compiled.likeness_tree(likeness.trees[p].data) for p in PHASES)
        self._m_time = self._measured[:, 0]
        self._m_ball = self._measured[:, 1:3]
        self._m_ball_vel = self._measured[:, 3:5]

    def _setup_arrays(self) -> None:
        n, first = self.num_envs, self.envs[0]
        task = first.task
        self._dt, self._gravity = task.dt, task.gravity
        # the world (HandsWorld's state, batched)
        self._setup_world_arrays()
        self._flags = np.zeros((n, 3), dtype=np.bool_)  # held, left, dropped
        self._hand = np.zeros((n, 2))
        self._hand_vel = np.zeros((n, 2))
        self._ball = np.zeros((n, 2))
        self._ball_vel = np.zeros((n, 2))
        self._events = np.zeros((n, 2), dtype=np.bool_)  # caught, released
        # what the controller was last shown (the measured state)
        self._measured = np.zeros((n, 5))  # time, ball x, z, vx, vz
        self._m_flags = np.zeros((n, 3), dtype=np.bool_)  # held, released, caught
        # the sensor's delay line (a ring shared by all sub-environments: a reset fills
        # every slot of its own) and the observation's measurement history
        d = first.delay_steps
        self._ring = np.zeros((d + 1, n, 5))
        self._slot = 0
        self._history = np.zeros((n, HISTORY, 4))
        self._noisy = first.position_std > 0 or first.velocity_std > 0
        self._noise_std = np.array([first.position_std] * 2 + [first.velocity_std] * 2)
        self._noise = np.zeros((n, _NOISE_BLOCK, 4))
        self._noise_at = np.full(n, _NOISE_BLOCK, dtype=np.int64)  # next unused row
        self._counts = np.zeros((n, 2), dtype=np.int64)  # catches, tosses
        # the controller's plan
        self._fast = first.controller_name in _FAST_CONTROLLERS
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
        # corrections made here reach the controller at its next event (_sync)
        self._stale = np.zeros(n, dtype=np.bool_)
        self._pending: list[list[tuple[float, float]]] = [[] for _ in range(n)]
        self._coef = np.zeros((n, 1, 2))
        self._c_basis = np.zeros((n, 1, 1))
        self._c_derivative = np.zeros((n, 1, 1))
        self._c_a = np.zeros((n, 1, 3, 1))
        self._c_pinv = np.zeros((n, 1, 1, 3))
        weights = first.reward_weights
        self._w = (weights["catch"], weights["drop"], weights["likeness"], weights["action"])
        self._bounds = np.stack([first._low, first._high])
        if self._fast:
            self._use_options(first.controller.juggler.options)
        self._obs_dim = first._low.shape[0]
        self._link()
        scalars = (task.dt, LIKENESS_TAU, *self._w, first.max_catches, first._time_limit)
        self._scalars = np.array([*scalars, float(self._noisy)])

    def _use_options(self, options: ControlOptions) -> None:
        """The juggler's options as the compiled events and advance read them."""
        self._options = options
        task = self.envs[0].task
        self._flags_ctl = (options.correction, self._ahead)
        self._event_constants = np.array(
            [task.dt, task.gravity, self._latency, options.correction_tolerance, _TOSS, _CATCH]
        )
        self._advance = np.array([task.dt, options.release_after, _TOSS], dtype=np.float64)

    def _episode(self, i: int) -> JugglingController:
        episode = self.envs[i].controller.juggler.episode
        assert episode is not None
        return episode  # type: ignore[no-any-return]

    def _after_reset(self, i: int) -> None:
        if self.backend != "numba":
            return
        env = self.envs[i]
        self._load_world(i)
        self._flags[i] = (self._holder[i, 0] >= 0, self._left[i, 0], self._dropped[i, 0])
        state = env._state
        self._hand[i] = state.hand_pos
        self._hand_vel[i] = state.hand_vel
        self._m_time[i] = state.time
        self._m_ball[i] = state.ball_pos
        self._m_ball_vel[i] = state.ball_vel
        self._m_flags[i] = (state.held, state.released, state.caught)
        self._ring[:, i] = env.sensor._buffer[0]
        self._noise_at[i] = _NOISE_BLOCK  # the reset's new generator: draw afresh
        self._history[i] = list(env._history)
        self._counts[i] = 0
        self._load_plan(i)

    def _load_plan(self, i: int) -> None:
        """Copy sub-environment ``i``'s controller state into the arrays."""
        c = self.envs[i].controller
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
            wider = np.zeros((self.num_envs, grid.shape[0], 2))
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

    def _load_rows(self, i: int, ep: JugglingController) -> None:
        """Copy the eq. 10 rows of ``ep``'s catch plan (shared by the plans of its
        duration: :func:`~motion_envs.models.juggling.eq10_rows`), its basis on the grid
        and its coefficients into row ``i`` of the arrays the corrections gather from."""
        rows = eq10_rows(ep._tau, ep._basis, ep.duration, self._dt)
        m, nb = ep._basis.shape
        if m > self._c_basis.shape[1] or nb != self._c_basis.shape[2]:
            n, width = self.num_envs, max(m, self._c_basis.shape[1])
            if nb != self._c_basis.shape[2]:  # the first catch (one model: one basis size)
                width = m
            self._c_basis = _wider(self._c_basis, (n, width, nb))
            self._c_derivative = _wider(self._c_derivative, (n, width, nb))
            self._c_a = _wider(self._c_a, (n, width, 3, nb))
            self._c_pinv = _wider(self._c_pinv, (n, width, nb, 3))
            self._coef = _wider(self._coef, (n, nb, 2))
        self._c_basis[i, :m] = ep._basis
        self._c_derivative[i, :m] = rows.derivative
        self._c_a[i, :m] = rows.a
        self._c_pinv[i, :m] = rows.pinv
        self._coef[i] = ep.coefficients

    # -- the step -------------------------------------------------------------------------
    def _step_batch(self, envs: NDArray[np.int64], actions: NDArray[np.float64]) -> tuple[
        NDArray[np.float32], NDArray[np.float64], NDArray[np.bool_], NDArray[np.bool_], Columns
    ]:  # fmt: skip
        if self.backend != "numba":
            return super()._step_batch(envs, actions)
        # the action (clipped_pair)
        invalid = np.logical_not(np.isfinite(actions).all(axis=1))
        a = np.clip(np.where(np.isnan(actions), 0.0, actions), -1.0, 1.0)
        target, armed = self._commands(envs)
        first = self.envs[0]
        residual = a  # the reward's action penalty is the whole action's (as step's)
        if first.residual_phases is not None:  # as JugglingV1Env._advance: a selection
            acts = first.residual_acts[self._phase[envs]]
            residual = np.where(acts[:, None], a, 0.0)
        target = target + first.residual_scale * residual
        self._world_periods(envs, target[:, None, :], armed[:, None])
        q, v = self._qv(envs)
        self._hand[envs], self._hand_vel[envs] = q[:, 0:2], v[:, 0:2]
        self._ball[envs], self._ball_vel[envs] = q[:, 2:4], v[:, 2:4]
        self._flags[envs] = np.stack(
            (self._holder[envs, 0] >= 0, self._left[envs, 0], self._dropped[envs, 0]), axis=1
        )
        released = self._released[envs, 0] >= 0
        self._events[envs] = np.stack((self._caught[envs, 0] >= 0, released), axis=1)
        if released.any():
            self._release(envs[released])
        points = np.concatenate((self._hand[envs], LIKENESS_TAU * self._hand_vel[envs]), axis=1)
        likeness = self._compiled.nearest_rows(points, self._phase[envs], self._trees)
        if self._noisy:  # every world keeps a row of noise drawn ahead
            for i in envs[self._noise_at[envs] == _NOISE_BLOCK].tolist():
                # the sensor's own generator read ahead: a block of rows is the sequence
                # of as many standard_normal(4) calls
                self._noise[i] = self.envs[i].sensor._rng.standard_normal((_NOISE_BLOCK, 4))
                self._noise_at[i] = 0
        self._slot = (self._slot + 1) % self._ring.shape[0]
        n = envs.size
        obs = np.empty((n, self._obs_dim), dtype=np.float32)
        out = np.empty((n, 7))
        ends = np.empty((n, 2), dtype=np.bool_)
        self._kernels.v1_finish(
            envs,
            self._hand,
            self._hand_vel,
            self._ball,
            self._ball_vel,
            self._flags,
            self._events,
            self._k,
            self._scalars,
            self._ring,
            self._slot,
            self._noise,
            self._noise_at,
            self._noise_std,
            self._counts,
            self._history,
            self._phase,
            self._pk,
            self._duration,
            self._end,
            self._grid,
            self._glen,
            self._next,
            self._fast,
            likeness,
            self._bounds,
            a,
            self._measured,
            self._m_flags,
            obs,
            out,
            ends,
        )
        time = out[:, 6]
        for i, t in zip(envs.tolist(), time.tolist(), strict=True):
            self._datas[i].time = t
        counts = self._counts[envs]
        columns: Columns = {
            "reward_catch": out[:, 1],
            "reward_drop": out[:, 2],
            "reward_likeness": out[:, 3],
            "reward_action": out[:, 4],
            "likeness": out[:, 5],
            "caught": self._events[envs, 0],
            "catches": counts[:, 0],
            "tosses": counts[:, 1],
            "cycles": counts[:, 1].copy(),
            "phase": self._phase[envs],  # codes: _vector.numeric_info
            "held": self._flags[envs, 0],
            "time": time,
            "hand": self._hand[envs],
            "ball": self._ball[envs],
            "action_invalid": invalid,
        }
        return obs, out[:, 0], ends[:, 0], ends[:, 1], columns

    def _commands(self, envs: NDArray[np.int64]) -> tuple[NDArray[np.float64], NDArray[np.bool_]]:
        """The controllers' hand targets and release arming for ``envs``: array indexing
        between events, the controller itself at them (see the module docstring)."""
        if not self._fast:
            return self._python_commands(envs)
        options = self._episode(int(envs[0])).options
        if options is not self._options:  # the juggler's options were replaced
            self._use_options(options)
        python, due, predicted = self._kernels.v1_events(
            envs,
            (self._phase, self._pk, self._end_k, self._t_start, self._duration, self._end),
            self._measured,
            self._m_flags,
            self._event_constants,
            self._flags_ctl,
        )
        if due.any():
            self._correct(envs[due], predicted[due])
        if not python.any():
            return self._kernels.v1_advance(  # type: ignore[no-any-return]
                envs, self._pk, self._grid, self._glen, self._last, self._phase, self._advance
            )
        target = np.empty((envs.size, 2))
        armed = np.empty(envs.size, dtype=np.bool_)
        fast = ~python
        if fast.any():
            target[fast], armed[fast] = self._kernels.v1_advance(
                envs[fast], self._pk, self._grid, self._glen, self._last, self._phase, self._advance
            )
        target[python], armed[python] = self._python_commands(envs[python])
        return target, armed

    def _correct(self, rows: NDArray[np.int64], target: NDArray[np.float64]) -> None:
        """The eq. 10 corrections of the catches ``rows`` toward the predicted intercepts
        ``target (r, 2)`` (where :meth:`JugglingController.correct` would re-plan:
        :func:`~motion_envs.envs.juggling._compiled_v1.v1_events`): on the catch's rows
        (:meth:`JugglingController.replan`'s numbers: the same stacked products,
        :func:`~motion_envs.models.juggling.eq10_many`, and the same product of the basis
        and the new coefficients for the rest of the grid), or, where the controller has
        no rows for the step, by the sub-environment's own controller. A controller gets
        the corrections made here at its next event or reset (:meth:`_sync`), as it gets
        its step count there."""
        dt = self._dt
        k = self._pk[rows]
        duration = self._duration[rows]
        tau1 = k * dt / duration
        glen = self._glen[rows]
        on_rows = (tau1 < 1.0) & (k < glen)  # JugglingController._rows is not None
        times = self._m_time[rows].tolist()
        if not on_rows.all():
            for j in np.flatnonzero(~on_rows).tolist():
                i, kj = int(rows[j]), int(k[j])
                self._sync(i)
                ep = self._episode(i)
                ep.k = kj
                ep.replan(times[j], target[j].copy())
                self._grid[i, kj + 1 : self._glen[i]] = ep.grid[kj + 1 :]
                self._end[i] = ep.end
                self._coef[i] = ep.coefficients
            rows, k, duration, tau1, glen, target = (
                x[on_rows] for x in (rows, k, duration, tau1, glen, target)
            )
            times = [t for t, on in zip(times, on_rows.tolist(), strict=True) if on]
            if not rows.size:
                return
        n, nb = rows.size, self._coef.shape[1]
        derivative = np.empty((n, 1, nb))
        derivative[:, 0] = self._c_derivative[rows, k]
        out = eq10_many(
            derivative,
            self._c_a[rows, k],
            self._c_pinv[rows, k],
            self._coef[rows],
            duration,
            self._grid[rows, k],
            target,
        )
        self._coef[rows] = out
        self._end[rows] = target
        self._stale[rows] = True
        basis, grid, pending = self._c_basis, self._grid, self._pending
        for j, (i, kj, gj, t, tj) in enumerate(
            zip(rows.tolist(), k.tolist(), glen.tolist(), times, tau1.tolist(), strict=True)
        ):
            grid[i, kj + 1 : gj] = basis[i, kj + 1 : gj] @ out[j]  # as _grid_from does
            pending[i].append((t, tj))

    def _sync(self, i: int) -> None:
        """Give sub-environment ``i``'s controller the corrections made here since its
        last event (its coefficients, end, grid and their record)."""
        if not self._stale[i]:
            return
        self._stale[i] = False
        ep = self._episode(i)
        ep.coefficients = self._coef[i].copy()
        ep.end = self._end[i].copy()
        ep.grid[:] = self._grid[i, : self._glen[i]]
        ep.corrections.extend(self._pending[i])
        self._pending[i].clear()

    def _reset_env(self, i: int, seed: int | None, options: dict[str, Any] | None = None) -> Any:
        if self.backend == "numba":
            self._sync(i)  # the ending episode's controller complete
        return super()._reset_env(i, seed, options)

    def _python_commands(
        self, envs: NDArray[np.int64]
    ) -> tuple[NDArray[np.float64], NDArray[np.bool_]]:
        """The controllers of ``envs`` run in Python on the measured state; their plans
        are copied back into the arrays."""
        from motion_envs.datasets.juggling import JugglingState

        target = np.empty((envs.size, 2))
        armed = np.empty(envs.size, dtype=np.bool_)
        for j, i in enumerate(envs.tolist()):
            if self._fast:
                self._sync(i)
                ep = self._episode(i)
                ep.k = int(self._pk[i])
                ep._last = [self._last[i, 0].copy(), self._last[i, 1].copy()]
            held, released, caught = self._m_flags[i].tolist()
            state = JugglingState(
                time=float(self._m_time[i]),
                hand_pos=self._hand[i].copy(),
                hand_vel=self._hand_vel[i].copy(),
                ball_pos=self._m_ball[i].copy(),
                ball_vel=self._m_ball_vel[i].copy(),
                held=held,
                released=released,
                caught=caught,
                dropped=bool(self._flags[i, 2]),
            )
            t, a = self.envs[i].controller.command(state)
            target[j], armed[j] = t, a
            self._load_plan(i)
        return target, armed

    def _release(self, envs: NDArray[np.int64]) -> None:
        """The release of ``envs`` (their world's rule fired): the ball leaves the hand with
        the hand's velocity, scattered by the world's generator."""
        for i in envs.tolist():
            w = self.envs[i].world
            v = perturb_release(
                self._hand_vel[i].copy(), w.release_speed_std, w.release_angle_std, w._rng
            )
            ux, uz = float(v[0]), float(v[1])
            qvel = self._datas[i].qvel
            qvel[2], qvel[3] = ux, uz
            self._ball_vel[i] = ux, uz


def _wider(array: NDArray[np.float64], shape: tuple[int, ...]) -> NDArray[np.float64]:
    """``array`` in a zero array of ``shape``, its old content kept where it fits (the
    basis size axis only grows from the placeholder's 1)."""
    out = np.zeros(shape)
    if array.shape[2:] == shape[2:]:
        out[:, : array.shape[1]] = array
    return out
