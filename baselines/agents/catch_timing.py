r"""A learned catch-timing policy: the felt task error in, the told delay out, on top of
the delay tracker or the delay estimator with the catch plan (Juggling-v2 and Cascade-v1
with ``timing_scale``).

Why this action. The learners on the position residual found no repeatable gradient at
their base (``experiments/ars_gradient_signal.py``): the room the oracle leaves is in
WHEN the hand meets the ball, and a residual on the hand target turns a felt timing
error into a position only through a product of observations. The envs' timing entry
(``timing_scale``) re-times the catch directly: the delay the juggler is told is the
tracker's plus ``timing_scale * u`` (:mod:`motion_envs.models.juggling._delay_tracker`),
or the estimator's estimate plus ``delay_offset + timing_scale * u``, latched at each
release.

The policy (:class:`TimingPolicy`) reads only the task-error entries of the observation
(``observe_task_error=True``; per hand its last catch's ``(offset, timing, timed,
catches)``, held until its next catch), so its action is constant between catches: one
decision per catch, as a person adjusts after feeling a catch. Per hand the features are

.. math:: \phi_h = (\mathrm{offset}/0.05\,\mathrm{m},\ \mathrm{timing}/0.05\,\mathrm{s},\
          \mathrm{timed},\ [\mathrm{catches} > 0]),

then a constant 1, and ``u = clip(w . phi, -1, 1)``. With ``memory=True`` the policy
also keeps, per row of the batch and per hand, what it has felt in the episode: the sum
``S`` of its timed catches' timing errors and their count ``n``, and adds per hand
``(S / 0.05 s, S / (n 0.05 s))`` (0 while ``n = 0``): an integrator (the tracker's own
state, with a learned gain) and the running mean (the estimate of a constant delay
error a Kalman filter converges to), so the learned correction can use every catch of
the episode, not the last one only. A row's memory is cleared when its catch count
falls (a new episode in that row) or the batch changes size. The residual entries are 0 (the
hand follows the juggler; its likeness is the controller's). ``w = 0`` is the base (the
tracker with its validated gain and offset, or the estimator with its validated
offset). The base itself is in the family only through its own state; the policy adds a
correction per catch on top of it, the residual on an analytic prior of Ploeger &
Peters.

The learner (:func:`train_timing_cem`) is the cross-entropy method (diagonal Gaussian
over ``w``, mean 0 and standard deviation ``sigma`` at the start): each generation
draws ``population`` candidates, plays each on the SAME ``batch`` TRAINING episodes
(common random numbers; seeds ``SPLIT_SEEDS["train"] + seed * 10**6 + g * batch + i``,
new ones every generation), keeps the ``elite`` best by the block's score (one ball: the
catch rate pooled over the episodes; cascades: mean catches before the first drop) and
moves the mean and standard deviation to theirs (smoothed, never below ``min_sigma``).
The mean after every generation is scored on ``val_episodes`` VALIDATION episodes; the
generation with the best validation score is kept (the earliest on ties), as a
checkpoint is chosen; test seeds are never played here. With ``keep_base`` the base
(``w = 0``, the controller alone) is scored on the same validation episodes first and
competes in that choice, winning ties: a learner that finds nothing better on
validation keeps the base instead of a generation validation scores below it. With a
``keep_margin`` of ``m`` standard errors the best generation replaces the base only when
its paired validation gain over the base exceeds ``m`` standard errors of that gain
(:func:`paired_gain`): the best of several generations on the same validation episodes
is biased upward (the winner's curse), and a gain within the noise keeps the base.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import NDArray

from motion_envs._typing import FloatArray

__all__ = [
    "MEMORY_ENTRIES",
    "TIMING_ENTRIES",
    "CEMSettings",
    "FeltErrors",
    "TimingPolicy",
    "TimingTraining",
    "n_features",
    "play_scores",
    "timing_features",
    "train_timing_cem",
]

#: Task-error entries per hand at the end of the observation (``observe_task_error``).
TIMING_ENTRIES = 4
#: The memory's features per hand (``memory=True``): the sum and the mean of the felt
#: timing errors.
MEMORY_ENTRIES = 2
#: Scales of the features (m, s): a 5 cm offset, a 50 ms timing error -> 1.
_OFFSET_SCALE, _TIMING_SCALE = 0.05, 0.05


def timing_features(obs: NDArray[Any], hands: int) -> FloatArray:
    """The policy's features ``(N, 4 hands + 1)`` from observations ``(N, d)`` ending
    with the hands' task-error entries (module docstring)."""
    obs = np.asarray(obs, dtype=np.float64)
    tail = obs[:, -TIMING_ENTRIES * hands :].reshape(len(obs), hands, TIMING_ENTRIES)
    phi = np.stack(
        [
            tail[..., 0] / _OFFSET_SCALE,
            tail[..., 1] / _TIMING_SCALE,
            tail[..., 2],
            (tail[..., 3] > 0).astype(np.float64),
        ],
        axis=-1,
    ).reshape(len(obs), -1)
    return np.hstack([phi, np.ones((len(obs), 1))])


