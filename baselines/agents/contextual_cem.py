"""A contextual bandit learner over the coefficients: a linear policy from the context to
the coefficients, optimised by the cross-entropy method (CEM) from the reward alone.

``OrientationCoefficients-v0`` (and ``PositionCoefficients-v0``) are one-step episodes:
the context (start, goal, duration, task) in, residual coefficients out, the reward minus
the episode's max error. With one step, the problem is a contextual bandit, and a policy
can be judged on many contexts at once (:meth:`~motion_envs.envs._coefficients.
CoefficientEnv.score`, the same arithmetic as ``step``).

The policy: ``a = clip(W [z; 1], -1, 1)`` on the first ``policy_sines`` sine terms per
axis (the higher ones 0), ``z`` the context standardised with the training contexts' mean
and standard deviation (a constant feature gets 1). ``W = 0`` is the nominal.

CEM (diagonal Gaussian over ``W``, mean 0 and standard deviation ``sigma`` at the start):
each generation draws ``population`` candidates, scores each on the same minibatch of
``batch`` training episodes (common random numbers: the candidates are ranked on the same
reaches), keeps the ``elite`` lowest mean max errors and moves the mean and standard
deviation to theirs (smoothed by ``smoothing``; the standard deviation never below
``min_sigma``). A generation uses ``population * batch`` episodes; ``budget`` episodes in
all (the PPO agents' 30,000 steps are 30,000 episodes of the same environment). The mean
after every generation is the policy kept at that step (:attr:`CEMResult.means`), so that
the step, like a PPO checkpoint, can be chosen on validation people.

Settings chosen out of sample (:func:`lopo_fold`, run by
``experiments/contextual_cem_lopo.py``): for a leave-one-person-out fold, every setting
of the declared grid (:func:`settings_grid`: start standard deviation ``sigma`` in
{0.02, 0.05, 0.1}, ``policy_sines`` in {1, 3}, ``(population, elite)`` in {(20, 5),
(40, 10)}; ``batch`` 50, ``smoothing`` 0.3 and ``min_sigma`` 0.005 fixed: 12 settings,
each with the same budget) is trained, per seed, on the fold's training people minus one
and scored on that one (inner leave one person out over the training people: the
environment's ``val_folds`` equal to their number), at every generation, by the
criterion over the inner nominal's (median over the person's reaches of the max error,
the nominal fitted on the inner training people). Per seed and setting the generation
with the lowest mean over the inner people is kept; the setting with the lowest mean of
those over seeds is the fold's (first on ties); then one learner per seed is trained on
all training people with it and kept at its seed's generation, and only then is the
held-out person read, once. :class:`InnerChoice` records the choice and every inner score;
``tests/test_contextual_cem.py`` watches the held-out person's reaches in the dataset the
environments are built from and fails if one is read before the choice.

The budget is PPO's: every learner, inner or final, trains on ``budget`` episodes
(30,000, the PPO agents' timesteps: one step is one episode), and the kept learner has
used ``g * population * batch <= budget`` of them, as a PPO checkpoint at most its
timesteps. The choice multiplies the compute, not the final learner's data: per fold and
seed 12 settings x 7 inner folds = 84 inner learners (2.52 M episodes of the training
people), where the PPO sweep trains 3 inner agents and searches no hyper-parameter.
An earlier version of this module fixed ``sigma = 0.05``, ``smoothing = 0.3`` and 3 sine
terms by hand from trials on fold 0 with the held-out person printed beside; those
defaults stay as :class:`CEMConfig`'s, the LOPO run no longer uses them unchosen.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from motion_envs._typing import FloatArray

__all__ = [
    "ENV_ID",
    "GRID_POLICY_SINES",
    "GRID_POPULATIONS",
    "GRID_SIGMAS",
    "CEMConfig",
    "CEMResult",
    "InnerChoice",
    "LinearPolicy",
    "choose_by_inner_folds",
    "generation_ratios",
    "lopo_fold",
    "policy_ratio",
    "settings_grid",
    "train_cem",
]

#: The environment :func:`lopo_fold` judges the learner on.
ENV_ID = "MotionEnvs/OrientationCoefficients-v0"
#: The declared grid of :func:`settings_grid` (module docstring).
GRID_SIGMAS: tuple[float, ...] = (0.02, 0.05, 0.1)
GRID_POLICY_SINES: tuple[int, ...] = (1, 3)
GRID_POPULATIONS: tuple[tuple[int, int], ...] = ((20, 5), (40, 10))


@dataclass(frozen=True)
class CEMConfig:
    """The learner's settings (module docstring); ``budget`` in episodes."""

    budget: int = 30_000
    population: int = 20
    batch: int = 50
    elite: int = 5
    sigma: float = 0.05
    min_sigma: float = 0.005
    smoothing: float = 0.3
    policy_sines: int = 3

    def __post_init__(self) -> None:
        for name in ("budget", "population", "batch", "elite", "policy_sines"):
            if int(getattr(self, name)) < 1:
                raise ValueError(f"{name} must be >= 1; got {getattr(self, name)}")
        if self.elite > self.population:
            raise ValueError(f"elite must be <= population; got {self.elite} > {self.population}")
        if self.budget < self.population * self.batch:
            raise ValueError(
                f"budget must hold one generation (population * batch = "
                f"{self.population * self.batch}); got {self.budget}"
            )
        for name in ("sigma", "min_sigma"):
            if not float(getattr(self, name)) > 0:
                raise ValueError(f"{name} must be > 0; got {getattr(self, name)}")
        if not 0.0 < self.smoothing <= 1.0:
            raise ValueError(f"smoothing must be in (0, 1]; got {self.smoothing}")

    @property
    def generations(self) -> int:
        """Generations the budget pays for."""
        return self.budget // (self.population * self.batch)


