"""Cascade-v0's native vector environment: the ``N`` cascades' control periods batched.

:class:`CascadeVectorEnv` is ``gym.make_vec("MotionEnvs/Cascade-v0", N)``. Each
sub-environment is bit-identical to ``CascadeEnv`` seeded with ``seed + i`` (as under
``SyncVectorEnv``; tested for the three autoreset modes). With numba (the ``fast``
extra, ``backend="numba"``, the default when installed) a step runs:

* the controllers compiled between their events: the tests of
  :class:`~motion_envs.models.juggling.CascadeHand`'s ``command`` (a release, a catch,
  a ball held early, a reached end point, a re-aimed catch) and of the eq. 10
  correction (on the hand's view of its oldest queued ball, predicted forward by the
  latency-aware controller) with the controller's arithmetic
  (:func:`~motion_envs.envs.juggling._compiled.cascade_events`), and each hand's command
  an index into its plan on the control grid
  (:func:`~motion_envs.envs.juggling._compiled.cascade_advance`). A correction found due
  is made by the hand's own ``correct`` and its plan copied back; at any other event the
  sub-environment's own :class:`~motion_envs.models.juggling.CascadeController` runs in
  Python on the measured state and both hands' plans are copied back (controllers other
  than ``juggler`` and ``juggler_latency_aware`` always run in Python);
* the worlds' control period compiled, MuJoCo's ``mj_step`` called from the loop
  (:func:`~motion_envs.envs.juggling._compiled.cascade_periods`, the contacts read from
  the world's contact sensors; in ``threads`` threads over blocks of worlds); the
  releases' noise in Python, from each world's
  generator, hand 0 before hand 1;
* the sensors' delay line, the step's bookkeeping and the observation rows compiled, the
  measurement noise drawn in Python from each sensor's generator; the human-likeness
  compiled (the nearest demonstrated state found in a compiled k-d tree of
  :class:`~motion_envs.models.juggling.HumanLikeness`'s samples: the same numbers); the
  reward and the infos as array operations.

With ``frame_skip=k`` a step runs these ``k`` times (``CascadeVectorEnv._period``),
each time for the sub-environments whose episode has not ended in the step, and sums
the rewards, reward terms, likeness and catches as ``CascadeEnv.step`` does.

``backend="python"`` runs each single environment's ``step`` (no numba needed).
"""

from __future__ import annotations

from typing import Any

import numpy as np
from numpy.typing import NDArray

from motion_envs.datasets.juggling import CASCADE_HANDS, PHASES
from motion_envs.envs.juggling._batch import WorldBatch
from motion_envs.envs.juggling._cascade_env import CASCADE_HISTORY, CascadeEnv
from motion_envs.envs.juggling._vector import Columns, JugglingVectorEnv
from motion_envs.models.juggling import (
    LIKENESS_TAU,
    CascadeController,
    CascadeHand,
    CascadeState,
    ControlOptions,
    perturb_release,
    replan_many,
)

__all__ = ["CascadeVectorEnv"]

_TOSS, _GO_DOWN, _CATCH = PHASES.index("toss"), PHASES.index("go_down"), PHASES.index("catch")
_PHASE_CODES = np.array([_TOSS, _GO_DOWN, _CATCH], dtype=np.int64)
_FAST_CONTROLLERS = ("juggler", "juggler_latency_aware")
_SIGN = np.array([1.0, -1.0])  # x in each hand's own frame (the left hand's mirrored)
_HIST = 4 * CASCADE_HISTORY


