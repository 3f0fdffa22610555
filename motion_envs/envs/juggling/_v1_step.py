"""Juggling-v1's step beyond the world's period, written once as scalar code for the worlds
``envs`` of a batch (:class:`~motion_envs.envs.juggling._v1_batch.V1Batch`; the single
environment is the batch of one):

* :func:`v1_command`: the action (clipped, NaN as 0), the controller's phase events and
  eq. 10 corrections due (the tests of ``JugglingController.command`` and ``correct`` on
  the measured state), and between events the command (the plan's next grid point) with
  the residual (:func:`aim`);
* :func:`v1_finish`: after the world's period, the release's scatter, the sensor, the
  counts, the human-likeness, the reward, the episode's end and the observation
  (:func:`v1_observe`);
* :func:`v1_step` and :func:`v1_rest`: the step in one call (the command, the worlds'
  period of :mod:`~motion_envs.envs.juggling._period`, the finish) while no world needs
  the controller in Python, and the period with the finish after it does (each compiled
  call costs the unboxing of its arrays, so fewer calls make a cheaper step).

**Written once, run two ways** (as :mod:`~motion_envs.envs.juggling._period`): plain
Python here (the path without numba), and compiled by
:mod:`~motion_envs.envs.juggling._compiled_v1` from the very same function bodies, their
global names bound to the compiled equivalents (``py_hypot`` is CPython's ``math.hypot``
in both; ``hand_likeness`` the k-d tree search, the same number): bit-identical.
"""

from __future__ import annotations

import math
from typing import Any

from motion_envs.datasets.juggling import PHASES
from motion_envs.envs.juggling._period import py_hypot, world_periods

__all__ = [
    "OUT_COLUMNS",
    "advance",
    "aim",
    "hand_likeness",
    "v1_advance",
    "v1_aim",
    "v1_command",
    "v1_finish",
    "v1_observe",
    "v1_rest",
    "v1_step",
]

#: The columns of :func:`v1_finish`'s ``out`` rows.
OUT_COLUMNS = (
    "reward", "reward_catch", "reward_drop", "reward_likeness", "reward_action", "likeness",
    "time", "caught", "catches", "tosses", "phase", "held", "action_invalid", "hand_x",
    "hand_z", "ball_x", "ball_z", "terminated", "truncated",
)  # fmt: skip


def hand_likeness(
    trees: Any, phase: int, point: tuple[float, float, float, float], tau: float, stack: Any
) -> float:
    """m; :meth:`~motion_envs.models.juggling.HumanLikeness.distance` of the hand at
    ``point = (x, z, vx, vz)`` in phase ``PHASES[phase]`` (``trees``: the likeness, whose
    velocity weight is ``tau``; compiled: its phases' k-d trees, the same number)."""
    x, z, vx, vz = point
    return float(trees.distance(PHASES[phase], (x, z), (vx, vz)))


def advance(i: int, plan: Any, dt: float, release_after: float, toss: int) -> Any:
    """``JugglingController.command`` without an event for world ``i``: the next grid
    point (``k + 1``), the last two commands kept, the release armed in the toss after
    ``release_after``. ``plan = (phase, k, end_k, t_start, duration, end, grid, glen,
    last)``. Returns ``(x, z, armed)``."""
    phase, pk, grid, glen, last = plan[0], plan[1], plan[6], plan[7], plan[8]
    k = pk[i] + 1
    pk[i] = k
    g = min(k, glen[i] - 1)
    tx, tz = grid[i, g, 0], grid[i, g, 1]
    last[i, 0, 0], last[i, 0, 1] = last[i, 1, 0], last[i, 1, 1]
    last[i, 1, 0], last[i, 1, 1] = tx, tz
    return tx, tz, phase[i] == toss and k * dt >= release_after


def aim(
    i: int, tx: float, tz: float, armed: bool, a: Any, phase: Any, residual: Any, world: Any
) -> None:
    """World ``i``'s command into the world's ``target, armed = world``: the controller's
    target ``(tx, tz)`` plus ``scale`` times the action ``a = (ax, az, invalid)`` where the
    phase after the command is one the residual acts in (``residual = (scale, acts)``)."""
    scale, acts = residual
    target, arm = world
    ax, az = (a[0], a[1]) if acts[phase[i]] else (0.0, 0.0)
    target[i, 0, 0] = tx + scale * ax
    target[i, 0, 1] = tz + scale * az
    arm[i, 0] = armed


