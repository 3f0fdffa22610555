"""Running the analytic juggler in a juggling world, one seeded cycle at a time.

A cycle starts with the ball in the hand at the juggler's home (the mean training toss
start) and ends at the catch (``through_return=False``, what the catch rate needs) or
after the return phase; a drop, or no release within ``max_time``, ends it as a failure.
Cycle ``i`` of a run with seed ``s`` draws everything (release and tracking noise, the
juggler's random targets and durations) from ``SeedSequence(s).spawn(...)[i]``, so cycles
are independent and a run is reproducible however it is split.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from motion_envs._typing import FloatArray
from motion_envs.datasets.juggling import PHASES as PHASES_ORDER
from motion_envs.datasets.juggling import JugglingNoise, rules
from motion_envs.models.juggling._juggler import AnalyticJuggler
from motion_envs.models.juggling._world import BallisticWorld, JugglingWorld, tracked_hand

__all__ = [
    "CycleResult",
    "cycle_rng",
    "cycle_rngs",
    "run_cycle",
    "run_cycles",
    "run_cycles_fast",
]


@dataclass(frozen=True)
class CycleResult:
    """Outcome and trace of one cycle (trace arrays only when recorded)."""

    caught: bool
    dropped: bool
    released: bool
    steps: int
    corrections: int
    release_velocity: FloatArray | None = None
    times: FloatArray | None = None
    hand: FloatArray | None = None  # (K, 2) commanded = true hand
    ball: FloatArray | None = None
    phase: NDArray[np.str_] | None = None


def cycle_rngs(seed: int, n: int) -> list[tuple[np.random.Generator, np.random.Generator]]:
    """Per cycle: (world noise rng, juggler rng), independent streams."""
    out = []
    for ss in np.random.SeedSequence(seed).spawn(n):
        a, b = ss.spawn(2)
        out.append((np.random.default_rng(a), np.random.default_rng(b)))
    return out


def cycle_rng(seed: int, cycle: int) -> tuple[np.random.Generator, np.random.Generator]:
    """``cycle_rngs(seed, cycle + 1)[cycle]`` in O(1): cycle ``cycle``'s (world, juggler)
    generators, from the spawn key ``(cycle,)`` that ``SeedSequence.spawn`` gives its
    ``cycle``-th child (bit-identical streams)."""
    a, b = np.random.SeedSequence(seed, spawn_key=(cycle,)).spawn(2)
    return np.random.default_rng(a), np.random.default_rng(b)


def run_cycle(
    juggler: AnalyticJuggler,
    world: JugglingWorld,
    noise: JugglingNoise,
    rngs: tuple[np.random.Generator, np.random.Generator],
    through_return: bool = False,
    record: bool = False,
    max_time: float = 8.0,
) -> CycleResult:
    """One cycle of ``juggler`` in ``world`` (a BallisticWorld or the MuJoCo scene); the
    cycle is ``juggler``'s current episode (``juggler.plans`` etc. afterwards)."""
    world_rng, juggler_rng = rngs
    state = world.reset(juggler.home_, noise=noise, rng=world_rng)
    juggler.reset(state, juggler_rng)
    dt = juggler.task.dt
    max_steps = int(max_time / dt)
    times, hand, ball, phase = [], [], [], []
    if record:
        times.append(state.time)
        hand.append(np.asarray(juggler.home_, dtype=np.float64))
        ball.append(state.ball_pos)
        phase.append(juggler.phase)
    released = caught = False
    release_velocity = None
    k = 0
    while k < max_steps:
        k += 1
        target, armed = juggler.command(state)
        label = juggler.phase
        state = world.step(target, armed)
        if record:
            times.append(state.time)
            hand.append(np.array(target))
            ball.append(state.ball_pos)
            phase.append(label)
        if state.released:
            released = True
            release_velocity = state.ball_vel
        if state.caught:
            caught = True
            if not through_return:
                break
        if state.dropped:
            break
        if caught and juggler.phase == "toss":  # return finished, the next toss began
            break
    return CycleResult(
        caught=caught,
        dropped=bool(state.dropped),
        released=released,
        steps=k,
        corrections=len(juggler.corrections),
        release_velocity=release_velocity,
        times=np.asarray(times) if record else None,
        hand=np.asarray(hand) if record else None,
        ball=np.asarray(ball) if record else None,
        phase=np.asarray(phase, dtype=str) if record else None,
    )


