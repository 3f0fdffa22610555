"""SIMULATED juggling demonstrations: a seeded model of a person doing the paper's task.

The paper's recordings (Polhemus tracker, 200 Hz, one user) are not public. This module
simulates a person performing the virtual task of section III-A, cycle after cycle:

1. **toss**: from rest at home the person plans a minimum-jerk (quintic) reach upward
   and to the left that stops sharply upwards (zero vertical end velocity, a vertical end
   acceleration of ``brake`` m/s^2, still moving left at ``toss_vx``); the virtual world
   releases the ball at the first sample where the vertical hand acceleration (second
   backward difference of the tracked signal) falls below ``-toss_threshold``; the ball
   leaves with the hand's velocity;
2. **go down**: a quintic from the hand's state at the release (position, velocity,
   acceleration) to the person's bottom point, at rest; its duration is chosen so that
   the catch reach will take the person's preferred time;
3. **catch**: the person picks a catch height (a style distance below the apex) and aims
   a quintic from the bottom at the point where the real flight crosses it, arriving when
   the ball does; the first aim carries a perception error, re-planned to the real
   intercept after a reaction delay of 150-250 ms (a quintic from the current state);
   the catch is the first sample where the hand centre is within ``catch_radius`` of
   the ball centre;
4. **return**: a quintic from the hand's state at the catch to home, at rest.

Per person (seeded): home, bottom, toss height and direction, brake, speed, catch drop,
reaction delay. Per cycle: small variations of each, physiological tremor (two 8-12 Hz
sinusoids of ~0.1 mm) and sensor noise on the recorded hand (white, 0.05 mm). Phase
labels are the true boundaries (release sample, arrival at the bottom, catch sample,
arrival at home). The generator uses only quintic polynomials and the ballistic closed
form: it does NOT use the sine-series model, so fitting that model to these data is a
real test. Every generated set has ``simulated = True``.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from motion_envs._typing import FloatArray
from motion_envs.datasets.juggling import rules
from motion_envs.datasets.juggling._records import JugglingDemos, JugglingRecording
from motion_envs.datasets.juggling._task import JugglingTask, ballistic_position
from motion_envs.geometry.minimum_jerk import quintic, quintic_evaluate

__all__ = ["PersonStyle", "draw_person", "generate_demonstrations"]


@dataclass(frozen=True)
class PersonStyle:
    """A simulated person's style (SI units; see the module docstring)."""

    home: tuple[float, float]
    bottom: tuple[float, float]  # offset from home
    toss: tuple[float, float]  # toss plan end offset from home (dx < 0: to the left)
    brake: float  # m/s^2, vertical end acceleration of the toss plan (negative)
    toss_vx: float  # m/s, horizontal end velocity of the toss plan (negative: to the left)
    toss_time: float  # s, toss plan duration
    catch_drop: float  # m, catch height below the apex
    catch_time: float  # s, preferred catch reach
    return_time: float  # s
    reaction: float  # s, reaction delay of the catch correction
    aim_error: float  # m, std of the first aim of the catch
    variation: float  # relative per-cycle variation of durations
    spread: float  # m, per-cycle std of the points


def draw_person(rng: np.random.Generator) -> PersonStyle:
    """A person's style drawn from the generator's population (seeded by ``rng``)."""
    u = rng.uniform
    speed = u(0.93, 1.07)
    return PersonStyle(
        home=(0.2 + u(-0.03, 0.03), 1.0 + u(-0.03, 0.03)),
        bottom=(u(-0.12, -0.04), u(-0.3, -0.22)),
        toss=(u(-0.12, -0.06), u(0.36, 0.44)),
        brake=u(-11.0, -8.5),
        toss_vx=u(-0.4, -0.3),
        toss_time=u(0.9, 0.98) * speed,
        catch_drop=u(0.46, 0.54),
        catch_time=u(0.78, 0.86) * speed,
        return_time=u(0.8, 0.95) * speed,
        reaction=u(0.15, 0.25),
        aim_error=u(0.015, 0.03),
        variation=u(0.02, 0.04),
        spread=u(0.01, 0.02),
    )


