"""Cascade-v0's step beyond the worlds' period, written once as scalar code for the
worlds ``envs`` of a batch (:class:`~motion_envs.envs.juggling._cascade_batch.CascadeBatch`;
the single environment is the batch of one):

* :func:`cascade_command`: the action (clipped, NaN as 0), the tests of
  :class:`~motion_envs.models.juggling.CascadeHand`'s ``command`` (a release, a catch, a
  ball held early, a reached end point, a re-aimed catch) and of the eq. 10 correction
  (on the hand's view of its oldest queued ball, predicted forward by the latency-aware
  controller) with the controller's arithmetic, and between events each hand's command
  (the next point of its plan on the control grid) plus its residual (:func:`aim`);
* :func:`cascade_finish`: after the worlds' period, the releases' scatter, the sensors,
  the counts, the human-likeness, the reward, the episode's end and the observation
  (:func:`cascade_observe`).

**Written once, run two ways** (as :mod:`~motion_envs.envs.juggling._period` and
:mod:`~motion_envs.envs.juggling._v1_step`): plain Python here (the path without numba),
and compiled by :mod:`~motion_envs.envs.juggling._compiled_cascade` from the very same
function bodies, their global names bound to the compiled equivalents: bit-identical
(tested).
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from motion_envs.envs.juggling._period import py_hypot, world_periods
from motion_envs.envs.juggling._v1_step import hand_likeness

__all__ = [
    "advance",
    "aim",
    "cascade_advance",
    "cascade_aim",
    "cascade_command",
    "cascade_finish",
    "cascade_observe",
    "cascade_period",
    "holds",
    "out_columns",
]

#: The first columns of :func:`cascade_finish`'s ``out`` rows; then the hands' ``x, z``
#: (4) and the balls' ``x, z`` (``2 B``).
OUT_COLUMNS = (
    "reward", "reward_catch", "reward_drop", "reward_likeness", "reward_action", "likeness",
    "time", "caught", "catches", "tosses", "phase_0", "phase_1", "held_0", "held_1",
    "action_invalid", "terminated", "truncated",
)  # fmt: skip
_HANDS = len(OUT_COLUMNS)


def out_columns(balls: int) -> int:
    """The width of :func:`cascade_finish`'s ``out`` rows with ``balls`` balls."""
    return _HANDS + 4 + 2 * balls


def holds(holder: Any, i: int, h: int) -> bool:
    """Whether hand ``h`` of world ``i`` holds a ball (``holder (N, B)``)."""
    for b in range(holder.shape[1]):
        if holder[i, b] == h:
            return True
    return False


def advance(i: int, h: int, plan: Any, dt: float, release_after: float, toss: int) -> Any:
    """``JugglingController.command`` without an event for hand ``h`` of world ``i``: the
    next grid point (``k + 1``), the last two commands kept, the release armed in the toss
    after ``release_after``. ``plan`` as :func:`cascade_command` takes it. Returns ``(x,
    z, armed)`` in the hand's own frame."""
    phase, pk, grid, glen, last = plan[0], plan[1], plan[8], plan[9], plan[10]
    k = pk[i, h] + 1
    pk[i, h] = k
    g = min(k, glen[i, h] - 1)
    tx, tz = grid[i, h, g, 0], grid[i, h, g, 1]
    last[i, h, 0, 0], last[i, h, 0, 1] = last[i, h, 1, 0], last[i, h, 1, 1]
    last[i, h, 1, 0], last[i, h, 1, 1] = tx, tz
    return tx, tz, phase[i, h] == toss and k * dt >= release_after


def aim(
    i: int, h: int, tx: float, tz: float, armed: bool, a: Any, phase: Any, residual: Any,
    world: Any,
) -> None:  # fmt: skip
    """Hand ``h`` of world ``i``'s command into ``world = (target, armed)``: the
    controller's target ``(tx, tz)`` (world frame) plus ``scale`` times the hand's action
    ``a[2 h], a[2 h + 1]`` where the hand's phase after the command is one the residual
    acts in (``residual = (scale, acts)``), else plus 0."""
    scale, acts = residual
    target, arm = world
    ax, az = (scale * a[2 * h], scale * a[2 * h + 1]) if acts[phase[i, h]] else (0.0, 0.0)
    target[i, h, 0] = tx + ax
    target[i, h, 1] = tz + az
    arm[i, h] = armed