def n_features(hands: int, memory: bool = False) -> int:
    """The length of ``w``: per hand the task-error features (and the memory's), then
    the constant."""
    return (TIMING_ENTRIES + (MEMORY_ENTRIES if memory else 0)) * hands + 1


class FeltErrors:
    """Per row and hand, the sum and count of the timed catches' timing errors felt in
    the episode (module docstring), updated from the held task-error entries: a catch is
    new when the hand's catch count grows."""

    def __init__(self) -> None:
        self.total = np.zeros((0, 0))
        self.count = np.zeros((0, 0))
        self.seen = np.zeros((0, 0))

    def update(self, obs: NDArray[Any], hands: int) -> FloatArray:
        """Take this step's observations ``(N, d)``; return the memory's features ``(N,
        2 hands)``: per hand ``(S / 0.05, S / (n 0.05))``."""
        obs = np.asarray(obs, dtype=np.float64)
        tail = obs[:, -TIMING_ENTRIES * hands :].reshape(len(obs), hands, TIMING_ENTRIES)
        caught = tail[..., 3]
        if self.seen.shape != caught.shape:
            self.total, self.count = np.zeros(caught.shape), np.zeros(caught.shape)
            self.seen = np.zeros(caught.shape)
        fresh = caught < self.seen  # a new episode in that row
        self.total[fresh], self.count[fresh] = 0.0, 0.0
        new = (caught > self.seen) & (tail[..., 2] > 0.5)
        self.total += np.where(new, tail[..., 1], 0.0)
        self.count += new
        self.seen = caught.copy()
        mean = np.divide(
            self.total, self.count, out=np.zeros_like(self.total), where=self.count > 0
        )
        return np.stack([self.total, mean], axis=-1).reshape(len(obs), -1) / _TIMING_SCALE


@dataclass
class TimingPolicy:
    """``u = clip(phi . w, -1, 1)`` per row (module docstring).

    ``weights`` ``(p,)`` for every row, or ``(N, p)``: one candidate per row of the
    observations (CEM plays its candidates side by side); ``p`` is :func:`n_features`.
    With ``memory`` the features of the felt errors come before the constant; call a
    memory policy on every step of its episodes (it counts the catches). Called on
    observations ``(N, d)``, returns actions ``(N, action_dim)``: zeros but the last
    entry, ``u``."""

    weights: FloatArray
    hands: int
    action_dim: int
    memory: bool = False
    felt: FeltErrors = field(default_factory=FeltErrors, repr=False)

    def __call__(self, obs: NDArray[Any]) -> NDArray[np.float32]:
        phi = timing_features(obs, self.hands)
        if self.memory:
            phi = np.hstack([phi[:, :-1], self.felt.update(obs, self.hands), phi[:, -1:]])
        w = np.asarray(self.weights, dtype=np.float64)
        u = phi @ w if w.ndim == 1 else np.einsum("np,np->n", phi, w[: len(phi)])
        out = np.zeros((len(phi), self.action_dim), dtype=np.float32)
        out[:, -1] = np.clip(u, -1.0, 1.0)
        return out


