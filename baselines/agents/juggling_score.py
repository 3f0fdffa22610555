"""Juggling-v0's criteria for agents: catch rate, and the hand's distance from people.

The reaching environments score a policy by the papers' criterion on trajectories of a
data split. Juggling-v0 has no trajectories to replay: an episode is a seeded run of the
juggling world (release noise, tracking noise, the juggler's random phase ends). Its
splits are therefore *seed ranges*, disjoint from any seed training uses:

* ``"val"``: episodes reset with seeds ``VAL_SEED + i``; the hand is compared with the
  *training* demonstrations (those the analytic juggler was fitted on);
* ``"test"``: seeds ``TEST_SEED + i``; the hand is compared with the *held-out*
  demonstrations (the juggler never saw them);
* ``"train"``: seeds ``TRAIN_SEED + i`` (a sample of what training sees), training
  demonstrations.

``motion-bench train`` resets its environments with seeds ``seed .. seed + n_envs - 1``
(SB3's ``VecEnv.seed``) and then with seeds drawn from the environments' generators;
``VAL_SEED`` and ``TEST_SEED`` lie above any seed the command line accepts for training
runs of practical size (< 10^9), so validation and test episodes are never trained on.

For each episode :func:`juggling_episodes` records

* ``tosses`` (releases) and ``catches``; the **catch rate** is ``sum(catches) /
  sum(tosses)`` over the episodes and the **criterion** (lower is better, as the reaching
  criterion) is the drop rate ``1 - catch rate``;
* the hand's path, cut into phase segments by the juggler's phase labels (a run of one
  label plus the first sample of the next, as the demonstrations are cut); each complete
  segment is resampled to ``N_POINTS`` points of normalised time ``tau_k`` and compared
  with every demonstration segment of the same phase (also resampled) *retargeted* to
  the segment's own start and end (the demonstration's departure from its straight line,
  added to the segment's straight line; ``motion-bench juggling`` retargets the same
  way). The retargeted demonstration and the segment share their end points, so the
  comparison is of shape, not of where the release noise sent the ball: with ``r(y)_k =
  y_k - (y_0 + tau_k (y_N - y_0))`` a path's departure from its line, the segment's
  **deviation** is the distance to the *nearest* demonstration, ``min_j max_k |r(hand)_k
  - r(demo_j)_k|`` (Lippi's max-over-time error against the closest human movement). The
  **deviation** of a policy is the median over all complete segments of all episodes, in
  metres.

The nominal (zero action) is scored on the same seeds, so ``deviation_ratio = deviation /
nominal deviation`` is the issue's "hand deviation from held-out demonstrations relative
to the nominal's".
"""

from __future__ import annotations

import functools
import math
from collections.abc import Callable, Collection, Mapping
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, Protocol

import numpy as np
from numpy.typing import NDArray

from motion_envs._typing import FloatArray
from motion_envs.datasets.juggling import (
    PHASES,
    SPLIT_SEEDS,
    departure_from_line,
    episode_seeds,
    resample_path,
)

if TYPE_CHECKING:
    from baselines.stats import Difference
    from motion_envs.datasets.juggling import JugglingDemos

__all__ = [
    "DEFAULT_EPISODES",
    "JUGGLING_ENV_IDS",
    "N_POINTS",
    "JugglingEpisodes",
    "SegmentDeviations",
    "TossCounts",
    "catch_rate_comparison",
    "catch_rate_difference",
    "catch_rate_interval",
    "demonstration_paths",
    "departure_from_line",
    "deviation_interval",
    "episodes_from_paths",
    "is_juggling",
    "juggling_episodes",
    "phase_departures",
    "play_until_ended",
    "pooled_catch_rate",
    "segment_deviations",
    "split_episode_count",
]

Policy = Callable[[NDArray[np.float32]], NDArray[np.floating]]

#: Environment ids scored by this module.
JUGGLING_ENV_IDS: tuple[str, ...] = (
    "MotionEnvs/Juggling-v0",
    "MotionEnvs/Juggling-v1",
    "MotionEnvs/Juggling-v2",
)
#: Episodes per split when not given.
DEFAULT_EPISODES: Mapping[str, int] = {"train": 20, "val": 20, "test": 50}
#: Points of normalised time a phase segment is resampled to.
N_POINTS = 50


def is_juggling(env_id: str) -> bool:
    """True for the environments this module scores."""
    return env_id in JUGGLING_ENV_IDS


@functools.lru_cache(maxsize=8)
def _demonstration_paths(
    data: str | None, gravity: float | None, split: str
) -> dict[str, FloatArray]:
    from motion_envs.datasets.juggling import JugglingTask
    from motion_envs.models.juggling import juggler_demonstrations

    task = JugglingTask() if gravity is None else JugglingTask(gravity=float(gravity))
    demos, train, test = juggler_demonstrations(data, task)
    return phase_departures(demos, test if split == "test" else train)