def v1_command(
    envs: Any,
    actions: Any,
    plan: Any,
    measured: Any,
    constants: Any,
    flags: Any,
    residual: Any,
    world: Any,
    a_out: Any,
    status: Any,
    predicted: Any,
) -> int:
    """The start of a step for ``envs``: each action ``actions[j]`` clipped to [-1, 1]
    (NaN as 0) into ``a_out[j] = (ax, az, invalid)``; which worlds need the controller
    in Python (a phase event: ``status[j] = 1``) or an eq. 10 correction (status 2, the
    predicted intercept in ``predicted[j]``; the latency-aware controller's forward
    prediction first); the others' commands (:func:`advance`, :func:`aim`: status 0).

    ``plan`` as :func:`advance` takes it; ``measured = (values (N, 5): time, ball x, z,
    vx, vz; flags (N, 3): held, released, caught)``; ``constants = (dt, gravity,
    latency, tolerance, toss, catch, release_after)``; ``flags = (fast, correction,
    ahead)`` (not ``fast``: every world's controller runs in Python); ``status (m,)``
    and ``predicted (m, 2)`` are written. Returns how many worlds need Python (status
    not 0)."""
    phase, pk, end_k, t_start, duration, end = plan[0], plan[1], plan[2], plan[3], plan[4], plan[5]
    values, m_flags = measured
    dt, g, latency, tolerance = constants[0], constants[1], constants[2], constants[3]
    toss, catch, release_after = int(constants[4]), int(constants[5]), constants[6]
    fast, correction, ahead = flags
    m = envs.shape[0]
    events = 0
    for j in range(m):
        status[j] = 0
        i = envs[j]
        ax, az = actions[j, 0], actions[j, 1]
        invalid = not (math.isfinite(ax) and math.isfinite(az))
        ax = 0.0 if math.isnan(ax) else (-1.0 if ax < -1.0 else (1.0 if ax > 1.0 else ax))
        az = 0.0 if math.isnan(az) else (-1.0 if az < -1.0 else (1.0 if az > 1.0 else az))
        a_out[j, 0], a_out[j, 1], a_out[j, 2] = ax, az, 1.0 if invalid else 0.0
        ph, k = phase[i], pk[i]
        held, released, caught = m_flags[i, 0], m_flags[i, 1], m_flags[i, 2]
        if (
            not fast
            or (ph == toss and released)
            or (ph == catch and caught)
            or (end_k[i] >= 0 and k >= end_k[i])
        ):
            status[j] = 1
            events += 1
            continue
        if correction and ph == catch and not held:
            bx, bz = values[i, 1], values[i, 2]
            vx, vz = values[i, 3], values[i, 4]
            if ahead:  # predict_forward(..., latency): rules.flight from time 0
                s = latency - 0.0
                bx, bz = bx + vx * s, bz + vz * s - 0.5 * g * s * s
                vz = vz - g * s
            s = t_start[i] + duration[i] - values[i, 0]
            px = bx + vx * (s - 0.0)
            pz = bz + vz * (s - 0.0) - 0.5 * g * (s - 0.0) * (s - 0.0)
            if s > dt and py_hypot(px - end[i, 0], pz - end[i, 1]) > tolerance:
                status[j] = 2
                events += 1
                predicted[j, 0], predicted[j, 1] = px, pz
                continue
        tx, tz, armed = advance(i, plan, dt, release_after, toss)
        aim(i, tx, tz, armed, a_out[j], phase, residual, world)
    return events


def v1_rest(envs: Any, period: Any, finish: Any) -> int:
    """The rest of a step once every world's command is made: the worlds' control period
    (:func:`~motion_envs.envs.juggling._period.world_periods`, ``period`` its arguments
    after ``envs``), then :func:`v1_finish` (``finish`` its arguments after ``envs``);
    returns :func:`v1_finish`'s count."""
    world_periods(envs, *period)
    return v1_finish(envs, *finish)


def v1_step(envs: Any, actions: Any, command: Any, period: Any, finish: Any) -> int:
    """A whole step in one call where no world needs Python: :func:`v1_command`
    (``command`` its arguments after ``envs, actions``), then, if no world has an event
    or a correction due, :func:`v1_rest`. Returns -1 when some world needs Python
    (its commands to be completed, then :func:`v1_rest`), else :func:`v1_finish`'s count."""
    if v1_command(envs, actions, *command) > 0:
        return -1
    return v1_rest(envs, period, finish)


