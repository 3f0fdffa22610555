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

from motion_envs.models.juggling_juggler import AnalyticJuggler
from motion_envs.models.juggling_task import JugglingNoise
from motion_envs.models.juggling_world import BallisticWorld

__all__ = ["CycleResult", "cycle_rngs", "run_cycle", "run_cycles"]

FloatArray = NDArray[np.float64]


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


def run_cycle(
    juggler: AnalyticJuggler,
    world: object,
    noise: JugglingNoise,
    rngs: tuple[np.random.Generator, np.random.Generator],
    through_return: bool = False,
    record: bool = False,
    max_time: float = 8.0,
) -> CycleResult:
    """One cycle of ``juggler`` in ``world`` (a BallisticWorld or the MuJoCo scene)."""
    world_rng, juggler_rng = rngs
    state = world.reset(juggler.home_, noise=noise, rng=world_rng)  # type: ignore[attr-defined]
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
    for k in range(1, max_steps + 1):
        target, armed = juggler.command(state)
        label = juggler.phase
        state = world.step(target, armed)  # type: ignore[attr-defined]
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
    world: object | None = None,
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