def phase_departures(
    demos: JugglingDemos, cycles: Collection[tuple[int, int]]
) -> dict[str, FloatArray]:
    """Per phase of :data:`~motion_envs.datasets.juggling.PHASES`, the departures from
    their lines (:func:`departure_from_line`) of the segments ``(m, N_POINTS, 2)`` of
    ``demos`` whose ``(recording, cycle)`` is in ``cycles``, each resampled to
    :data:`N_POINTS` points of normalised time: what :func:`segment_deviations` compares
    a hand's segments with."""
    out: dict[str, FloatArray] = {}
    for phase in PHASES:
        segs = [s for s in demos.segments(phase) if (s.recording, s.cycle) in cycles]
        out[phase] = departure_from_line(np.stack([s.resampled(N_POINTS) for s in segs]))
    return out


def demonstration_paths(env_kwargs: Mapping[str, Any], split: str) -> dict[str, FloatArray]:
    """Per phase, the departures from their lines (:func:`departure_from_line`) of the
    demonstration segments ``(m, N_POINTS, 2)`` a split is compared with: held-out
    demonstrations for ``"test"``, training ones otherwise."""
    if split not in SPLIT_SEEDS:
        raise ValueError(f"split must be one of {sorted(SPLIT_SEEDS)}; got {split!r}")
    data = env_kwargs.get("data")
    gravity = env_kwargs.get("gravity")
    return _demonstration_paths(
        None if data is None else str(data), None if gravity is None else float(gravity), split
    )


def segment_deviations(
    times: FloatArray, hand: FloatArray, phases: list[str], demos: Mapping[str, FloatArray]
) -> list[tuple[str, float]]:
    """``(phase, deviation)`` of every complete phase segment of one episode's hand path.

    ``times (n,)``, ``hand (n, 2)`` and ``phases`` (n labels) are sampled at the episode's
    steps, sample 0 being the reset state. A segment is a run of one label plus the first
    sample of the next label; the last run (not followed by another label) is incomplete
    and skipped, as is a run of fewer than 3 samples. ``demos`` maps a phase to the
    demonstrations' departures from their lines (:func:`demonstration_paths`).
    """
    out: list[tuple[str, float]] = []
    start = 0
    for k in range(1, len(phases) + 1):
        if k < len(phases) and phases[k] == phases[start]:
            continue
        if k == len(phases):
            break
        stop = k  # the first sample of the next phase closes the segment
        if stop - start >= 2 and phases[start] in demos:
            path = resample_path(times[start : stop + 1], hand[start : stop + 1], N_POINTS)
            path = departure_from_line(path)
            dist = np.linalg.norm(demos[phases[start]] - path[None], axis=-1)  # (m, N)
            out.append((phases[start], float(dist.max(axis=1).min())))
        start = k
    return out


@dataclass(frozen=True)
class JugglingEpisodes:
    """Per-episode counts and per-segment deviations of a policy on a split."""

    seeds: NDArray[np.int64]
    tosses: NDArray[np.int64]
    catches: NDArray[np.int64]
    dropped: NDArray[np.bool_]
    segment_phase: NDArray[np.str_]
    segment_episode: NDArray[np.int64]
    segment_deviation: FloatArray

    @property
    def catch_rate(self) -> float:
        """Catches per toss over all episodes."""
        return float(self.catches.sum() / max(int(self.tosses.sum()), 1))

    @property
    def criterion(self) -> float:
        """Drop rate per toss, ``1 - catch_rate`` (lower is better)."""
        return 1.0 - self.catch_rate

    @property
    def deviation(self) -> float:
        """Median over complete phase segments of the distance (m) to the nearest
        demonstration of the split."""
        return float(np.median(self.segment_deviation))

    def phase_deviation(self, phase: str) -> float:
        """:attr:`deviation` over the segments of one phase."""
        return float(np.median(self.segment_deviation[self.segment_phase == phase]))

    def episode_deviation(self) -> FloatArray:
        """Per episode, the median deviation of its segments (NaN without segments)."""
        out = np.full(self.seeds.size, np.nan)
        for i in range(self.seeds.size):
            d = self.segment_deviation[self.segment_episode == i]
            if d.size:
                out[i] = np.median(d)
        return out