class _Session:
    """Builds one person's continuous recording, sample by sample (the grid ``k dt``)."""

    def __init__(self, task: JugglingTask, style: PersonStyle, rng: np.random.Generator) -> None:
        self.task, self.style, self.rng = task, style, rng
        self.hand: list[FloatArray] = []  # true hand incl. tremor
        self.ball: list[FloatArray] = []
        self.phase: list[str] = []
        freqs = rng.uniform(8.0, 12.0, size=(2, 2))
        phases = rng.uniform(0, 2 * np.pi, size=(2, 2))
        amps = rng.uniform(0.5e-4, 1.5e-4, size=(2, 2))
        self.tremor = (freqs, phases, amps)
        self.start = np.asarray(style.home, dtype=np.float64)
        # styles are for the default gravity; under gravity g the same sizes take
        # sqrt(g0 / g) of the time (lengths fixed: T ~ sqrt(L / g)), the reaction delay not
        self.time_scale = float(np.sqrt(JugglingTask().gravity / task.gravity))

    def _tremor(self, t: FloatArray) -> FloatArray:
        f, ph, a = self.tremor
        arg = 2 * np.pi * f[None] * t[:, None, None] + ph[None]
        return np.sum(a[None] * np.sin(arg), axis=2)  # (K, 2)

    def _append(self, c: FloatArray, t0: float, k_from: int, k_to: int, phase: str) -> None:
        dt = self.task.dt
        k = np.arange(k_from, k_to)
        t = k.astype(np.float64) * dt
        y = quintic_evaluate(c, t - t0) + self._tremor(t)
        self.hand.extend(y)
        self.phase.extend([phase] * len(k))

    def _vary(self, x: float) -> float:
        return x * (1 + self.style.variation * self.rng.standard_normal())

    def _point(self, base: tuple[float, float]) -> FloatArray:
        return np.asarray(base) + self.style.spread * self.rng.standard_normal(2)

    def cycle(self) -> bool:
        """Append one cycle; returns False (nothing appended) if the toss never fired."""
        task, st, dt = self.task, self.style, self.task.dt
        k0 = len(self.hand)
        t0 = k0 * dt
        z2 = np.zeros(2)
        start = self.start
        # 1. toss: plan to the top, stop sharply; release at the acceleration threshold
        top = start + (np.asarray(st.toss) * (1 + st.variation * self.rng.standard_normal(2)))
        ts = self.time_scale
        t_toss = self._vary(st.toss_time) * ts
        v_top = np.array([self._vary(st.toss_vx) / ts, 0.0])
        brake = np.array([0.0, st.brake / ts**2])
        c_toss = quintic(start, z2, z2, top, v_top, brake, t_toss)
        n_plan = int(np.floor(t_toss / dt))
        k = np.arange(k0, k0 + n_plan + 1)
        tk = k.astype(np.float64) * dt
        y = quintic_evaluate(c_toss, tk - t0) + self._tremor(tk)
        prev = np.asarray(self.hand[-2:]) if k0 >= 2 else np.repeat(y[:1], 2, axis=0)
        full = np.concatenate([prev, y])
        az = rules.hand_acceleration(full[2:, 1], full[1:-1, 1], full[:-2, 1], dt)
        fired = np.flatnonzero(rules.release_fires(np.arange(len(k)) > 0, az, task.toss_threshold))
        if fired.size == 0:
            return False
        j = int(fired[0])
        k_rel = k0 + j
        t_rel = k_rel * dt
        self._append(c_toss, t0, k0, k_rel, "toss")
        self.ball.extend(self.hand[k0:k_rel])
        p_rel = y[j]
        v_ball = rules.hand_velocity(y[j], full[j + 1], dt)  # as the virtual world
        # 2. the flight, the catch point and the go-down timing
        g = task.gravity
        apex = p_rel[1] + max(v_ball[1], 0.0) ** 2 / (2 * g)
        catch_z = apex - self._vary(st.catch_drop)
        disc = v_ball[1] ** 2 + 2 * g * (p_rel[1] - catch_z)
        s_catch = (v_ball[1] + np.sqrt(max(disc, 0.0))) / g
        t_c = t_rel + s_catch
        target = ballistic_position(p_rel, v_ball, s_catch, g)
        t_catch_reach = self._vary(st.catch_time) * ts
        k_bottom = round((t_c - t_catch_reach) / dt)
        k_bottom = max(k_bottom, k_rel + int(0.5 * ts / dt))
        k_bottom = min(k_bottom, int(np.floor(t_c / dt)) - 4)
        s_rel = t_rel - t0
        p_r, v_r, a_r = (quintic_evaluate(c_toss, np.array(s_rel), o) for o in range(3))
        bottom = self._point((start[0] + st.bottom[0], start[1] + st.bottom[1]))
        c_down = quintic(p_r, v_r, a_r, bottom, z2, z2, (k_bottom - k_rel) * dt)
        self._append(c_down, t_rel, k_rel, k_bottom, "go_down")
        # 3. catch: first aim with a perception error, corrected after the reaction delay
        t_b = k_bottom * dt
        aim = target + st.aim_error * self.rng.standard_normal(2)
        c_aim = quintic(bottom, z2, z2, aim, z2, z2, t_c - t_b)
        # the correction comes after the reaction delay, at the latest 60 % into the reach
        t_fix = t_b + min(self._vary(st.reaction), 0.6 * (t_c - t_b))
        q = [quintic_evaluate(c_aim, np.array(t_fix - t_b), o) for o in range(3)]
        c_fix = quintic(q[0], q[1], q[2], target, z2, z2, t_c - t_fix)
        k_fix = int(np.ceil(t_fix / dt))
        self._append(c_aim, t_b, k_bottom, k_fix, "catch")
        k_end = int(np.ceil(t_c / dt)) + 1
        self._append(c_fix, t_fix, k_fix, k_end, "catch")
        hand = np.asarray(self.hand[k_rel:])
        kk = np.arange(k_rel, k_rel + len(hand))
        ball = ballistic_position(p_rel, v_ball, kk * dt - t_rel, g)
        dist = np.linalg.norm(hand - ball, axis=1)
        left = np.maximum.accumulate(dist > task.catch_radius)
        touch = np.flatnonzero(
            rules.catch_fires(dist, left, False, task.catch_radius) & (kk >= k_bottom)
        )
        if touch.size == 0:  # cannot happen: the hand reaches the ball centre at t_c
            raise RuntimeError("simulated catch missed the ball")
        k_touch = k_rel + int(touch[0])
        del self.hand[k_touch:]
        del self.phase[k_touch:]
        self.ball.extend(ball[: k_touch - k_rel])
        # 4. return home, from the catch state
        t_touch = k_touch * dt
        c_last, t_last = (c_fix, t_fix) if t_touch >= t_fix else (c_aim, t_b)
        q = [quintic_evaluate(c_last, np.array(t_touch - t_last), o) for o in range(3)]
        home_next = self._point(st.home)
        k_home = k_touch + round(self._vary(st.return_time) * ts / dt)
        c_ret = quintic(q[0], q[1], q[2], home_next, z2, z2, (k_home - k_touch) * dt)
        self._append(c_ret, t_touch, k_touch, k_home, "return")
        self.start = home_next
        self.ball.extend(self.hand[k_touch:k_home])
        return True


