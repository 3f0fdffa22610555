"""Juggling-v1's batched step beyond the world's period, compiled by numba: the phase
events and eq. 10 corrections due (:func:`v1_events`), the commands between events
(:func:`v1_advance`) and the rest of the step: sensor, counts, reward, observation
(:func:`v1_finish`). Each is written as the single environment's Python writes it, in
the same order (the vector environment equals ``SyncVectorEnv`` bit for bit: tested).

Importing this module imports numba (the ``fast`` extra).
"""

from __future__ import annotations

from typing import Any

import numpy as np
from numba import njit

from motion_envs.envs.juggling._compiled import py_hypot

__all__ = ["v1_advance", "v1_events", "v1_finish"]


@njit(cache=True)
def v1_events(envs: Any, plan: Any, measured: Any, m_flags: Any, constants: Any, flags: Any) -> Any:
    """Which of ``envs`` need Juggling-v1's controller in Python this step (a phase
    event) and which eq. 10 corrections are due: the tests of
    ``JugglingController.command`` and ``correct`` on the measured state, with their
    arithmetic (the latency-aware controller's forward prediction first).

    ``plan = (phase, k, end_k, t_start, duration, end)`` per sub-environment;
    ``measured (N, 5)`` (time, ball x, z, vx, vz) and ``m_flags (N, 3)`` (held,
    released, caught); ``constants = (dt, gravity, latency, tolerance, toss, catch)``;
    ``flags = (correction, ahead)``. Returns ``python (m,)``, ``due (m,)`` and the
    predicted intercepts ``(m, 2)`` where due."""
    phase, pk, end_k, t_start, duration, end = plan
    dt, g, latency, tolerance = constants[0], constants[1], constants[2], constants[3]
    toss, catch = int(constants[4]), int(constants[5])
    correction, ahead = flags[0], flags[1]
    m = envs.shape[0]
    python = np.zeros(m, dtype=np.bool_)
    due = np.zeros(m, dtype=np.bool_)
    predicted = np.zeros((m, 2))
    for j in range(m):
        i = envs[j]
        ph, k = phase[i], pk[i]
        held, released, caught = m_flags[i, 0], m_flags[i, 1], m_flags[i, 2]
        if (
            (ph == toss and released)
            or (ph == catch and caught)
            or (end_k[i] >= 0 and k >= end_k[i])
        ):
            python[j] = True
            continue
        if not correction or ph != catch or held:
            continue
        bx, bz = measured[i, 1], measured[i, 2]
        vx, vz = measured[i, 3], measured[i, 4]
        if ahead:  # predict_forward(..., latency): rules.flight from time 0
            s = latency - 0.0
            bx, bz = bx + vx * s, bz + vz * s - 0.5 * g * s * s
            vz = vz - g * s
        s = t_start[i] + duration[i] - measured[i, 0]
        px = bx + vx * (s - 0.0)
        pz = bz + vz * (s - 0.0) - 0.5 * g * (s - 0.0) * (s - 0.0)
        if s > dt and py_hypot(px - end[i, 0], pz - end[i, 1]) > tolerance:
            due[j] = True
            predicted[j, 0], predicted[j, 1] = px, pz
    return python, due, predicted


@njit(cache=True)
def v1_advance(
    rows: Any, pk: Any, grid: Any, glen: Any, last: Any, phase: Any, constants: Any
) -> Any:
    """``JugglingController.command`` without events for ``rows``: the next grid point
    (``k + 1``), the last two commands, the release armed in the toss after
    ``release_after``; ``constants = (dt, release_after, toss)``. Returns the targets
    ``(r, 2)`` and ``armed (r,)``."""
    dt, release_after, toss = constants[0], constants[1], int(constants[2])
    r = rows.shape[0]
    targets = np.empty((r, 2))
    armed = np.empty(r, dtype=np.bool_)
    for j in range(r):
        i = rows[j]
        k = pk[i] + 1
        pk[i] = k
        g = min(k, glen[i] - 1)
        tx, tz = grid[i, g, 0], grid[i, g, 1]
        last[i, 0, 0], last[i, 0, 1] = last[i, 1, 0], last[i, 1, 1]
        last[i, 1, 0], last[i, 1, 1] = tx, tz
        targets[j, 0], targets[j, 1] = tx, tz
        armed[j] = phase[i] == toss and k * dt >= release_after
    return targets, armed