@dataclass(frozen=True)
class LinearPolicy:
    """``a = clip(W [(x - mean) / scale; 1], -1, 1)`` on the first ``policy_sines`` sine
    terms of ``n_sines`` per axis (``width`` axes); the other actions are 0."""

    weights: FloatArray  # (policy_sines * width, n_context + 1)
    mean: FloatArray
    scale: FloatArray
    n_sines: int
    width: int

    def features(self, contexts: Any) -> FloatArray:
        z = (np.asarray(contexts, dtype=np.float64) - self.mean) / self.scale
        return np.concatenate([z, np.ones((z.shape[0], 1))], axis=1)

    def act(self, contexts: Any, weights: FloatArray | None = None) -> FloatArray:
        """Actions ``(N, n_sines * width)`` for contexts ``(N, n_context)``."""
        w = self.weights if weights is None else weights
        head = np.clip(self.features(contexts) @ w.T, -1.0, 1.0)
        out = np.zeros((head.shape[0], self.n_sines * self.width))
        out[:, : head.shape[1]] = head
        return out


@dataclass(frozen=True)
class CEMResult:
    """The policy after every generation (``means[g]``: after ``g + 1`` generations) and
    the mean training minibatch error of the mean policy's elite at each."""

    policy: LinearPolicy
    means: FloatArray  # (generations, *weights.shape)
    elite_errors: FloatArray
    episodes_per_generation: int

    def at(self, generation: int) -> LinearPolicy:
        """The policy kept after ``generation`` generations (0: the nominal)."""
        w = np.zeros_like(self.policy.weights) if generation == 0 else self.means[generation - 1]
        return LinearPolicy(w, self.policy.mean, self.policy.scale, self.policy.n_sines,
                            self.policy.width)  # fmt: skip


