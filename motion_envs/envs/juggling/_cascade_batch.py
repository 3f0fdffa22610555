"""Cascade-v0's step for a batch of episodes: the ONE home of its commands between the
controllers' events, its sensors, reward, observation and episode end.

:class:`CascadeBatch` steps the episodes of ``parts`` (Cascade-v0 single environments:
each its world, controller, sensors and generators) together: the single environment is
the batch of one (its rows are its world's own arrays), the native vector environment
(:class:`~motion_envs.envs.juggling.CascadeVectorEnv`) the batch of ``N``. A control
period:

* the command (:func:`~motion_envs.envs.juggling._cascade_step.cascade_command`):
  between the hands' events (decided as :class:`~motion_envs.models.juggling.CascadeHand`
  decides them) each hand's command is an index into its plan on the control grid; a
  correction found due is made by the hand's own ``correct`` arithmetic, all of them
  together (:func:`~motion_envs.models.juggling.replan_many`), and its plan copied back;
  at any other event the episode's own controller runs in Python on the measured state
  and both hands' plans are copied back (always, for controllers other than ``juggler``
  and ``juggler_latency_aware`` and for the siteswap juggler); the residual added where
  ``residual_phases`` lets it act;
* the worlds' one control period (:class:`~motion_envs.envs.juggling._batch.WorldBatch`,
  in threads for a large batch; else in the same compiled call as the rest,
  :func:`~motion_envs.envs.juggling._cascade_step.cascade_period`);
* the rest (:func:`~motion_envs.envs.juggling._cascade_step.cascade_finish`): the
  releases' scatter and the sensors' noise (drawn ahead in blocks from the world's and
  the sensors' own generators: the same sequences), the human-likeness, the reward, the
  episode's end, the observation.

A step is ``frame_skip`` such periods, each for the episodes whose episode has not ended
in the step, the rewards, reward terms, likeness and catches summed.

``backend="numba"`` runs the kernels compiled
(:mod:`~motion_envs.envs.juggling._compiled_cascade`), ``"python"`` as plain Python
(bit-identical).
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np
from numpy.typing import NDArray

from motion_envs.datasets.juggling import CASCADE_HANDS, PHASES
from motion_envs.envs.juggling import _cascade_step
from motion_envs.envs.juggling._batch import NOISE_BLOCK as _NOISE_BLOCK
from motion_envs.envs.juggling._batch import WorldBatch
from motion_envs.envs.juggling._cascade_step import OUT_COLUMNS, out_columns
from motion_envs.models.juggling import (
    LIKENESS_TAU,
    CascadeController,
    CascadeHand,
    CascadeState,
    ControlOptions,
    replan_many,
)

__all__ = ["CascadeBatch", "Columns"]

_TOSS, _GO_DOWN, _CATCH = PHASES.index("toss"), PHASES.index("go_down"), PHASES.index("catch")
_FAST_CONTROLLERS = ("juggler", "juggler_latency_aware")
#: Noise rows drawn from a generator at a time.
_COL = {name: c for c, name in enumerate(OUT_COLUMNS)}
#: The columns a step sums over its periods.
_SUMMED = np.array([_COL[k] for k in (
    "reward", "reward_catch", "reward_drop", "reward_likeness", "reward_action", "likeness",
    "caught",
)])  # fmt: skip
#: A step's per-episode values by info key (the stepped episodes along the first axis).
Columns = dict[str, NDArray[Any]]


class CascadeBatch(WorldBatch):
    """Cascade-v0's episodes of ``parts`` stepped together (see the module docstring).

    ``parts``: ``CascadeEnv`` instances with the same arguments; ``backend``: ``"numba"``
    or ``"python"``; ``threads``: threads stepping the worlds (numba)."""

    LINKED = (*WorldBatch.LINKED, "_kernels", "_trees", "_qv", "_args", "_period_args")

    def __init__(self, parts: Sequence[Any], backend: str, threads: int = 1) -> None:
        super().__init__(parts, backend, threads)
        n, first = self.n, self.parts[0]
        task = first.task
        self._dt = task.dt
        self._frame_skip = first.frame_skip
        nb = self._nb = first.balls
        # what the controller was last shown (the measured balls)
        self._m_time = np.zeros(n)
        self._m_ball = np.zeros((n, nb, 2))
        self._m_ball_vel = np.zeros((n, nb, 2))
        # the sensors' delay line (a ring shared by all episodes: a reset fills every
        # slot of its own), the observation's measurement history, the noise drawn ahead
        self._ring = np.zeros((first.delay_steps + 1, n, nb, 5))
        self._slot = np.zeros(1, dtype=np.int64)  # the ring's newest entry
        self._history = np.zeros((n, nb, 4 * first.history))
        self.setup_draws(first)
        # the hands' plans
        c0 = first.controller
        self._fast = first.controller_name in _FAST_CONTROLLERS and c0.compiled_events
        latency = c0.latency
        ahead = first.controller_name == "juggler_latency_aware" and latency > 0
        self._phase = np.zeros((n, 2), dtype=np.int64)
        self._pk = np.zeros((n, 2), dtype=np.int64)
        self._end_k = np.zeros((n, 2), dtype=np.int64)
        self._grid = np.zeros((n, 2, 1, 2))
        self._glen = np.ones((n, 2), dtype=np.int64)
        self._last = np.zeros((n, 2, 2, 2))
        self._t_start = np.zeros((n, 2))
        self._duration = np.zeros((n, 2))
        self._end = np.zeros((n, 2, 2))  # own frame (fast) / world (slow)
        self._incoming = np.full((n, 2), -1, dtype=np.int64)  # first queued ball
        self._catch_ball = np.full((n, 2), -1, dtype=np.int64)
        self._phase_time = np.zeros((n, 2))  # the slow controllers' observation
        self._next = np.zeros((n, 2, 2))
        # the fitted juggler's constants (the siteswap juggler's: unused)
        fitted = isinstance(c0, CascadeController)
        options = c0.options if fitted else ControlOptions()
        reaim = c0.tunables.reaim_after * c0.beat if fitted else 0.0
        self._ctl = np.array(
            [c0.task.dt, c0.task.gravity, reaim, latency, options.correction_tolerance,
             options.release_after, _TOSS, _GO_DOWN, _CATCH]
        )  # fmt: skip
        self._flags = (self._fast, bool(options.correction), ahead)
        self._residual = (float(first.residual_scale), first.residual_acts.copy())
        self._bounds = np.stack([first._low, first._high])
        w = first.reward_weights
        scalars = [task.dt, LIKENESS_TAU, w["catch"], w["drop"], w["likeness"], w["action"]]
        scalars += [first.max_catches, first._time_limit, float(self._noisy)]
        self._scalars = np.array(scalars)
        self._width = out_columns(nb)

    def link(self) -> None:
        """The worlds' links, the kernels, the likeness's k-d trees (again when unpickled)."""
        super().link()
        self.link_steps("motion_envs.envs.juggling._compiled_cascade", _cascade_step)
        self._qv = (self._worlds[2], self._worlds[3])
        self._period_args = self.period_args()
        self._args: tuple[tuple[Any, ...], tuple[Any, ...]] | None = None

    def _kernel_args(self) -> tuple[tuple[Any, ...], tuple[Any, ...]]:
        """The arguments of ``cascade_command`` and ``cascade_finish`` that are this
        batch's arrays (made again when a wider grid replaces ``_grid``)."""
        if self._args is None:
            plan = self._plan()
            command = (
                plan,
                (self._holder, self._caught, self._released, self._qv[0], self._qv[1]),
                (self._m_time, self._m_ball, self._m_ball_vel), self._ctl, self._flags,
                self._residual, (self._target, self._armed),
            )  # fmt: skip
            finish = (
                self._qv,
                (self._holder, self._dropped, self._k, self._caught, self._released),
                (self._ring, self._slot, self._noise, self._noise_at, self._noise_std),
                (self._rel_noise, self._rel_at, self._rel_std),
                self._counts,
                plan,
                (self._trees, self._stack),
                self._scalars,
                self._bounds,
            )
            self._args = (command, finish)
        return self._args

    # -- a reset ---------------------------------------------------------------------------
    def load(self, i: int, measured: CascadeState) -> None:
        """Copy episode ``i``'s state after its reset (world, the ``measured`` state,
        sensors, controller) into the arrays; draw its noise ahead."""
        if not self._linked:
            self.link()
        env = self.parts[i]
        self.load_world(i)
        self._caught[i], self._released[i] = measured.caught, measured.released
        self._m_time[i] = measured.time
        self._m_ball[i] = measured.ball_pos
        self._m_ball_vel[i] = measured.ball_vel
        size = self._ring.shape[0]
        for b, sensor in enumerate(env.sensor.sensors):
            for j, entry in enumerate(sensor._buffer):
                self._ring[(int(self._slot[0]) + 1 + j) % size, i, b] = entry
        rows = np.concatenate([measured.ball_pos, measured.ball_vel], axis=1)
        self._history[i] = np.tile(rows, env.history)
        self._counts[i] = 0
        self._noise_at[i] = self._rel_at[i] = _NOISE_BLOCK
        self._draw(i)
        for h in range(CASCADE_HANDS):
            self._load_hand(i, h)

    def _draw(self, i: int) -> None:
        """Draw episode ``i``'s noise ahead where fewer rows are left than a period may
        take (one per ball, one per hand): the rows left moved to the front, the rest
        drawn from the sensors' generator (the sequence of as many ``standard_normal(4)``
        calls), from the world's for the releases (of ``standard_normal(2)`` calls)."""
        at = int(self._noise_at[i])
        if self._noisy and at > _NOISE_BLOCK - self._nb:
            rng = self.parts[i].sensor.sensors[0]._rng
            self._noise[i, : _NOISE_BLOCK - at] = self._noise[i, at:]
            self._noise[i, _NOISE_BLOCK - at :] = rng.standard_normal((at, 4))
            self._noise_at[i] = 0
        at = int(self._rel_at[i])
        if self._scatter and at > _NOISE_BLOCK - CASCADE_HANDS:
            rng = self.parts[i].world._rng
            self._rel_noise[i, : _NOISE_BLOCK - at] = self._rel_noise[i, at:]
            self._rel_noise[i, _NOISE_BLOCK - at :] = rng.standard_normal((at, 2))
            self._rel_at[i] = 0

    def _load_hand(self, i: int, h: int) -> None:
        """Copy hand ``h`` of episode ``i``'s controller into the arrays."""
        c = self.parts[i].controller
        self._phase[i, h] = PHASES.index(c.phase(h))
        if not self._fast:
            self._phase_time[i, h] = c.phase_time(h)
            self._duration[i, h] = c.duration(h)
            self._next[i, h] = c.nominal_next(h)
            self._end[i, h] = c.plan_end(h)
            return
        hand: CascadeHand = c.hands[h]
        self._pk[i, h] = hand.k
        self._end_k[i, h] = hand.end_k
        self._load_grid(i, h, hand)
        self._last[i, h, 0], self._last[i, h, 1] = hand._last[0], hand._last[1]
        self._t_start[i, h] = hand.t_start
        self._duration[i, h] = hand.duration
        self._end[i, h] = hand.end
        self._incoming[i, h] = hand.incoming[0][0] if hand.incoming else -1
        self._catch_ball[i, h] = hand._catch_ball

    def _load_grid(self, i: int, h: int, hand: CascadeHand) -> None:
        grid = hand.grid
        if grid.shape[0] > self._grid.shape[2]:
            wider = np.zeros((self.n, 2, grid.shape[0], 2))
            wider[:, :, : self._grid.shape[2]] = self._grid
            self._grid = wider
            self._args = None
        self._grid[i, h, : grid.shape[0]] = grid
        self._glen[i, h] = grid.shape[0]

    def _plan(self) -> tuple[Any, ...]:
        """The plans as the kernels read them."""
        return (
            self._phase, self._pk, self._end_k, self._t_start, self._duration, self._end,
            self._incoming, self._catch_ball, self._grid, self._glen, self._last,
            self._fast, self._phase_time, self._next, self._end,
        )  # fmt: skip

    def observation(self, i: int) -> NDArray[np.float32]:
        """Episode ``i``'s observation now (at its reset)."""
        if not self._linked:
            self.link()
        obs = np.empty(self._bounds.shape[1], dtype=np.float32)
        true = (self._qv[0][i], self._qv[1][i], self._holder, self._history)
        self._kernels.cascade_observe(i, obs, true, self._plan(), self._bounds, self._dt)
        return obs

    def true_state(self, i: int, measured: bool = False) -> CascadeState:
        """Episode ``i``'s true state after its last period (``measured``: with the balls
        as the controller sees them, at the time they were measured)."""
        d, nb = self._datas[i], self._nb
        q, v = d.qpos, d.qvel
        return CascadeState(
            time=float(self._m_time[i] if measured else d.time),
            hand_pos=q[0:4].reshape(2, 2).copy(),
            hand_vel=v[0:4].reshape(2, 2).copy(),
            ball_pos=(self._m_ball[i] if measured else q[4 : 4 + 2 * nb].reshape(-1, 2)).copy(),
            ball_vel=(self._m_ball_vel[i] if measured else v[4 : 4 + 2 * nb].reshape(-1, 2)).copy(),
            holder=tuple(self._holder[i].tolist()),
            released=(int(self._released[i, 0]), int(self._released[i, 1])),
            caught=(int(self._caught[i, 0]), int(self._caught[i, 1])),
            dropped=tuple(self._dropped[i].tolist()),
        )

    # -- the step -------------------------------------------------------------------------
    def step(self, envs: NDArray[np.int64], actions: NDArray[np.float64]) -> tuple[
        NDArray[np.float32], NDArray[np.float64]
    ]:  # fmt: skip
        """Step episodes ``envs`` with ``actions (m, 4)`` (float64, as given: clipped
        here, NaN counts as 0) over ``frame_skip`` periods, each episode's until its
        episode ends; returns their observations and their rows (:data:`OUT_COLUMNS`,
        the summed terms summed over the periods played)."""
        obs, out = self.period(envs, actions)
        if self._frame_skip == 1:
            return obs, out
        live = np.flatnonzero(out[:, _COL["terminated"]] + out[:, _COL["truncated"]] == 0.0)
        summed = _SUMMED
        for _ in range(self._frame_skip - 1):
            if live.size == 0:
                break
            o, rows = self.period(envs[live], actions[live])
            sums = out[live][:, summed] + rows[:, summed]
            out[live] = rows
            out[np.ix_(live, summed)] = sums
            obs[live] = o
            live = live[rows[:, _COL["terminated"]] + rows[:, _COL["truncated"]] == 0.0]
        return obs, out

    def period(self, envs: NDArray[np.int64], actions: NDArray[np.float64]) -> tuple[
        NDArray[np.float32], NDArray[np.float64]
    ]:  # fmt: skip
        """One control period of ``envs`` with ``actions (m, 4)``: their observations
        and rows (:data:`OUT_COLUMNS`, then the hands' and balls' ``x, z``)."""
        if not self._linked:
            self.link()
        kernels, entry = self._kernels, self.entry
        command, finish = self._kernel_args()
        m = envs.size
        a_out = np.empty((m, 6))
        args: tuple[Any, ...] = (envs, actions, *command, a_out)
        status, due, predicted = entry(kernels.cascade_command, *args)(*args)
        if (status[0] != 0) if m == 1 else status.any():
            self._commands(envs, status, due, predicted, a_out)
            command, finish = self._kernel_args()  # a wider grid may have replaced _grid
        # the action's squared norm as CascadeEnv computed it (numpy's matmul over a stack
        # calls the BLAS dot per row as for one row; its order is not the naive sum's)
        if m == 1:
            a = a_out[0, :4].copy()
            a_out[0, 5] = a @ a
        else:
            a = a_out[:, :4].copy()  # contiguous, as the rows of a (m, 4) array
            a_out[:, 5] = np.matmul(a[:, None, :], a[:, :, None])[:, 0, 0]
        obs = np.empty((m, self._bounds.shape[1]), dtype=np.float32)
        out = np.empty((m, self._width))
        measured = (self._m_time, self._m_ball, self._m_ball_vel, self._history)
        rest = (*finish, a_out, measured, obs, out)
        if self.blocks(m) > 1:  # the periods in threads
            self.world_periods(envs)
            used_up = entry(kernels.cascade_finish, envs, *rest)(envs, *rest)
        else:  # the periods and the rest in one call
            args = (envs, self._period_args, rest)
            used_up = entry(kernels.cascade_period, *args)(*args)
        if used_up:
            for i in envs.tolist():
                self._draw(i)
        time = _COL["time"]
        if m == 1:
            self._datas[int(envs[0])].time = out[0, time]
        else:
            for i, t in zip(envs.tolist(), out[:, time].tolist(), strict=True):
                self._datas[i].time = t
        return obs, out

    def columns(self, out: NDArray[np.float64]) -> Columns:
        """The infos of step rows ``out`` as columns (``phase``, ``phases``: indices in
        PHASES), typed as a single environment's info values stack."""
        col, m = _COL, out.shape[0]
        tosses = out[:, col["tosses"]].astype(np.int64)
        phases = out[:, col["phase_0"] : col["phase_1"] + 1].astype(np.int64)
        hands = out[:, len(OUT_COLUMNS) : len(OUT_COLUMNS) + 4]
        return {
            "phase": phases[:, 0].copy(),
            "phases": phases,
            "held": out[:, col["held_0"] : col["held_1"] + 1] > 0.0,
            "time": out[:, col["time"]],
            "hand": hands[:, 0:2].copy(),
            "hands": hands.reshape(m, 2, 2).copy(),
            "balls": out[:, len(OUT_COLUMNS) + 4 :].reshape(m, self._nb, 2).copy(),
            "reward_catch": out[:, col["reward_catch"]],
            "reward_drop": out[:, col["reward_drop"]],
            "reward_likeness": out[:, col["reward_likeness"]],
            "reward_action": out[:, col["reward_action"]],
            "likeness": out[:, col["likeness"]],
            "caught": out[:, col["caught"]].astype(np.int64),
            "catches": out[:, col["catches"]].astype(np.int64),
            "tosses": tosses,
            "cycles": tosses.copy(),
            "action_invalid": out[:, col["action_invalid"]] > 0.0,
        }

    def info(self, row: NDArray[np.float64]) -> dict[str, Any]:
        """One step row ``out[j]`` as a single environment's ``info``."""
        r, col, width = row.tolist(), _COL, len(OUT_COLUMNS)
        phases = (PHASES[int(r[col["phase_0"]])], PHASES[int(r[col["phase_1"]])])
        tosses = int(r[col["tosses"]])
        return {
            "phase": phases[0],
            "phases": phases,
            "held": (r[col["held_0"]] > 0.0, r[col["held_1"]] > 0.0),
            "time": r[col["time"]],
            "hand": row[width : width + 2].copy(),
            "hands": row[width : width + 4].reshape(2, 2).copy(),
            "balls": row[width + 4 :].reshape(-1, 2).copy(),
            "reward_catch": r[col["reward_catch"]],
            "reward_drop": r[col["reward_drop"]],
            "reward_likeness": r[col["reward_likeness"]],
            "reward_action": r[col["reward_action"]],
            "likeness": r[col["likeness"]],
            "caught": int(r[col["caught"]]),
            "catches": int(r[col["catches"]]),
            "tosses": tosses,
            "cycles": tosses,
            "action_invalid": r[col["action_invalid"]] > 0.0,
        }

    # -- the controllers ----------------------------------------------------------------
    def _commands(
        self,
        envs: NDArray[np.int64],
        status: NDArray[np.int64],
        due: NDArray[np.bool_],
        predicted: NDArray[np.float64],
        a_out: NDArray[np.float64],
    ) -> None:
        """The commands ``cascade_command`` left: the eq. 10 corrections due (status 2),
        then their commands; the controllers in Python at their events (status 1)."""
        command, kernels, entry = (self._target, self._armed), self._kernels, self.entry
        one = envs.size == 1  # the batch of one: its rows as they are
        for code in (2, 1):
            hit = (status[0] == code) if one else (status == code)
            if not hit.any():
                continue
            rows, a = (envs, a_out) if one else (envs[hit], a_out[hit])
            if code == 2:
                if one:
                    self._correct_one(int(envs[0]), due[0].tolist(), predicted[0])
                else:
                    self._correct(rows, due[hit], predicted[hit])
                plan = self._plan()
                args: tuple[Any, ...] = (rows, plan, self._ctl, a, self._residual, command)
                entry(kernels.cascade_advance, *args)(*args)
            else:
                targets, armed = self._python_commands(rows)
                args = (rows, targets, armed, a, self._phase, self._residual, command)
                entry(kernels.cascade_aim, *args)(*args)

    def _correct(
        self, envs: NDArray[np.int64], due: NDArray[np.bool_], predicted: NDArray[np.float64]
    ) -> None:
        """The eq. 10 corrections found due: each hand re-plans toward its view's ball's
        predicted intercept ``predicted (m, 2, 2)`` (:meth:`JugglingController.correct`'s
        flight, own frame), all of them together
        (:func:`~motion_envs.models.juggling.replan_many`: each hand's
        :meth:`JugglingController.replan` numbers); the new plans are copied back."""
        rows, hands_at = np.nonzero(due)
        at = envs[rows].tolist()
        hands: list[CascadeHand] = []
        for i, hh in zip(at, hands_at.tolist(), strict=True):
            hand = self.parts[i].controller.hands[hh]
            hand.k = int(self._pk[i, hh])
            hands.append(hand)
        replan_many(hands, self._m_time[at].tolist(), predicted[rows, hands_at])
        for i, hh, hand in zip(at, hands_at.tolist(), hands, strict=True):
            self._load_grid(i, hh, hand)
            self._end[i, hh] = hand.end

    def _correct_one(self, i: int, due: list[bool], predicted: NDArray[np.float64]) -> None:
        """:meth:`_correct` of episode ``i``'s hands ``due`` (hand 0 first), each by its
        own :meth:`JugglingController.replan` (no stacking)."""
        time = float(self._m_time[i])
        for h in (0, 1):
            if due[h]:
                hand = self.parts[i].controller.hands[h]
                hand.k = int(self._pk[i, h])
                hand.replan(time, predicted[h].copy())
                self._load_grid(i, h, hand)
                self._end[i, h] = hand.end

    def sync(self, i: int) -> None:
        """Give episode ``i``'s controller its hands' step counts and last commands (the
        batch steps them in its arrays between events)."""
        if not self._fast:
            return
        for h, hand in enumerate(self.parts[i].controller.hands):
            hand.k = int(self._pk[i, h])
            hand._last = [self._last[i, h, 0].copy(), self._last[i, h, 1].copy()]

    def _python_commands(
        self, envs: NDArray[np.int64]
    ) -> tuple[NDArray[np.float64], NDArray[np.bool_]]:
        """The controllers of ``envs`` run in Python on the measured state; their plans
        are copied back into the arrays."""
        targets = np.empty((envs.size, 2, 2))
        armed = np.empty((envs.size, 2), dtype=np.bool_)
        for j, i in enumerate(envs.tolist()):
            self.sync(i)
            state = self.true_state(i, measured=True)
            t, a = self.parts[i].controller.command(state)
            targets[j], armed[j] = t, a
            for h in range(CASCADE_HANDS):
                self._load_hand(i, h)
        return targets, armed