@dataclass(frozen=True)
class CEMSettings:
    """The learner's settings (declared before any run; module docstring)."""

    generations: int = 12
    population: int = 10
    elite: int = 3
    batch: int = 16
    sigma: float = 0.3
    min_sigma: float = 0.02
    smoothing: float = 0.3
    val_episodes: int = 50
    memory: bool = False
    #: the base (``w = 0``) competes in the validation choice (module docstring)
    keep_base: bool = False
    #: standard errors of the paired validation gain a generation needs over the base
    #: to replace it (with ``keep_base``; 0: any gain; module docstring)
    keep_margin: float = 0.0

    def __post_init__(self) -> None:
        for name in ("generations", "population", "elite", "batch", "val_episodes"):
            if int(getattr(self, name)) < 1:
                raise ValueError(f"{name} must be >= 1; got {getattr(self, name)!r}")
        if not (math.isfinite(self.keep_margin) and self.keep_margin >= 0):
            raise ValueError(f"keep_margin must be finite and >= 0; got {self.keep_margin!r}")
        if self.keep_margin and not self.keep_base:
            raise ValueError("keep_margin needs keep_base (the base it is a margin over)")
        if self.elite > self.population:
            raise ValueError(f"elite must be <= population; got {self.elite} > {self.population}")
        if not (self.sigma > 0 and 0 < self.min_sigma <= self.sigma and 0 <= self.smoothing < 1):
            raise ValueError(
                "need sigma > 0, 0 < min_sigma <= sigma and 0 <= smoothing < 1; got "
                f"{self.sigma}, {self.min_sigma}, {self.smoothing}"
            )

    @property
    def episodes(self) -> int:
        """Training episodes used by the whole run."""
        return self.generations * self.population * self.batch


#: ``score(policy, seeds) -> per-policy-row score`` (higher is better).
Scorer = Callable[[TimingPolicy, NDArray[np.int64]], float]


def play_scores(
    env_id: str,
    kwargs: Mapping[str, Any],
    policy: TimingPolicy,
    seeds: NDArray[np.int64],
) -> tuple[NDArray[np.int64], NDArray[np.int64]]:
    """``(catches, tosses)`` per episode of ``env_id`` reset with ``seeds`` (row ``i`` of
    a per-row policy plays ``seeds[i]``), each stepped until it ends."""
    import gymnasium as gym

    import motion_envs  # noqa: F401  (registers the ids)
    from baselines.agents.juggling_score import play_until_ended

    n = len(seeds)
    catches = np.zeros(n, dtype=np.int64)
    tosses = np.zeros(n, dtype=np.int64)
    toss_key = "tosses" if env_id.startswith("MotionEnvs/Cascade") else "cycles"

    def record(i: int, info: dict[str, Any], ended: bool, terminated: bool) -> None:
        if ended:
            catches[i] = int(info["catches"])
            tosses[i] = int(info[toss_key])

    envs = [gym.make(env_id, **kwargs) for _ in range(n)]
    play_until_ended(envs, np.asarray(seeds, dtype=np.int64), policy, record)
    return catches, tosses


def block_score(catches: NDArray[np.int64], tosses: NDArray[np.int64], cascade: bool) -> float:
    """The block's score of a set of episodes: mean catches before the first drop on a
    cascade, else the catch rate pooled (catches over tosses)."""
    if cascade:
        return float(np.mean(catches))
    return float(catches.sum() / max(int(tosses.sum()), 1))


def paired_gain(
    played: tuple[NDArray[np.int64], NDArray[np.int64]],
    base: tuple[NDArray[np.int64], NDArray[np.int64]],
    cascade: bool,
) -> tuple[float, float]:
    r"""``(gain, standard error)`` of :func:`block_score` of ``played`` over ``base``, two
    ``(catches, tosses)`` on the same episodes (paired).

    Cascades: the mean of ``d_i = c_i - c'_i`` and ``sd(d) / sqrt(n)``. One ball (the
    pooled catch rate ``R = \sum c / \sum t``), by the delta method: each episode's
    influence ``e_i = (c_i - R t_i) / \bar t``, the gain ``R - R'`` and the standard error
    ``sd(e - e') / sqrt(n)``. ``sd`` with ``n - 1``; 0 for one episode."""
    c1, t1 = (np.asarray(a, dtype=np.float64) for a in played)
    c0, t0 = (np.asarray(a, dtype=np.float64) for a in base)
    if not (c1.shape == t1.shape == c0.shape == t0.shape and c1.ndim == 1 and len(c1)):
        raise ValueError(f"need paired 1-d scores of one length; got {c1.shape}, {c0.shape}")
    if cascade:
        d = c1 - c0
        gain = float(d.mean())
    else:
        r1, r0 = c1.sum() / max(t1.sum(), 1.0), c0.sum() / max(t0.sum(), 1.0)
        d = (c1 - r1 * t1) / max(t1.mean(), 1e-12) - (c0 - r0 * t0) / max(t0.mean(), 1e-12)
        gain = float(r1 - r0)
    se = float(d.std(ddof=1) / math.sqrt(len(d))) if len(d) > 1 else 0.0
    return gain, se