def v1_advance(rows: Any, plan: Any, constants: Any, a_out: Any, residual: Any, world: Any) -> None:
    """:func:`advance` and :func:`aim` for ``rows`` (their corrections made), with their
    actions ``a_out (r, 3)``; ``constants`` as :func:`v1_command` takes them."""
    dt, toss, release_after = constants[0], int(constants[4]), constants[6]
    for j in range(rows.shape[0]):
        i = rows[j]
        tx, tz, armed = advance(i, plan, dt, release_after, toss)
        aim(i, tx, tz, armed, a_out[j], plan[0], residual, world)


def v1_aim(
    rows: Any, targets: Any, armed: Any, a_out: Any, phase: Any, residual: Any, world: Any
) -> None:
    """:func:`aim` for ``rows`` with the controller's ``targets (r, 2)`` and ``armed
    (r,)`` (its commands in Python)."""
    for j in range(rows.shape[0]):
        aim(rows[j], targets[j, 0], targets[j, 1], armed[j], a_out[j], phase, residual, world)


def v1_finish(
    envs: Any,
    worlds: Any,
    world: Any,
    true: Any,
    sensor: Any,
    release: Any,
    counts: Any,
    plan: Any,
    likeness: Any,
    scalars: Any,
    bounds: Any,
    a_out: Any,
    measured: Any,
    obs: Any,
    out: Any,
) -> int:
    """The rest of Juggling-v1's step for each world ``i = envs[j]`` after its period:

    * the true state read from the world (``worlds``: its ``qpos`` and ``qvel`` per
      world, as the period's links hold them; ``world =
      (holder, left, dropped, k, caught, released)``) into ``true = (state (N, 8): hand
      x, z, vx, vz, ball x, z, vx, vz; flags (N, 3): held, left, dropped)``; a released
      ball's velocity (the hand's) turned and scaled by the next row of ``release =
      (noise (N, R, 2), at (N,), std (2,): speed, angle (rad))``, drawn ahead from the
      world's generator, when a std is not zero (:func:`perturb_release`'s numbers);
    * the sensor (:meth:`~motion_envs.models.juggling.BallSensor.measure_values`):
      ``sensor = (ring (S, N, 5), slot, noise (N, R, 4), at (N,), std (4,))``; the delay
      line takes the true ball ``(x, z, vx, vz, held)`` at ``slot``; the measurement is
      the true state while held, else the oldest entry, plus the next row of noise
      (drawn ahead from the sensor's generator) times ``std`` when that entry was flying
      and ``noisy``;
    * the measured state for the controller (``measured = (values, flags)`` as
      :func:`v1_command` reads it), the measurement ``history`` (in ``plan``) shifted,
      the catches and tosses ``counts (N, 2)``, the episode's end;
    * the hand's human-likeness (:func:`hand_likeness`; ``likeness = (trees, stack)``),
      the reward terms and the reward (weights in ``scalars = (dt, likeness_tau,
      w_catch, w_drop, w_likeness, w_action, max_catches, time_limit, noisy)``);
    * the observation (:func:`v1_observe`; ``plan = (phase, k, duration, end, grid,
      glen, next, fast, history)``) into ``obs[j]`` and the row ``out[j]``
      (:data:`OUT_COLUMNS`: the reward, its terms, the infos, the episode's end).

    Returns the number of generators whose block of noise drawn ahead is used up (to be
    drawn again before the next step)."""
    holder, left, dropped_w, k, caught_w, released_w = world
    state, t_flags = true
    ring, slot, noise, noise_at, noise_std = sensor
    r_noise, r_at, r_std = release
    trees, stack = likeness
    values, m_flags = measured
    history = plan[8]
    dt, tau = scalars[0], scalars[1]
    w_catch, w_drop, w_like, w_act = scalars[2], scalars[3], scalars[4], scalars[5]
    max_catches, time_limit, noisy = scalars[6], scalars[7], scalars[8] > 0.0
    scatter = r_std[0] != 0 or r_std[1] != 0
    oldest_slot = (slot + 1) % ring.shape[0]
    n_hist = history.shape[1]
    used_up = 0
    for j in range(envs.shape[0]):
        i = envs[j]
        q, v = worlds[0][i], worlds[1][i]
        caught, released = caught_w[i, 0] >= 0, released_w[i, 0] >= 0
        if released and scatter:  # perturb_release
            r = r_at[i]
            factor = 1.0 + r_std[0] * r_noise[i, r, 0]
            theta = r_std[1] * r_noise[i, r, 1]
            c, s = math.cos(theta), math.sin(theta)
            ux, uz = v[0], v[1]
            v[2], v[3] = (c * ux - s * uz) * factor, (s * ux + c * uz) * factor
            r_at[i] = r + 1
            if r + 1 == r_noise.shape[1]:
                used_up += 1
        held, dropped = holder[i, 0] >= 0, dropped_w[i, 0]
        hx, hz, hvx, hvz = q[0], q[1], v[0], v[1]
        bx, bz, ux, uz = q[2], q[3], v[2], v[3]
        state[i, 0], state[i, 1], state[i, 2], state[i, 3] = hx, hz, hvx, hvz
        state[i, 4], state[i, 5], state[i, 6], state[i, 7] = bx, bz, ux, uz
        t_flags[i, 0], t_flags[i, 1], t_flags[i, 2] = held, left[i, 0], dropped
        time = k[i] * dt
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
                if r + 1 == noise.shape[1]:
                    used_up += 1
        values[i, 0], values[i, 1], values[i, 2] = time, px, pz
        values[i, 3], values[i, 4] = vx, vz
        m_flags[i, 0], m_flags[i, 1], m_flags[i, 2] = held, released, caught
        if n_hist > 0:  # Juggling-v2 keeps no measurement history
            for h in range(n_hist - 1, 0, -1):
                for c in range(4):
                    history[i, h, c] = history[i, h - 1, c]
            history[i, 0, 0], history[i, 0, 1] = px, pz
            history[i, 0, 2], history[i, 0, 3] = vx, vz
        if caught:
            counts[i, 0] += 1
        if released:
            counts[i, 1] += 1
        phase = plan[0][i]
        like = hand_likeness(trees, phase, (hx, hz, hvx, hvz), tau, stack)
        # the reward
        ax, az = a_out[j, 0], a_out[j, 1]
        r_catch = w_catch * (1 if caught else 0)
        r_drop = -w_drop * (1.0 if dropped else 0.0)
        r_like = -w_like * like
        r_act = -w_act * (ax * ax + az * az)
        row = out[j]
        row[0] = r_catch + r_drop + r_like + r_act
        row[1], row[2], row[3], row[4], row[5] = r_catch, r_drop, r_like, r_act, like
        row[6], row[7], row[8], row[9] = time, 1.0 if caught else 0.0, counts[i, 0], counts[i, 1]
        row[10], row[11], row[12] = phase, 1.0 if held else 0.0, a_out[j, 2]
        row[13], row[14], row[15], row[16] = hx, hz, bx, bz
        # the episode's end: a drop, else max_catches catches or the time limit
        row[17] = 1.0 if dropped else 0.0
        ended = dropped or counts[i, 0] >= max_catches or time >= time_limit
        row[18] = 1.0 if ended and not dropped else 0.0
        v1_observe(i, obs[j], true, plan, bounds, dt)
    return used_up


def v1_observe(i: int, row: Any, true: Any, plan: Any, bounds: Any, dt: float) -> None:
    """World ``i``'s observation into ``row`` (float32; see ``JugglingV1Env``), clipped to
    ``bounds = (low, high)``; ``true`` and ``plan`` as :func:`v1_finish` takes them (the
    next target read from the grid when ``fast``, else from ``next``)."""
    state, t_flags = true
    phases, plan_k, duration, plan_end, grid, glen, nominal, fast, history = plan
    low, high = bounds[0], bounds[1]
    row[0], row[1], row[2], row[3] = state[i, 0], state[i, 1], state[i, 2], state[i, 3]
    row[4] = 1.0 if t_flags[i, 0] else 0.0
    phase = phases[i]
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
    for h in range(history.shape[1]):
        for c in range(4):
            row[15 + 4 * h + c] = history[i, h, c]
    for c in range(row.shape[0]):
        if row[c] > high[c]:
            row[c] = high[c]
        if row[c] < low[c]:
            row[c] = low[c]