def generate_demonstrations(
    n_cycles: int = 50,
    n_persons: int = 1,
    seed: int = 0,
    task: JugglingTask | None = None,
    sensor_noise: float = 5e-5,
    styles: list[PersonStyle] | None = None,
) -> JugglingDemos:
    """SIMULATED demonstrations: ``n_persons`` recordings of ``n_cycles`` cycles each.

    The defaults match the paper's sizes (50 examples per phase, 150-200 samples each at
    200 Hz). ``sensor_noise`` is the std (m) of the white noise added to the recorded hand
    (the virtual world, and so the toss trigger, sees the hand without it). Seeded: the
    same arguments give the same arrays.
    """
    if n_cycles < 1 or n_persons < 1:
        raise ValueError(f"n_cycles and n_persons must be >= 1; got {n_cycles}, {n_persons}")
    if sensor_noise < 0:
        raise ValueError(f"sensor_noise must be >= 0; got {sensor_noise}")
    task = task or JugglingTask()
    root = np.random.SeedSequence(seed)
    recordings = []
    for p, ss in enumerate(root.spawn(n_persons)):
        rng = np.random.default_rng(ss)
        style = styles[p] if styles is not None else draw_person(rng)
        session = _Session(task, style, rng)
        done = tries = 0
        while done < n_cycles:
            tries += 1
            if tries > 3 * n_cycles:
                raise RuntimeError(
                    f"person {p}: the toss threshold {task.toss_threshold} m/s^2 fired in only "
                    f"{done} of {tries} tosses; the style cannot toss in this task"
                )
            if session.cycle():
                done += 1
            else:  # the person tries again with a sharper stop
                session.style = replace(session.style, brake=session.style.brake * 1.1)
        hand = np.asarray(session.hand)
        t = np.arange(len(hand), dtype=np.float64) * task.dt
        recorded = hand + sensor_noise * rng.standard_normal(hand.shape)
        recordings.append(
            JugglingRecording(
                name=f"simulated-person-{p}",
                t=t,
                hand=recorded,
                ball=np.asarray(session.ball),
                phase=np.asarray(session.phase, dtype=str),
                person=f"simulated-person-{p}",
            )
        )
    return JugglingDemos(
        name=f"simulated-juggling(seed={seed})",
        recordings=tuple(recordings),
        simulated=True,
        task=task,
    )