class CascadeVectorEnv(JugglingVectorEnv):
    """``num_envs`` Cascade-v0 episodes stepped together (see the module docstring and
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
        :class:`~motion_envs.envs.juggling.CascadeEnv`'s keyword arguments.
    """

    single_class = CascadeEnv
    _LINKED = ("_compiled", "_datas", "_trees")
    _batched = True

    # -- state ----------------------------------------------------------------------------
    def _link(self) -> None:
        """The worlds' links and the likeness's compiled k-d trees (made again after
        unpickling, which copies the worlds)."""
        batch = self._batch
        assert batch is not None
        batch.link()
        self._compiled, self._datas = batch._compiled, batch._datas
        likeness = self.envs[0].likeness
        compiled = self._compiled
        self._trees = tuple(compiled.likeness_tree(likeness.trees[p].data) for p in PHASES)

    def _setup_arrays(self) -> None:
        # the worlds' batch; its arrays are this env's
        self._batch = batch = WorldBatch(self.envs, "numba", self.threads)
        self._holder, self._dropped, self._k = batch._holder, batch._dropped, batch._k
        self._caught, self._released = batch._caught, batch._released
        self._link()
        n, first = self.num_envs, self.envs[0]
        task = first.task
        self._dt, self._gravity = task.dt, task.gravity
        nb = self._nb = first.balls
        self._q = np.zeros((n, 4 + 2 * nb))
        self._v = np.zeros((n, 4 + 2 * nb))
        # what the controller was last shown (the measured balls)
        self._m_time = np.zeros(n)
        self._m_ball = np.zeros((n, nb, 2))
        self._m_ball_vel = np.zeros((n, nb, 2))
        # the sensor's delay line (a ring shared by all sub-environments: a reset fills
        # every slot of its own) and the observation's measurement history
        d = first.delay_steps
        self._ring = np.zeros((d + 1, n, nb, 5))
        self._slot = 0
        self._history = np.zeros((n, nb, _HIST))
        self._noisy = first.position_std > 0 or first.velocity_std > 0
        self._std = np.array([first.position_std] * 2 + [first.velocity_std] * 2)
        self._counts = np.zeros((n, 2), dtype=np.int64)  # catches, tosses
        self._sensor_rngs: list[Any] = [None] * n  # the generator of each sensor
        # the hands' plans
        self._fast = first.controller_name in _FAST_CONTROLLERS and first.controller.compiled_events
        self._latency = first.controller.latency
        self._ahead = first.controller_name == "juggler_latency_aware" and self._latency > 0
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
        c0 = first.controller  # the fitted juggler's constants (the siteswap juggler's: unused)
        options = c0.options if isinstance(c0, CascadeController) else ControlOptions()
        self._options = options
        ctask = c0.task  # the controller's (the same numbers)
        reaim = c0.tunables.reaim_after * c0.beat if isinstance(c0, CascadeController) else 0.0
        self._event_constants = np.array(
            [ctask.dt, ctask.gravity, reaim, self._latency, options.correction_tolerance]
        )
        self._advance_constants = np.array([ctask.dt, options.release_after, _TOSS])
        self._record_constants = np.array([task.dt, first.max_catches, first._time_limit])
        weights = first.reward_weights
        self._w = (weights["catch"], weights["drop"], weights["likeness"], weights["action"])
        self._low, self._high = first._low, first._high

    def _after_reset(self, i: int) -> None:
        if self.backend != "numba":
            return
        env = self.envs[i]
        w = env.world
        self._batch.load_world(i)
        self._q[i], self._v[i] = w.data.qpos, w.data.qvel
        state = env._state
        self._caught[i], self._released[i] = state.caught, state.released
        self._m_time[i] = state.time
        self._m_ball[i] = state.ball_pos
        self._m_ball_vel[i] = state.ball_vel
        size = self._ring.shape[0]
        for b, sensor in enumerate(env.sensor.sensors):
            for j, entry in enumerate(sensor._buffer):
                self._ring[(self._slot + 1 + j) % size, i, b] = entry
        self._history[i] = env._history
        self._sensor_rngs[i] = env.sensor.sensors[0]._rng
        self._counts[i] = 0
        for h in range(CASCADE_HANDS):
            self._load_hand(i, h)

    def _load_hand(self, i: int, h: int) -> None:
        """Copy hand ``h`` of sub-environment ``i``'s controller into the arrays."""
        c = self.envs[i].controller
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
            wider = np.zeros((self.num_envs, 2, grid.shape[0], 2))
            wider[:, :, : self._grid.shape[2]] = self._grid
            self._grid = wider
        self._grid[i, h, : grid.shape[0]] = grid
        self._glen[i, h] = grid.shape[0]

    # -- the step -------------------------------------------------------------------------
    def _step_batch(self, envs: NDArray[np.int64], actions: NDArray[np.float64]) -> tuple[
        NDArray[np.float32], NDArray[np.float64], NDArray[np.bool_], NDArray[np.bool_], Columns
    ]:  # fmt: skip
        if self.backend != "numba":
            return super()._step_batch(envs, actions)
        m = envs.size
        # the action (as CascadeEnv.step)
        invalid = np.logical_not(np.isfinite(actions).all(axis=1))
        a = np.clip(np.where(np.isnan(actions), 0.0, actions), -1.0, 1.0)
        residual = self.envs[0].residual_scale * a.reshape(m, 2, 2)
        # CascadeEnv's a @ a: the same dot product per row (numpy's matmul loop over the
        # stack calls it as for one row; the BLAS dot's order is not the naive sum's)
        action_sq = np.matmul(a[:, None, :], a[:, :, None])[:, 0, 0]
        # the control periods, each sub-environment's until its episode ends (as
        # CascadeEnv.step: the reward terms, the likeness and the catches summed)
        live = np.arange(m)
        for period in range(self.envs[0].frame_skip):
            out = self._period(envs[live], residual[live], action_sq[live])
            if period == 0:  # the first period's own values (frame_skip 1: unchanged)
                time, terminated, truncated, sums = out
            else:
                t, term, trunc, terms = out
                time[live], terminated[live], truncated[live] = t, term, trunc
                for key, value in terms.items():
                    sums[key][live] += value
            live = live[np.logical_not(terminated[live] | truncated[live])]
            if live.size == 0:
                break
        q = self._q[envs]
        holder = self._holder[envs]
        counts = self._counts
        phase = self._phase[envs]
        held = np.stack([(holder == h).any(axis=1) for h in range(CASCADE_HANDS)], axis=1)
        obs = self._observations(envs)
        reward = sums.pop("reward")
        columns: Columns = {
            "phase": phase[:, 0].copy(),  # codes: _vector.numeric_info
            "phases": phase.copy(),
            "held": held,
            "time": time,
            "hand": q[:, 0:2].copy(),
            "hands": q[:, 0:4].reshape(m, 2, 2).copy(),
            "balls": q[:, 4:].reshape(m, self._nb, 2).copy(),
            **sums,
            "catches": counts[envs, 0].copy(),
            "tosses": counts[envs, 1].copy(),
            "cycles": counts[envs, 1].copy(),
            "action_invalid": invalid,
        }
        return obs, reward, terminated, truncated, columns

    def _period(
        self, envs: NDArray[np.int64], residual: NDArray[np.float64], action_sq: NDArray[Any]
    ) -> tuple[NDArray[np.float64], NDArray[np.bool_], NDArray[np.bool_], Columns]:
        """One control period of ``envs`` with the residuals ``residual (m, 2, 2)`` (m):
        their time, terminations and truncations, and the period's reward (``"reward"``),
        reward terms, likeness and catches (``"caught"``)."""
        targets, armed = self._commands(envs)
        first = self.envs[0]
        if first.residual_phases is not None:  # as CascadeEnv._period: a selection
            acts = first.residual_acts[self._phase[envs]]
            residual = np.where(acts[:, :, None], residual, 0.0)
        batch = self._batch
        assert batch is not None
        batch.world_periods(envs, targets + residual, armed)
        self._q[envs], self._v[envs] = batch.qv(envs)
        released = self._released[envs]
        if (released >= 0).any():
            self._release(envs[(released >= 0).any(axis=1)])
        rows = self._measure(envs)
        time, caught_n, dropped, terminated, truncated = self._compiled.cascade_record(
            envs,
            rows,
            (self._k, self._caught, self._released, self._dropped),
            (self._m_time, self._m_ball, self._m_ball_vel, self._history),
            self._counts,
            self._record_constants,
        )
        for i, t in zip(envs.tolist(), time.tolist(), strict=True):
            self._datas[i].time = t
        likeness = self._likeness_of(self._phase[envs], self._q[envs], self._v[envs])
        w_catch, w_drop, w_like, w_act = self._w
        r_catch = w_catch * caught_n
        r_drop = -w_drop * dropped.astype(np.float64)
        r_like = -w_like * likeness
        r_act = -w_act * action_sq
        terms: Columns = {
            "reward": r_catch + r_drop + r_like + r_act,
            "reward_catch": r_catch.astype(np.float64),
            "reward_drop": r_drop,
            "reward_likeness": r_like,
            "reward_action": r_act,
            "likeness": likeness,
            "caught": caught_n.astype(np.int64),
        }
        return time, terminated, truncated, terms

    # -- the controllers ----------------------------------------------------------------
    def _commands(self, envs: NDArray[np.int64]) -> tuple[NDArray[np.float64], NDArray[np.bool_]]:
        """Both hands' targets ``(m, 2, 2)`` (world) and release arming ``(m, 2)`` for
        ``envs``: array indexing between events, the hand's own ``correct`` where an eq.
        10 correction is due, the controller itself at other events (see the module
        docstring)."""
        if not self._fast:
            return self._python_commands(envs)
        c = self._compiled
        python, due, ball = c.cascade_events(
            envs,
            (
                self._phase,
                self._pk,
                self._end_k,
                self._t_start,
                self._duration,
                self._end,
                self._incoming,
                self._catch_ball,
            ),
            (self._holder, self._caught, self._released, self._q, self._v),
            (self._m_time, self._m_ball, self._m_ball_vel),
            self._event_constants,
            _PHASE_CODES,
            self._options.correction,
            self._ahead,
        )
        if due.any():
            self._correct(envs, due, ball)
        targets = np.empty((envs.size, 2, 2))
        armed = np.empty((envs.size, 2), dtype=np.bool_)
        fast = ~python
        if fast.any():
            t, a = c.cascade_advance(
                envs[fast],
                self._pk,
                self._grid,
                self._glen,
                self._last,
                self._phase,
                self._advance_constants,
            )
            targets[fast], armed[fast] = t, a
        if python.any():
            t, a = self._python_commands(envs[python])
            targets[python], armed[python] = t, a
        return targets, armed

    def _correct(
        self, envs: NDArray[np.int64], due: NDArray[np.bool_], ball: NDArray[np.float64]
    ) -> None:
        """The eq. 10 corrections found due: each hand re-plans toward its view's ball's
        predicted intercept (:meth:`JugglingController.correct`'s flight, own frame),
        all of them together (:func:`~motion_envs.models.juggling.replan_many`); the new
        plans are copied back."""
        rows, hands_at = np.nonzero(due)
        if rows.size == 0:
            return
        at = envs[rows]
        g = float(self._event_constants[1])
        b = ball[rows, hands_at]
        s = self._t_start[at, hands_at] + self._duration[at, hands_at] - self._m_time[at]
        predicted = np.empty((rows.size, 2))
        predicted[:, 0] = b[:, 0] + b[:, 2] * (s - 0.0)
        predicted[:, 1] = b[:, 1] + b[:, 3] * (s - 0.0) - 0.5 * g * (s - 0.0) * (s - 0.0)
        hands: list[CascadeHand] = []
        for i, hh in zip(at.tolist(), hands_at.tolist(), strict=True):
            hand = self.envs[i].controller.hands[hh]
            hand.k = int(self._pk[i, hh])
            hands.append(hand)
        replan_many(hands, self._m_time[at].tolist(), predicted)
        for i, hh, hand in zip(at.tolist(), hands_at.tolist(), hands, strict=True):
            self._load_grid(i, hh, hand)
            self._end[i, hh] = hand.end

    def _python_commands(
        self, envs: NDArray[np.int64]
    ) -> tuple[NDArray[np.float64], NDArray[np.bool_]]:
        """The controllers of ``envs`` run in Python on the measured state; their plans
        are copied back into the arrays."""
        targets = np.empty((envs.size, 2, 2))
        armed = np.empty((envs.size, 2), dtype=np.bool_)
        for j, i in enumerate(envs.tolist()):
            c = self.envs[i].controller
            if self._fast:
                for h, hand in enumerate(c.hands):
                    hand.k = int(self._pk[i, h])
                    hand._last = [self._last[i, h, 0].copy(), self._last[i, h, 1].copy()]
            q, v = self._q[i], self._v[i]
            state = CascadeState(
                time=float(self._m_time[i]),
                hand_pos=q[0:4].reshape(2, 2).copy(),
                hand_vel=v[0:4].reshape(2, 2).copy(),
                ball_pos=self._m_ball[i].copy(),
                ball_vel=self._m_ball_vel[i].copy(),
                holder=tuple(self._holder[i].tolist()),
                released=(int(self._released[i, 0]), int(self._released[i, 1])),
                caught=(int(self._caught[i, 0]), int(self._caught[i, 1])),
                dropped=tuple(self._dropped[i].tolist()),
            )
            t, a = c.command(state)
            targets[j], armed[j] = t, a
            for h in range(CASCADE_HANDS):
                self._load_hand(i, h)
        return targets, armed

    # -- the world's releases, the sensor, the likeness, the observation -----------------
    def _release(self, envs: NDArray[np.int64]) -> None:
        """The releases of ``envs`` (their world's rule fired; hand 0 first): the ball
        leaves with its hand's velocity, scattered by the world's generator."""
        for i in envs.tolist():
            w = self.envs[i].world
            qvel = self._datas[i].qvel
            for h in range(CASCADE_HANDS):
                b = int(self._released[i, h])
                if b < 0:
                    continue
                u = perturb_release(
                    qvel[2 * h : 2 * h + 2].copy(), w.release_speed_std, w.release_angle_std,
                    w._rng,
                )  # fmt: skip
                c = 4 + 2 * b
                qvel[c], qvel[c + 1] = float(u[0]), float(u[1])
                self._v[i, c], self._v[i, c + 1] = qvel[c], qvel[c + 1]

    def _measure(self, envs: NDArray[np.int64]) -> Any:
        """The sensor (:meth:`CascadeSensor.measure`) for ``envs``: ``(m, B, 4)`` rows
        ``(x, z, vx, vz)`` per ball, the true state while held, the delayed (noisy) one
        else."""
        self._slot = slot = (self._slot + 1) % self._ring.shape[0]
        rows, noisy = self._compiled.cascade_measure(
            envs, self._q, self._v, self._holder, self._ring, slot
        )
        if self._noisy and noisy.any():
            # per sub-environment one draw for its noisy balls in order (a generator's
            # normals are a stream: 4 k at once are k draws of 4)
            counts = noisy.sum(axis=1)
            rngs = self._sensor_rngs
            draws = [
                rngs[i].standard_normal(4 * c)
                for i, c in zip(envs.tolist(), counts.tolist(), strict=True)
                if c
            ]
            rows[noisy] += self._std * np.concatenate(draws).reshape(-1, 4)
        return rows

    def _likeness_of(
        self, phase: NDArray[np.int64], q: NDArray[np.float64], v: NDArray[np.float64]
    ) -> Any:
        """m; the mean over the hands of :meth:`HumanLikeness.distance` (own frame, the
        same numbers, compiled: :func:`~motion_envs.envs.juggling._compiled.nearest_rows`),
        summed as ``CascadeEnv.step`` sums it."""
        like = np.zeros(q.shape[0])
        for h in range(CASCADE_HANDS):
            sign = _SIGN[h]
            points = np.stack(
                [
                    q[:, 2 * h] * sign,
                    q[:, 2 * h + 1] * 1.0,
                    LIKENESS_TAU * (v[:, 2 * h] * sign),
                    LIKENESS_TAU * (v[:, 2 * h + 1] * 1.0),
                ],
                axis=1,
            )
            d = self._compiled.nearest_rows(points, phase[:, h], self._trees)
            like = like + d / CASCADE_HANDS
        return like

    def _observations(self, envs: NDArray[np.int64]) -> Any:
        rows = self._compiled.cascade_observations(
            envs,
            self._q,
            self._v,
            self._holder,
            self._history,
            self._phase,
            self._duration,
            (self._pk, self._grid, self._glen, self._end),
            self._dt,
            self._fast,
            (self._phase_time, self._next, self._end),
        )
        obs = rows.astype(np.float32)
        np.minimum(obs, self._high, out=obs)
        return np.maximum(obs, self._low, out=obs)