@dataclass
class TimingTraining:
    """One learner's run: the mean ``w`` after every generation, its validation score,
    the elite's mean training score, and the kept generation (best on validation; -1:
    the base ``w = 0``, only with ``keep_base``, whose validation score is
    ``base_score``, NaN without it)."""

    means: list[FloatArray] = field(default_factory=list)
    val_scores: list[float] = field(default_factory=list)
    train_scores: list[float] = field(default_factory=list)
    kept: int = 0
    base_score: float = math.nan
    #: the kept-or-not generation's paired validation gain over the base and its
    #: standard error (:func:`paired_gain`; NaN without ``keep_base``)
    gain: tuple[float, float] = (math.nan, math.nan)

    @property
    def weights(self) -> FloatArray:
        """The kept ``w`` (zeros when the base was kept)."""
        if self.kept == -1:
            return np.zeros_like(self.means[0])
        return self.means[self.kept]


def train_timing_cem(
    env_id: str,
    kwargs: Mapping[str, Any],
    settings: CEMSettings,
    seed: int,
    progress: Callable[[int, float, float], None] | None = None,
) -> TimingTraining:
    """CEM over the timing policy's weights on TRAINING episodes, the generation kept on
    VALIDATION episodes (module docstring). ``kwargs`` are the env's (with a controller
    that takes a timing entry, ``timing_scale > 0`` and ``observe_task_error=True``);
    ``progress(g, train, val)`` after each generation."""
    import gymnasium as gym

    import motion_envs  # noqa: F401
    from motion_envs.datasets.juggling import SPLIT_SEEDS

    probe = gym.make(env_id, **kwargs).unwrapped
    if not getattr(probe, "timing_scale", 0.0) or not getattr(probe, "observe_task_error", False):
        raise ValueError("kwargs need timing_scale > 0 and observe_task_error=True")
    cascade = env_id.startswith("MotionEnvs/Cascade")
    hands = 2 if cascade else 1
    action_dim = int(np.prod(probe.action_space.shape or (1,)))
    probe.close()
    p = n_features(hands, settings.memory)
    mem = settings.memory
    rng = np.random.default_rng(seed)
    mean, std = np.zeros(p), np.full(p, settings.sigma)
    out = TimingTraining()
    val_seeds = SPLIT_SEEDS["val"] + np.arange(settings.val_episodes, dtype=np.int64)
    s = settings
    base_played: tuple[NDArray[np.int64], NDArray[np.int64]] | None = None
    val_played: list[tuple[NDArray[np.int64], NDArray[np.int64]]] = []
    if s.keep_base:
        zero = TimingPolicy(np.zeros(p), hands, action_dim, mem)
        base_played = play_scores(env_id, kwargs, zero, val_seeds)
        out.base_score = block_score(*base_played, cascade)
    for g in range(s.generations):
        cand = mean + std * rng.standard_normal((s.population, p))
        base = SPLIT_SEEDS["train"] + seed * 10**6 + g * s.batch
        seeds = base + np.arange(s.batch, dtype=np.int64)
        rows = np.repeat(cand, s.batch, axis=0)
        catches, tosses = play_scores(
            env_id, kwargs, TimingPolicy(rows, hands, action_dim, mem), np.tile(seeds, s.population)
        )
        per = catches.reshape(s.population, s.batch), tosses.reshape(s.population, s.batch)
        scores = np.array([block_score(c, t, cascade) for c, t in zip(*per, strict=True)])
        elite = cand[np.argsort(-scores, kind="stable")[: s.elite]]
        mean = s.smoothing * mean + (1 - s.smoothing) * elite.mean(axis=0)
        std = np.maximum(s.smoothing * std + (1 - s.smoothing) * elite.std(axis=0), s.min_sigma)
        val_played.append(
            play_scores(
                env_id, kwargs, TimingPolicy(mean.copy(), hands, action_dim, mem), val_seeds
            )
        )
        val = block_score(*val_played[-1], cascade)
        out.means.append(mean.copy())
        out.val_scores.append(val)
        out.train_scores.append(float(np.sort(scores)[::-1][: s.elite].mean()))
        if progress is not None:
            progress(g, out.train_scores[-1], val)
    out.kept = int(np.argmax(out.val_scores))  # the first of the best
    if base_played is not None:  # the base wins ties, and gains within the margin
        out.gain = paired_gain(val_played[out.kept], base_played, cascade)
        if out.base_score >= out.val_scores[out.kept] or out.gain[0] <= s.keep_margin * out.gain[1]:
            out.kept = -1
    return out