def train_cem(env: Any, config: CEMConfig, seed: int) -> CEMResult:
    """Train the linear policy on every episode of ``env`` (an unwrapped coefficient
    environment: ``_context``, ``score``, ``n_sines``, ``_width``) with ``config``'s
    budget; ``seed`` seeds the candidates and the minibatches."""
    contexts = np.asarray(env._context, dtype=np.float64)
    n, d = contexts.shape
    width, n_sines = int(env._width), int(env.n_sines)
    k = min(config.policy_sines, n_sines)
    mean = contexts.mean(axis=0)
    scale = contexts.std(axis=0)
    scale = np.where(scale > 1e-12, scale, 1.0)
    template = LinearPolicy(np.zeros((k * width, d + 1)), mean, scale, n_sines, width)
    feats = template.features(contexts)
    rng = np.random.default_rng(seed)
    mu = np.zeros(template.weights.shape)
    sd = np.full(mu.shape, config.sigma)
    means, elite_errors = [], []
    for _ in range(config.generations):
        batch = rng.choice(n, size=min(config.batch, n), replace=False)
        cands = mu + sd * rng.standard_normal((config.population, *mu.shape))
        errors = np.empty(config.population)
        for c, w in enumerate(cands):
            head = np.clip(feats[batch] @ w.T, -1.0, 1.0)
            actions = np.zeros((batch.size, n_sines * width))
            actions[:, : head.shape[1]] = head
            errors[c] = float(np.mean(env.score(batch, actions)))
        best = cands[np.argsort(errors, kind="stable")[: config.elite]]
        a = config.smoothing
        mu = a * best.mean(axis=0) + (1 - a) * mu
        sd = np.maximum(a * best.std(axis=0) + (1 - a) * sd, config.min_sigma)
        means.append(mu.copy())
        elite_errors.append(float(np.sort(errors)[: config.elite].mean()))
    final = LinearPolicy(mu, mean, scale, n_sines, width)
    return CEMResult(
        final, np.asarray(means), np.asarray(elite_errors), config.population * config.batch
    )


def settings_grid(budget: int = 30_000) -> list[CEMConfig]:
    """The declared settings the inner folds choose from, each with ``budget`` episodes:
    :data:`GRID_SIGMAS` x :data:`GRID_POLICY_SINES` x :data:`GRID_POPULATIONS` (the other
    settings :class:`CEMConfig`'s defaults)."""
    return [
        CEMConfig(budget=budget, sigma=s, policy_sines=k, population=p, elite=e)
        for s in GRID_SIGMAS
        for k in GRID_POLICY_SINES
        for p, e in GRID_POPULATIONS
    ]


def policy_ratio(env: Any, policy: LinearPolicy) -> float:
    """On every episode of ``env``: the criterion (median of the max errors) of
    ``policy`` over the nominal's."""
    errors = env.score(np.arange(env._context.shape[0]), policy.act(env._context))
    return float(np.median(errors)) / float(np.median(env._nominal_errors))


def generation_ratios(env: Any, result: CEMResult) -> FloatArray:
    """``(generations + 1,)``: :func:`policy_ratio` of the policy kept after ``g``
    generations (``g = 0``: the nominal, 1)."""
    return np.array([policy_ratio(env, result.at(g)) for g in range(result.means.shape[0] + 1)])


@dataclass(frozen=True)
class InnerChoice:
    """The settings and generations chosen by inner folds (:func:`choose_by_inner_folds`).

    ``scores[c]``: ``(seeds, generations + 1)`` mean over the inner people of the inner
    criterion over the inner nominal's, setting ``c`` of ``grid``; ``inner_people``: the
    held-out person of each inner fold, in order."""

    grid: tuple[CEMConfig, ...]
    seeds: tuple[int, ...]
    scores: tuple[FloatArray, ...]
    inner_people: tuple[str, ...]

    def setting_scores(self) -> FloatArray:
        """Per setting: the mean over seeds of each seed's best inner score."""
        return np.array([float(s.min(axis=1).mean()) for s in self.scores])

    @property
    def config_index(self) -> int:
        """The chosen setting (lowest :meth:`setting_scores`, first on ties)."""
        return int(np.argmin(self.setting_scores()))

    @property
    def config(self) -> CEMConfig:
        return self.grid[self.config_index]

    def generation(self, seed: int) -> int:
        """The generation kept for ``seed`` under the chosen setting (first on ties)."""
        return int(np.argmin(self.scores[self.config_index][self.seeds.index(seed)]))

    def inner_score(self, seed: int) -> float:
        """The chosen setting's inner score at :meth:`generation` for ``seed``."""
        return float(self.scores[self.config_index][self.seeds.index(seed)].min())