def cascade_command(
    envs: Any,
    actions: Any,
    plan: Any,
    world: Any,
    measured: Any,
    constants: Any,
    flags: Any,
    residual: Any,
    command: Any,
    a_out: Any,
) -> Any:
    """The start of a control period for ``envs``: each action ``actions[j] (4,)``
    clipped to [-1, 1] (NaN as 0) into ``a_out[j] = (a_0 .. a_3, invalid)``; which worlds
    need their controller in Python (an event of either hand, or not ``fast``: status 1)
    or an eq. 10 correction (status 2: ``due[j, h]`` and the predicted intercept
    ``predicted[j, h]``, own frame); the others' commands (:func:`advance`, :func:`aim`:
    status 0) into ``command = (target (N, 2, 2), armed (N, 2))``.

    ``plan = (phase, k, end_k, t_start, duration, end, incoming, catch_ball, grid, glen,
    last)`` per ``(N, 2)`` hand (``end`` own frame); ``world = (holder, caught, released,
    q, v)`` (the last period's; ``q, v`` the worlds' ``qpos``/``qvel`` views);
    ``measured = (time, ball, ball_vel)``; ``constants = (dt, gravity, reaim, latency,
    tolerance, release_after, toss, go_down, catch)`` (``reaim``: s); ``flags = (fast,
    correction, ahead)``. Returns ``status (m,)``, ``due (m, 2)`` and ``predicted (m,
    2, 2)``."""
    phase, pk, end_k, t_start, duration, end, incoming, catch_ball = plan[:8]
    holder, caught, released, q, v = world
    m_time, m_ball, m_ball_vel = measured
    dt, g, reaim, latency, tolerance = (
        constants[0], constants[1], constants[2], constants[3], constants[4],
    )  # fmt: skip
    release_after = constants[5]
    toss, go_down, catch = int(constants[6]), int(constants[7]), int(constants[8])
    fast, correction, ahead = flags
    m = envs.shape[0]
    status = np.zeros(m, dtype=np.int64)
    due = np.zeros((m, 2), dtype=np.bool_)
    predicted = np.zeros((m, 2, 2))
    for j in range(m):
        i = envs[j]
        invalid = False
        for c in range(4):
            x = actions[j, c]
            if not math.isfinite(x):
                invalid = True
            a_out[j, c] = 0.0 if math.isnan(x) else (-1.0 if x < -1.0 else (1.0 if x > 1.0 else x))
        a_out[j, 4] = 1.0 if invalid else 0.0
        event = not fast or caught[i, 0] >= 0 or caught[i, 1] >= 0
        for h in range(2):
            held = holds(holder, i, h)
            ph, k, inc = phase[i, h], pk[i, h], incoming[i, h]
            was_caught, was_released = caught[i, h] >= 0, released[i, h] >= 0
            if (
                ((ph == go_down or ph == catch) and held)
                or (
                    ph == catch
                    and inc >= 0
                    and not held
                    and not was_caught
                    and (inc != catch_ball[i, h] or k * dt > duration[i, h] + reaim)
                )
                or (ph == toss and was_released)
                or (ph == catch and was_caught)
                or (end_k[i, h] >= 0 and k >= end_k[i, h])
            ):
                event = True
        if event:
            status[j] = 1
            continue
        for h in range(2):
            if not correction or phase[i, h] != catch or holds(holder, i, h):
                continue
            inc = incoming[i, h]
            if inc >= 0:
                bx, bz = m_ball[i, inc, 0], m_ball[i, inc, 1]
                vx, vz = m_ball_vel[i, inc, 0], m_ball_vel[i, inc, 1]
                if ahead and holder[i, inc] < 0:  # predict_forward(p, v, latency)
                    s = latency - 0.0
                    bx, bz = bx + vx * s, bz + vz * s - 0.5 * g * s * s
                    vz = vz - g * s
            else:
                bx, bz = q[i][2 * h], q[i][2 * h + 1]
                vx, vz = v[i][2 * h], v[i][2 * h + 1]
            if h == 1:  # the left hand's own frame
                bx, vx = -bx, -vx
            s = t_start[i, h] + duration[i, h] - m_time[i]
            if s <= dt:
                continue
            px = bx + vx * (s - 0.0)
            pz = bz + vz * (s - 0.0) - 0.5 * g * (s - 0.0) * (s - 0.0)
            if py_hypot(px - end[i, h, 0], pz - end[i, h, 1]) > tolerance:
                due[j, h] = True
                predicted[j, h, 0], predicted[j, h, 1] = px, pz
        if due[j, 0] or due[j, 1]:
            status[j] = 2
            continue
        for h in range(2):
            tx, tz, armed = advance(i, h, plan, dt, release_after, toss)
            aim(i, h, -tx if h == 1 else tx, tz, armed, a_out[j], phase, residual, command)
    return status, due, predicted