def juggling_episodes(
    policy: Policy | None,
    env_id: str,
    env_kwargs: Mapping[str, Any],
    split: str,
    episodes: int | None = None,
) -> JugglingEpisodes:
    """Play ``episodes`` (default :data:`DEFAULT_EPISODES`) deterministic episodes of
    ``split`` (seeds ``SPLIT_SEEDS[split] + i``), all at once; ``policy`` maps raw
    observations ``(N, obs_dim)`` to actions, None is the zero action (the analytic
    juggler). Each episode is stepped until it ends and no further (a finished episode's
    row of the batch keeps its last observation; the policy's action for it is unused):
    the same episodes as a ``SyncVectorEnv`` of the N environments, whose autoreset would
    play new episodes in the finished rows until the longest episode ends. The zero action
    on an environment with ``nominal_episode`` (Juggling-v1) is played by it, one episode
    after the other in one environment: the same numbers without the observations and
    the reward."""
    import gymnasium as gym

    import motion_envs  # noqa: F401  (registers the ids, also inside Ray workers)

    if not is_juggling(env_id):
        raise ValueError(f"{env_id} is not a juggling environment")
    n = split_episode_count(split, episodes)
    kwargs = {k: v for k, v in env_kwargs.items() if k != "split"}
    if env_id == "MotionEnvs/Juggling-v1":  # its default gravity, that of its demonstrations
        kwargs.setdefault("gravity", 9.81)
    # Juggling-v2 lives at 9.81 m/s^2 (no gravity argument): its demonstrations'
    demos = demonstration_paths(
        {**kwargs, "gravity": 9.81} if env_id == "MotionEnvs/Juggling-v2" else kwargs, split
    )
    seeds = episode_seeds(split, n)
    if policy is None:  # the controller alone: one env plays the episodes one by one
        env = gym.make(env_id, **kwargs)
        play = getattr(env.unwrapped, "nominal_episode", None)
        if play is not None:
            try:
                played = [play(int(seed)) for seed in seeds.tolist()]
            finally:
                env.close()
            return episodes_from_paths(
                seeds,
                [p["time"] for p in played],
                [p["hand"] for p in played],
                [p["phase"] for p in played],
                np.array([p["tosses"] for p in played], dtype=np.int64),
                np.array([p["catches"] for p in played], dtype=np.int64),
                np.array([p["dropped"] for p in played], dtype=bool),
                demos,
            )
        env.close()
    times: list[list[float]] = [[] for _ in range(n)]
    hands: list[list[FloatArray]] = [[] for _ in range(n)]
    phases: list[list[str]] = [[] for _ in range(n)]
    tosses = np.zeros(n, dtype=np.int64)
    catches = np.zeros(n, dtype=np.int64)
    dropped = np.zeros(n, dtype=bool)

    def record(i: int, info: dict[str, Any], ended: bool, terminated: bool) -> None:
        times[i].append(float(info["time"]))
        hands[i].append(np.asarray(info["hand"], dtype=np.float64))
        phases[i].append(str(info["phase"]))
        if ended:
            tosses[i] = int(info["cycles"])
            catches[i] = int(info["catches"])
            dropped[i] = terminated

    envs = [gym.make(env_id, **kwargs) for _ in range(n)]
    for i, info in enumerate(play_until_ended(envs, seeds, policy, record)):
        times[i].insert(0, float(info["time"]))
        hands[i].insert(0, np.asarray(info["hand"], dtype=np.float64))
        phases[i].insert(0, str(info["phase"]))
    return episodes_from_paths(
        seeds,
        [np.asarray(t) for t in times],
        [np.stack(h) for h in hands],
        phases,
        tosses,
        catches,
        dropped,
        demos,
    )


def split_episode_count(split: str, episodes: int | None) -> int:
    """How many episodes of ``split`` to play: ``episodes``, or the split's
    :data:`DEFAULT_EPISODES` when None (a one-line ``ValueError`` for an unknown split or
    fewer than one episode)."""
    if split not in SPLIT_SEEDS:
        raise ValueError(f"split must be one of {sorted(SPLIT_SEEDS)}; got {split!r}")
    n = DEFAULT_EPISODES[split] if episodes is None else int(episodes)
    if n < 1:
        raise ValueError(f"episodes must be >= 1; got {episodes!r}")
    return n


def play_until_ended(
    envs: list[Any],
    seeds: NDArray[np.int64],
    policy: Policy | None,
    record: Callable[[int, dict[str, Any], bool, bool], None],
) -> list[dict[str, Any]]:
    """Reset ``envs[i]`` with ``seeds[i]`` and step the episodes together, each until it
    ends and no further (a finished episode's row of the batch keeps its last observation;
    the policy's action for it is unused), then close the environments. ``policy`` maps
    the observations ``(N, obs_dim)`` to actions, None is the zero action; after each
    step of episode ``i``, ``record(i, info, ended, terminated)``. Returns the reset
    infos."""
    try:
        first = [env.reset(seed=int(seed)) for env, seed in zip(envs, seeds.tolist(), strict=True)]
        obs = np.stack([o for o, _ in first])
        active = list(range(len(envs)))
        shape = (len(envs), *(envs[0].action_space.shape or ()))
        while active:
            actions = np.zeros(shape, dtype=np.float32) if policy is None else policy(obs)
            actions = np.asarray(actions, dtype=np.float32)
            still = []
            for i in active:
                o, _, terminated, truncated, info = envs[i].step(actions[i])
                obs[i] = o
                record(i, info, bool(terminated or truncated), bool(terminated))
                if not (terminated or truncated):
                    still.append(i)
            active = still
    finally:
        for env in envs:
            env.close()
    return [info for _, info in first]