@njit(cache=True)
def v1_finish(
    envs: Any,
    hand: Any,
    hand_vel: Any,
    ball: Any,
    ball_vel: Any,
    flags: Any,
    events: Any,
    k: Any,
    scalars: Any,
    ring: Any,
    slot: int,
    noise: Any,
    noise_at: Any,
    noise_std: Any,
    counts: Any,
    history: Any,
    phases: Any,
    plan_k: Any,
    duration: Any,
    plan_end: Any,
    grid: Any,
    glen: Any,
    nominal: Any,
    fast: bool,
    likeness: Any,
    bounds: Any,
    actions: Any,
    measured: Any,
    m_flags: Any,
    obs: Any,
    out: Any,
    ends: Any,
) -> None:
    """The rest of Juggling-v1's step for each world ``i = envs[j]`` after its period
    (:meth:`JugglingV1Env._advance` after the world, then ``step``'s likeness, reward and
    observation), written as those write it:

    * the sensor (:meth:`~motion_envs.models.juggling.BallSensor.measure_values`): the
      delay line ``ring (R, N, 5)`` takes the true ball ``(x, z, vx, vz, held)`` at
      ``slot``; the measurement is the true state while held, else the oldest entry,
      plus the next row of ``noise[i]`` (drawn ahead from the sensor's generator; every
      world has one left) times ``noise_std`` when that entry was flying and
      ``noise_std`` is not zero;
    * the measured state for the controller ``measured[i] = (time, x, z, vx, vz)``,
      ``m_flags[i] = (held, released, caught)``; the ``history`` shifted; the catches
      and tosses ``counts``; the episode's end;
    * the reward terms and the reward, with the hand's human-likeness ``likeness[j]``
      (:func:`nearest_rows`);
    * the observation, clipped to ``bounds = (low, high)``.

    ``scalars = (dt, likeness_tau, w_catch, w_drop, w_likeness, w_action, max_catches,
    time_limit, noisy)``; ``phases, plan_k, duration, plan_end`` the plans after the
    commands (phase index, step in the phase, duration, end point); ``nominal[i]`` the
    next nominal target when not ``fast`` (else it is read from ``grid``). Out per row
    ``j``: ``obs[j]``, ``out[j] = (reward, r_catch, r_drop, r_likeness, r_action,
    likeness, time)``, ``ends[j] = (terminated, truncated)``.
    """
    dt = scalars[0]  # scalars[1], the likeness weight of the velocity, is used outside
    w_catch, w_drop, w_like, w_act = scalars[2], scalars[3], scalars[4], scalars[5]
    max_catches, time_limit, noisy = scalars[6], scalars[7], scalars[8] > 0.0
    size = ring.shape[0]
    oldest_slot = (slot + 1) % size
    n_hist = history.shape[1]
    low, high = bounds[0], bounds[1]
    for j in range(envs.shape[0]):
        i = envs[j]
        held, dropped = flags[i, 0], flags[i, 2]
        caught, released = events[i, 0], events[i, 1]
        time = k[i] * dt
        bx, bz, ux, uz = ball[i, 0], ball[i, 1], ball_vel[i, 0], ball_vel[i, 1]
        # the sensor
        ring[slot, i, 0], ring[slot, i, 1] = bx, bz
        ring[slot, i, 2], ring[slot, i, 3] = ux, uz
        ring[slot, i, 4] = 1.0 if held else 0.0
        if held:
            px, pz, vx, vz = bx, bz, ux, uz
        else:
            px, pz = ring[oldest_slot, i, 0], ring[oldest_slot, i, 1]
            vx, vz = ring[oldest_slot, i, 2], ring[oldest_slot, i, 3]
            if ring[oldest_slot, i, 4] == 0.0 and noisy:
                r = noise_at[i]
                px += noise_std[0] * noise[i, r, 0]
                pz += noise_std[1] * noise[i, r, 1]
                vx += noise_std[2] * noise[i, r, 2]
                vz += noise_std[3] * noise[i, r, 3]
                noise_at[i] = r + 1
        measured[i, 0], measured[i, 1], measured[i, 2] = time, px, pz
        measured[i, 3], measured[i, 4] = vx, vz
        m_flags[i, 0], m_flags[i, 1], m_flags[i, 2] = held, released, caught
        for h in range(n_hist - 1, 0, -1):
            for c in range(4):
                history[i, h, c] = history[i, h - 1, c]
        history[i, 0, 0], history[i, 0, 1] = px, pz
        history[i, 0, 2], history[i, 0, 3] = vx, vz
        if caught:
            counts[i, 0] += 1
        if released:
            counts[i, 1] += 1
        terminated = dropped
        truncated = not terminated and (counts[i, 0] >= max_catches or time >= time_limit)
        phase = phases[i]
        like = likeness[j]
        # the reward (LevelsEnvMixin._rewards)
        ax, az = actions[j, 0], actions[j, 1]
        r_catch = w_catch * (1 if caught else 0)
        r_drop = -w_drop * (1.0 if dropped else 0.0)
        r_like = -w_like * like
        r_act = -w_act * (ax * ax + az * az)
        out[j, 0] = r_catch + r_drop + r_like + r_act
        out[j, 1], out[j, 2], out[j, 3], out[j, 4] = r_catch, r_drop, r_like, r_act
        out[j, 5], out[j, 6] = like, time
        ends[j, 0], ends[j, 1] = terminated, truncated
        # the observation (JugglingV1Env._observation)
        row = obs[j]
        row[0], row[1] = hand[i, 0], hand[i, 1]
        row[2], row[3] = hand_vel[i, 0], hand_vel[i, 1]
        row[4] = 1.0 if held else 0.0
        for p in range(4):
            row[5 + p] = 1.0 if p == phase else 0.0
        row[9] = plan_k[i] * dt
        row[10] = duration[i]
        if fast:
            g = min(plan_k[i] + 1, glen[i] - 1)
            row[11], row[12] = grid[i, g, 0], grid[i, g, 1]
        else:
            row[11], row[12] = nominal[i, 0], nominal[i, 1]
        row[13], row[14] = plan_end[i, 0], plan_end[i, 1]
        for h in range(n_hist):
            for c in range(4):
                row[15 + 4 * h + c] = history[i, h, c]
        for c in range(row.shape[0]):
            if row[c] > high[c]:
                row[c] = high[c]
            if row[c] < low[c]:
                row[c] = low[c]