def cascade_advance(
    rows: Any, plan: Any, constants: Any, a_out: Any, residual: Any, command: Any
) -> None:
    """:func:`advance` and :func:`aim` for both hands of ``rows`` (their corrections
    made), with their actions ``a_out (r, 5)``; ``constants`` as :func:`cascade_command`
    takes them."""
    dt, release_after, toss = constants[0], constants[5], int(constants[6])
    for j in range(rows.shape[0]):
        i = rows[j]
        for h in range(2):
            tx, tz, armed = advance(i, h, plan, dt, release_after, toss)
            aim(i, h, -tx if h == 1 else tx, tz, armed, a_out[j], plan[0], residual, command)


def cascade_aim(
    rows: Any, targets: Any, armed: Any, a_out: Any, phase: Any, residual: Any, command: Any
) -> None:
    """:func:`aim` for both hands of ``rows`` with the controllers' ``targets (r, 2, 2)``
    (world frame) and ``armed (r, 2)`` (their commands in Python)."""
    for j in range(rows.shape[0]):
        for h in range(2):
            tx, tz = targets[j, h, 0], targets[j, h, 1]
            aim(rows[j], h, tx, tz, armed[j, h], a_out[j], phase, residual, command)


def cascade_finish(
    envs: Any,
    worlds: Any,
    world: Any,
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
    """The rest of Cascade-v0's control period for each world ``i = envs[j]``:

    * the releases (hand 0, then hand 1): a released ball's velocity (its hand's) turned
      and scaled by the next row of ``release = (noise (N, R, 2), at (N,), std (2,):
      speed, angle (rad))``, drawn ahead from the world's generator, when a std is not
      zero (:func:`~motion_envs.models.juggling.perturb_release`'s numbers), written into
      the world (``worlds = (qpos, qvel)`` views per world; ``world = (holder, dropped,
      k, caught, released)``);
    * the sensors (:meth:`~motion_envs.models.juggling.CascadeSensor.measure`): ``sensor
      = (ring (S, N, B, 5), slot (1,), noise (N, R, 4), at (N,), std (4,))``; the delay
      line takes each true ball ``(x, z, vx, vz, held)`` at the next slot (``slot[0]``
      advanced); its measurement is the
      true state while held, else the oldest entry, plus the next row of noise (drawn
      ahead from the sensors' generator, ball by ball) times ``std`` when that entry was
      flying and the sensor is noisy;
    * what the controller sees next (``measured = (time, ball, ball_vel, history)``, the
      history shifted by one measurement, newest first), the catches and tosses
      ``counts (N, 2)``, the episode's end;
    * the hands' mean human-likeness (:func:`hand_likeness`, own frame; ``likeness =
      (trees, stack)``), the reward terms and the reward (``scalars = (dt, likeness_tau,
      w_catch, w_drop, w_likeness, w_action, max_catches, time_limit, noisy)``) with the
      action's squared norm ``a_out[j, 5]``;
    * the observation (:func:`cascade_observe`) into ``obs[j]`` and the row ``out[j]``
      (:data:`OUT_COLUMNS`, then the hands' and balls' ``x, z``).

    Returns the number of worlds with fewer rows of noise drawn ahead left than a period
    may take (one per ball, one per hand: to be drawn again before the next period)."""
    qs, vs = worlds
    holder, dropped_w, k, caught_w, released_w = world
    ring, slot_at, noise, noise_at, noise_std = sensor
    slot = (slot_at[0] + 1) % ring.shape[0]  # the ring's newest entry: this period's
    if envs.shape[0] > 0:  # (a call with no world, compiling the kernel, changes nothing)
        slot_at[0] = slot
    r_noise, r_at, r_std = release
    trees, stack = likeness
    m_time, m_ball, m_ball_vel, history = measured
    dt, tau = scalars[0], scalars[1]
    w_catch, w_drop, w_like, w_act = scalars[2], scalars[3], scalars[4], scalars[5]
    max_catches, time_limit, noisy = scalars[6], scalars[7], scalars[8] > 0.0
    scatter = r_std[0] != 0 or r_std[1] != 0
    old = (slot + 1) % ring.shape[0]
    nb, n_hist = holder.shape[1], history.shape[2]
    phase = plan[0]
    used_up = 0
    for j in range(envs.shape[0]):
        i = envs[j]
        q, v = qs[i], vs[i]
        for h in range(2):  # the releases (perturb_release)
            b = released_w[i, h]
            if b < 0 or not scatter:
                continue
            r = r_at[i]
            factor = 1.0 + r_std[0] * r_noise[i, r, 0]
            theta = r_std[1] * r_noise[i, r, 1]
            c, s = math.cos(theta), math.sin(theta)
            ux, uz = v[2 * h], v[2 * h + 1]
            v[4 + 2 * b] = (c * ux - s * uz) * factor
            v[5 + 2 * b] = (s * ux + c * uz) * factor
            r_at[i] = r + 1
        t = k[i] * dt
        m_time[i] = t
        dropped = False
        for b in range(nb):  # the sensors, what the controller sees, the history
            held = holder[i, b] >= 0
            x, z, vx, vz = q[4 + 2 * b], q[5 + 2 * b], v[4 + 2 * b], v[5 + 2 * b]
            ring[slot, i, b, 0], ring[slot, i, b, 1] = x, z
            ring[slot, i, b, 2], ring[slot, i, b, 3] = vx, vz
            ring[slot, i, b, 4] = 1.0 if held else 0.0
            if not held:
                x, z = ring[old, i, b, 0], ring[old, i, b, 1]
                vx, vz = ring[old, i, b, 2], ring[old, i, b, 3]
                if ring[old, i, b, 4] == 0.0 and noisy:
                    r = noise_at[i]
                    x += noise_std[0] * noise[i, r, 0]
                    z += noise_std[1] * noise[i, r, 1]
                    vx += noise_std[2] * noise[i, r, 2]
                    vz += noise_std[3] * noise[i, r, 3]
                    noise_at[i] = r + 1
            m_ball[i, b, 0], m_ball[i, b, 1] = x, z
            m_ball_vel[i, b, 0], m_ball_vel[i, b, 1] = vx, vz
            for c in range(n_hist - 1, 3, -1):
                history[i, b, c] = history[i, b, c - 4]
            history[i, b, 0], history[i, b, 1] = x, z
            history[i, b, 2], history[i, b, 3] = vx, vz
            if dropped_w[i, b]:
                dropped = True
        if (noisy and noise_at[i] > noise.shape[1] - nb) or (
            scatter and r_at[i] > r_noise.shape[1] - 2
        ):  # fewer rows left than the next period may take
            used_up += 1
        caught = 0
        for h in range(2):
            if caught_w[i, h] >= 0:
                caught += 1
            if released_w[i, h] >= 0:
                counts[i, 1] += 1
        counts[i, 0] += caught
        like = 0.0
        for h in range(2):
            sign = -1.0 if h == 1 else 1.0
            point = (q[2 * h] * sign, q[2 * h + 1] * 1.0, v[2 * h] * sign, v[2 * h + 1] * 1.0)
            like = like + hand_likeness(trees, phase[i, h], point, tau, stack) / 2
        # the reward (LevelsEnvMixin._rewards' expression)
        r_catch = w_catch * caught
        r_drop = -w_drop * (1.0 if dropped else 0.0)
        r_like = -w_like * like
        r_act = -w_act * a_out[j, 5]
        row = out[j]
        row[0] = r_catch + r_drop + r_like + r_act
        row[1], row[2], row[3], row[4], row[5] = r_catch, r_drop, r_like, r_act, like
        row[6], row[7], row[8], row[9] = t, caught, counts[i, 0], counts[i, 1]
        row[10], row[11] = phase[i, 0], phase[i, 1]
        row[12] = 1.0 if holds(holder, i, 0) else 0.0
        row[13] = 1.0 if holds(holder, i, 1) else 0.0
        row[14] = a_out[j, 4]
        # the episode's end: a drop, else max_catches catches or the time limit
        row[15] = 1.0 if dropped else 0.0
        row[16] = 1.0 if not dropped and (counts[i, 0] >= max_catches or t >= time_limit) else 0.0
        for c in range(4 + 2 * nb):
            row[_HANDS + c] = q[c]
        cascade_observe(i, obs[j], (q, v, holder, history), plan, bounds, dt)
    return used_up


def cascade_period(envs: Any, period: Any, rest: Any) -> int:
    """The worlds' control period (:func:`~motion_envs.envs.juggling._period.world_periods`
    with the arguments ``period`` after ``envs``), then :func:`cascade_finish` (with the
    arguments ``rest`` after ``envs``): one call for a batch whose worlds are stepped in
    one thread."""
    (links, ball_geoms, target, armed, ref, vref, z_before, holder, thrower, left, dropped,
     k, constants, caught, released) = period  # fmt: skip
    world_periods(
        envs, links, ball_geoms, target, armed, ref, vref, z_before, holder, thrower, left,
        dropped, k, constants, caught, released,
    )  # fmt: skip
    return cascade_finish(envs, *rest)


def cascade_observe(i: int, row: Any, true: Any, plan: Any, bounds: Any, dt: float) -> None:
    """World ``i``'s observation into ``row`` (float32; see ``CascadeEnv``), clipped to
    ``bounds = (low, high)``: per hand its true state, whether it holds a ball, its phase
    one-hot, the time in the phase, the plan's duration, the next target and the plan's
    end (world frame); per ball its holder; the measurement history.

    ``true = (q, v, holder, history)`` (``q, v`` world ``i``'s ``qpos``, ``qvel``);
    ``plan`` as :func:`cascade_command` takes it, then ``(fast, phase_time, next,
    shown_end)``: the next target and the time in the phase read from the grid when
    ``fast``, else as the controller reported them."""
    q, v, holder, history = true
    phase, pk, duration, end, grid, glen = plan[0], plan[1], plan[4], plan[5], plan[8], plan[9]
    fast, phase_time, nxt, shown_end = plan[11], plan[12], plan[13], plan[14]
    low, high = bounds[0], bounds[1]
    nb, n_hist = holder.shape[1], history.shape[2]
    for h in range(2):
        o = 15 * h
        row[o], row[o + 1], row[o + 2], row[o + 3] = q[2 * h], q[2 * h + 1], v[2 * h], v[2 * h + 1]
        row[o + 4] = 1.0 if holds(holder, i, h) else 0.0
        for p in range(4):
            row[o + 5 + p] = 1.0 if p == phase[i, h] else 0.0
        row[o + 10] = duration[i, h]
        if fast:
            row[o + 9] = pk[i, h] * dt
            r = min(pk[i, h] + 1, glen[i, h] - 1)
            x, ex = grid[i, h, r, 0], end[i, h, 0]
            row[o + 11] = -x if h == 1 else x
            row[o + 12] = grid[i, h, r, 1]
            row[o + 13] = -ex if h == 1 else ex
            row[o + 14] = end[i, h, 1]
        else:
            row[o + 9] = phase_time[i, h]
            row[o + 11], row[o + 12] = nxt[i, h, 0], nxt[i, h, 1]
            row[o + 13], row[o + 14] = shown_end[i, h, 0], shown_end[i, h, 1]
    for b in range(nb):
        row[30 + 2 * b] = 1.0 if holder[i, b] == 0 else 0.0
        row[31 + 2 * b] = 1.0 if holder[i, b] == 1 else 0.0
    for b in range(nb):
        for c in range(n_hist):
            row[30 + 2 * nb + n_hist * b + c] = history[i, b, c]
    for c in range(row.shape[0]):
        if row[c] > high[c]:
            row[c] = high[c]
        if row[c] < low[c]:
            row[c] = low[c]