def episodes_from_paths(
    seeds: NDArray[np.int64],
    times: list[FloatArray],
    hands: list[FloatArray],
    phases: list[list[str]],
    tosses: NDArray[np.int64],
    catches: NDArray[np.int64],
    dropped: NDArray[np.bool_],
    demos: Mapping[str, FloatArray],
) -> JugglingEpisodes:
    """The :class:`JugglingEpisodes` of played episodes (per episode ``times (n,)``,
    ``hands (n, 2)`` and ``phases`` at its steps, the reset's included)."""
    seg_phase: list[str] = []
    seg_episode: list[int] = []
    seg_dev: list[float] = []
    for i in range(seeds.size):
        for phase, dev in segment_deviations(times[i], hands[i], phases[i], demos):
            seg_phase.append(phase)
            seg_episode.append(i)
            seg_dev.append(dev)
    return JugglingEpisodes(
        seeds=seeds,
        tosses=tosses,
        catches=catches,
        dropped=dropped,
        segment_phase=np.asarray(seg_phase, dtype=str),
        segment_episode=np.asarray(seg_episode, dtype=np.int64),
        segment_deviation=np.asarray(seg_dev, dtype=np.float64),
    )


class TossCounts(Protocol):
    """Per-episode seeds, catches and tosses: what a pooled catch rate needs (one ball's
    :class:`JugglingEpisodes`, the cascade's episodes)."""

    @property
    def seeds(self) -> NDArray[np.int64]: ...
    @property
    def catches(self) -> NDArray[np.int64]: ...
    @property
    def tosses(self) -> NDArray[np.int64]: ...


def pooled_catch_rate(eps: TossCounts, rows: NDArray[np.int64]) -> float:
    """Catches per toss over the episodes ``rows`` (pooled)."""
    return float(eps.catches[rows].sum() / max(int(eps.tosses[rows].sum()), 1))


def catch_rate_interval(eps: TossCounts, seed: int = 0) -> tuple[float, float, float]:
    """``(catch_rate, low, high)``: the catch rate (catches per toss, pooled) and its 95 %
    bootstrap interval resampling episodes (:func:`baselines.stats.group_bootstrap`)."""
    from baselines.stats import group_bootstrap

    return group_bootstrap(
        lambda rows: pooled_catch_rate(eps, rows), np.arange(eps.seeds.size), seed=seed
    )


def catch_rate_difference(
    a: TossCounts, b: TossCounts, seed: int = 0
) -> tuple[float, float, float]:
    """``(difference, low, high)``: ``a``'s catch rate minus ``b``'s on the same seeds and
    its 95 % paired bootstrap interval (an episode of both is resampled together)."""
    c = catch_rate_comparison(a, b, seed)
    return c.difference, *c.ci95


def catch_rate_comparison(
    a: TossCounts, b: TossCounts, seed: int = 0, names: tuple[str, str] = ("agent", "nominal")
) -> Difference:
    """:func:`catch_rate_difference` as a :class:`baselines.stats.Difference` (with its
    power line); ``names``: what ``a`` and ``b`` are called in its words."""
    from baselines.stats import compare_difference

    if not np.array_equal(a.seeds, b.seeds):
        raise ValueError("the two policies were played on different seeds")
    return compare_difference(
        lambda rows: pooled_catch_rate(a, rows) - pooled_catch_rate(b, rows),
        np.arange(a.seeds.size), *names, "catch rate (catches per toss)", seed=seed,
    )  # fmt: skip


class SegmentDeviations(Protocol):
    """Per complete phase segment, its episode's index and its deviation (m): what a
    deviation's interval needs (one ball's :class:`JugglingEpisodes`, the cascades'
    :class:`~baselines.agents.cascade_score.CascadeDeviations`)."""

    @property
    def segment_episode(self) -> NDArray[np.int64]: ...
    @property
    def segment_deviation(self) -> FloatArray: ...


def deviation_interval(eps: SegmentDeviations, seed: int = 0) -> tuple[float, float, float]:
    """``(deviation, low, high)``: the median over the segments of their deviations (m;
    :attr:`JugglingEpisodes.deviation`) and its 95 % interval resampling episodes (their
    segments together); NaN without segments."""
    from baselines.stats import statistic_interval

    if eps.segment_deviation.size == 0:
        return math.nan, math.nan, math.nan
    return statistic_interval(eps.segment_deviation, eps.segment_episode, seed=seed)