def run_cycles(
    juggler: AnalyticJuggler,
    n_cycles: int,
    noise: JugglingNoise | None = None,
    seed: int = 0,
    world: JugglingWorld | None = None,
    progress: bool = False,
) -> list[CycleResult]:
    """``n_cycles`` independent seeded cycles (to the catch) in ``world``."""
    from tqdm import tqdm

    noise = noise or JugglingNoise()
    world = world if world is not None else BallisticWorld(juggler.task)
    rngs = cycle_rngs(seed, n_cycles)
    return [
        run_cycle(juggler, world, noise, r)
        for r in tqdm(rngs, desc="cycles", disable=not progress, leave=False)
    ]


def run_cycles_fast(
    juggler: AnalyticJuggler,
    n_cycles: int,
    noise: JugglingNoise | None = None,
    seed: int = 0,
    max_time: float = 8.0,
) -> list[CycleResult]:
    """:func:`run_cycles` in the pure-model world, all cycles stepped together.

    The same cycles as ``run_cycles(juggler, n_cycles, noise, seed)`` (same draws, same
    rules, same events; tested), tens of times faster: the world and the per-step part
    of the juggler are vectorised over cycles (the world's rules are the functions of
    :mod:`motion_envs.datasets.juggling.rules` on arrays); phase starts and eq. 10 corrections,
    which are rare, run one cycle at a time through each cycle's
    :class:`~motion_envs.models.juggling.JugglingController` (its public methods).
    """
    juggler.model.check_fitted()
    noise = noise or JugglingNoise()
    task = juggler.task
    options = juggler.options
    dt, g, thr, rc = task.dt, task.gravity, task.toss_threshold, task.catch_radius
    n = int(n_cycles)
    rngs = cycle_rngs(seed, n)
    world = BallisticWorld(task)
    ctls, track, factor = [], [], np.ones((n, 2))
    home = np.asarray(juggler.home_, dtype=np.float64)
    for b, (wr, jr) in enumerate(rngs):
        state = world.reset(home, noise=noise, rng=wr)
        factor[b] = world.release_factor
        track.append(world.tracking_noise)
        c = juggler.controller()
        c.reset(state, jr)
        ctls.append(c)
    tracks = None if track[0] is None else np.stack([t for t in track if t is not None])
    lmax = max(int(np.ceil(f.duration_range[1] / dt)) + 2 for f in juggler.phases_.values())
    grid = np.empty((n, lmax, 2))
    length = np.empty(n, dtype=np.int64)
    end_k = np.empty(n, dtype=np.int64)
    phase = np.zeros(n, dtype=np.int64)
    code = {p: i for i, p in enumerate(PHASES_ORDER)}
    t_end = np.empty(n)
    ends = np.empty((n, 2))

    def load(b: int) -> None:
        c = ctls[b]
        m = len(c.grid)
        grid[b, :m] = c.grid
        length[b] = m
        end_k[b] = c.end_k
        phase[b] = code[c.phase]
        t_end[b] = c.t_start + c.duration
        ends[b] = c.end

    for b in range(n):
        load(b)
    kj = np.zeros(n, dtype=np.int64)
    last0 = np.repeat(home[None], n, axis=0)
    last1 = last0.copy()
    if tracks is not None:
        last0 = tracked_hand(last0, tracks, 0)
        last1 = last0.copy()
    hand = np.repeat(home[None], n, axis=0)
    prev, prev2 = hand.copy(), hand.copy()
    ball, ball_v = hand.copy(), np.zeros((n, 2))
    held = np.ones(n, dtype=bool)
    left = np.zeros(n, dtype=bool)
    dropped = np.zeros(n, dtype=bool)
    rel = np.zeros((n, 5))
    released_ev = np.zeros(n, dtype=bool)
    caught_ev = np.zeros(n, dtype=bool)
    active = np.ones(n, dtype=bool)
    steps = np.zeros(n, dtype=np.int64)
    ever_released = np.zeros(n, dtype=bool)
    rel_vel = np.full((n, 2), np.nan)
    obs = last1.copy()
    rows = np.arange(n)
    corrections = np.zeros(n, dtype=np.int64)
    caught_out = np.zeros(n, dtype=bool)
    dropped_out = np.zeros(n, dtype=bool)
    max_steps = int(max_time / dt)
    for kw in range(1, max_steps + 1):
        time_prev = (kw - 1) * dt
        # -- the juggler's command, from the state after step kw - 1 ----------------
        switch = active & (
            ((phase == 0) & released_ev)
            | ((phase == 2) & caught_ev)
            | ((end_k >= 0) & (kj >= end_k))
        )
        for b in map(int, np.flatnonzero(switch)):
            ctls[b].next_phase(time_prev, obs[b].copy(), (last0[b], last1[b]))
            kj[b] = 0
            load(b)
        if options.correction:
            cand = active & ~switch & (phase == 2) & ~held
            if cand.any():
                s = t_end - time_prev
                px, pz, _, _ = rules.flight(
                    (0.0, ball[:, 0], ball[:, 1], ball_v[:, 0], ball_v[:, 1]), s, g
                )
                far = np.hypot(px - ends[:, 0], pz - ends[:, 1]) > options.correction_tolerance * (
                    1 - 1e-9
                )
                for b in map(int, np.flatnonzero(cand & far & (s > dt))):
                    ctls[b].k = int(kj[b])
                    if ctls[b].correct(time_prev, ball[b], ball_v[b]):
                        corrections[b] += 1
                        load(b)
        kj += 1
        target = grid[rows, np.minimum(kj, length - 1)]
        last0, last1 = last1, target
        armed = (phase == 0) & (kj * dt >= options.release_after)
        # -- the world's step (BallisticWorld.step, the same rules on the batch) --------
        t_now = kw * dt
        prev2, prev, hand = prev, hand, target
        vel = rules.hand_velocity(hand, prev, dt)
        az = rules.hand_acceleration(hand[:, 1], prev[:, 1], prev2[:, 1], dt)
        released_ev = rules.release_fires(held & armed, az, thr)
        caught_ev = np.zeros(n, dtype=bool)
        stay = held & ~released_ev
        ball = np.where(stay[:, None], hand, ball)
        ball_v = np.where(stay[:, None], vel, ball_v)
        if released_ev.any():
            bv = np.column_stack(
                rules.release_velocity(vel[:, 0], vel[:, 1], factor[:, 0], factor[:, 1])
            )
            rel[released_ev] = np.column_stack([np.full(n, t_now), hand, bv])[released_ev]
            ball[released_ev] = hand[released_ev]
            ball_v[released_ev] = bv[released_ev]
            held[released_ev] = False
            left[released_ev] = False
            rel_vel[released_ev & active] = bv[released_ev & active]
            ever_released |= released_ev & active
        fly = ~held & ~released_ev
        ball0 = ball.copy()
        if fly.any():
            bx, bz, bvx, bvz = rules.flight(
                (rel[:, 0], rel[:, 1], rel[:, 2], rel[:, 3], rel[:, 4]), t_now, g
            )
            ball[fly] = np.column_stack([bx, bz])[fly]
            ball_v[fly] = np.column_stack([bvx, bvz])[fly]
            dist = np.hypot(hand[:, 0] - ball[:, 0], hand[:, 1] - ball[:, 1])
            swept = rules.swept_distance(
                prev[:, 0] - ball0[:, 0],
                prev[:, 1] - ball0[:, 1],
                hand[:, 0] - ball[:, 0],
                hand[:, 1] - ball[:, 1],
            )
            catch = fly & rules.catch_fires(swept, left, dropped, rc)
            left |= fly & rules.has_left(dist, left, catch, rc)
            caught_ev = catch
            held |= catch
            ball[catch] = hand[catch]
            ball_v[catch] = vel[catch]
            dropped |= fly & rules.drop_fires(ball[:, 1], held, task.floor_z)
        obs = tracked_hand(hand, tracks, kw)
        steps[active] = kw
        fin = active & (caught_ev | dropped)
        caught_out[fin] = caught_ev[fin]
        dropped_out[fin] = dropped[fin]
        active &= ~fin
        if not active.any():
            break
    out = []
    for b in range(n):
        out.append(
            CycleResult(
                caught=bool(caught_out[b]),
                dropped=bool(dropped_out[b]),
                released=bool(ever_released[b]),
                steps=int(steps[b]),
                corrections=int(corrections[b]),
                release_velocity=rel_vel[b] if ever_released[b] else None,
            )
        )
    return out