EnvFactory = Callable[..., Any]


def choose_by_inner_folds(
    make_env: EnvFactory,
    seeds: Sequence[int],
    grid: Sequence[CEMConfig],
    progress: Any = None,
) -> InnerChoice:
    """Choose the setting of ``grid`` and each seed's generation by leave one person out
    over the training people of a fold (module docstring).

    ``make_env(split, **kwargs)`` builds the fold's unwrapped environment; only
    ``split="train"`` (the fold's training people, and with ``val_folds = K,
    val_fold = j`` the inner folds) and ``split="val"`` are asked for, never the held-out
    person. ``progress``: a tqdm bar, advanced once per learner trained."""
    train = make_env("train")
    people = np.unique(np.asarray(train.task.subjects).astype(str))
    k = int(people.size)
    inner = [
        (make_env("train", val_folds=k, val_fold=j), make_env("val", val_folds=k, val_fold=j))
        for j in range(k)
    ]
    held = [str(v) for tr, va in inner for v in np.unique(np.asarray(va.task.subjects).astype(str))]
    if sorted(held) != people.tolist():
        raise RuntimeError(f"the inner folds hold out {held}, not each of {people.tolist()} once")
    scores = []
    for config in grid:
        per_seed = np.zeros((len(seeds), config.generations + 1))
        for i, seed in enumerate(seeds):
            for tr, va in inner:
                per_seed[i] += generation_ratios(va, train_cem(tr, config, seed)) / k
                if progress is not None:
                    progress.update(1)
        scores.append(per_seed)
    return InnerChoice(tuple(grid), tuple(int(s) for s in seeds), tuple(scores), tuple(held))


def lopo_fold(
    fold: int,
    seeds: Sequence[int],
    grid: Sequence[CEMConfig],
    data: str = "vr-kitchen",
    progress: Any = None,
) -> tuple[list[dict[str, Any]], InnerChoice]:
    """One leave-one-person-out fold: the choice by inner folds over the training people
    (:func:`choose_by_inner_folds`), then per seed one learner on all training people
    with the chosen setting kept at its generation, scored on the held-out person with
    the nominal and the ridge fitted on the training people. Returns the trials (the keys
    :func:`baselines.agents.sweep.lopo.lopo_summary` reads) and the choice."""
    import gymnasium as gym

    import motion_envs  # noqa: F401  (registers the ids)
    from baselines.agents.learned_criterion import learned_episode_errors

    def make_env(split: str, **kwargs: Any) -> Any:
        return gym.make(ENV_ID, data=data, nominal="bezier-null", fold=fold, split=split,
                        **kwargs).unwrapped  # fmt: skip

    choice = choose_by_inner_folds(make_env, seeds, grid, progress)
    config = choice.config
    train = make_env("train")
    results = {}
    for seed in seeds:
        results[seed] = train_cem(train, config, seed)
        if progress is not None:
            progress.update(1)
    # only now the held-out person
    test = make_env("test")
    ridge = learned_episode_errors(ENV_ID, {"data": data, "nominal": "bezier-null",
                                            "fold": fold}, "test").errors  # fmt: skip
    if not np.array_equal(ridge.trajectory_ids, np.asarray(test.task.trajectory_ids)):
        raise RuntimeError(f"fold {fold}: the ridge's episodes are not the test episodes")
    nominal = float(np.median(test._nominal_errors))
    trials = []
    for seed in seeds:
        g = choice.generation(seed)
        ratio = policy_ratio(test, results[seed].at(g))
        crit = ratio * nominal
        trials.append(
            {
                "config_index": fold,
                "seed": int(seed),
                "test_ratio": ratio,
                "test_criterion": crit,
                "test_nominal_criterion": nominal,
                "test_learned_criterion": ridge.criterion,
                "test_learned_ratio": crit / ridge.criterion,
                "inner_val_ratio": choice.inner_score(seed),
                "chosen_setting": choice.config_index,
                "chosen_generation": g,
                "kept_initial_policy": g == 0,
                "episodes_trained": g * results[seed].episodes_per_generation,
            }
        )
    return trials, choice
