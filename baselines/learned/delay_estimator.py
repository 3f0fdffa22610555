"""A LEARNED delay rule: the episode's anchored flights so far -> the episode's delay.

A supervised regressor (no reinforcement learning) that plays as the release-anchored
estimators' :class:`~motion_envs.models.juggling.DelayRule` (the envs' ``delay_rule=``;
controllers ``juggler_delay_estimator``, ``juggler_delay_estimator_catch``,
``juggler_estimator_tracker_catch``). Its row ``learned_estimator_catch`` is
``juggler_delay_estimator_catch`` told this rule.

**Data.** :func:`collect_flights` plays ``juggler_delay_estimator_catch`` (the zero action)
with a :class:`RecordingRule` as its ``delay_rule``: at every call it stores the flights
it is given (copies) and the env's TRUE delay (the env attribute ``delay``, for
evaluation) and returns the default rule's value
(:func:`~motion_envs.models.juggling.mean_flight_delay`), so the episodes are
``delay_estimator_catch``'s and the flights are what the row sees. One sample per
episode and number of flights (the estimators ask again only when a flight is added).
:func:`train_delay_rule` reads the TRAINING split only (``SPLIT_SEEDS["train"] + i``).

**Features** (:func:`flight_features`, fixed length ``len(DELAY_GRID) + 7``; ``base`` the
default rule's value, the mean of the flights' least-residual delays). Per flight ``f``,
``r_f`` its :func:`~motion_envs.models.juggling.release_residuals` on
:data:`~motion_envs.models.juggling.DELAY_GRID` (flights with no finite entry are left
out, as the estimators leave them out) and its normalised curve ``c_f = min((r_f -
min r_f) / mean_finite(r_f - min r_f), CURVE_CLIP)`` (``inf`` -> ``CURVE_CLIP``):

1. the mean of the ``c_f`` over the flights (one entry per grid delay);
2. the mean of the flights' parabola-refined least-residual delays, minus ``base``;
3. the standard deviation of the flights' least-residual delays (0 for one flight);
4. the least-residual delay of the flights' summed raw residuals (pooled), minus ``base``
   (0 where no delay is finite for every flight);
5. that pooled delay parabola-refined, minus ``base``;
6. ``min(n, N_CAP)`` (``n`` the flights);
7. ``1 / n``;
8. the mean over flights of ``log10(min r_f + 1e-12)`` (the fit's noise).

The target is the correction ``delay - base``; the rule returns ``base + prediction``,
clipped to the grid's range. A zero model IS the default rule.

**Model.** Ridge regression (scikit-learn, standardised features) against a small torch
MLP (one tanh hidden layer, full-batch Adam, weight decay): each candidate (the ridge
penalties :data:`RIDGE_ALPHAS`; the MLP's weight decays :data:`MLP_DECAYS` x epochs
:data:`MLP_EPOCHS`) scored by the RMSE of the correction over grouped K-fold CV on the
TRAINING samples (groups = episodes; folds shuffled with the seed), the lowest chosen and
refitted on every training sample. Rows: the samples with at most :data:`N_CAP` flights.
The seed sets the folds and the MLP's initialisation.

**File.** :meth:`LearnedDelayRule.save` writes a safetensors model file
(:mod:`baselines.learned.model_file`: no pickle; weights hashed; float64 tensors);
:meth:`LearnedDelayRule.load` rejects a corrupt, truncated or wrong-shape file with a
one-line :class:`~baselines.learned.model_file.LearnedModelFileError` naming the file.
Predictions after ``save`` -> ``load`` are bit-identical (both evaluate the stored
float64 arrays with numpy).
"""

from __future__ import annotations

import math
import os
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from baselines.learned.model_file import (
    data_hash,
    model_file_error,
    read_model_file,
    write_model_file,
)
from motion_envs.datasets.juggling import episode_seeds
from motion_envs.models.juggling import (
    DELAY_GRID,
    AnchoredFlight,
    mean_flight_delay,
    parabolic_minimum,
)
from motion_envs.models.juggling import release_residuals as _residuals

__all__ = [
    "CURVE_CLIP",
    "KINDS",
    "MLP_DECAYS",
    "MLP_EPOCHS",
    "N_CAP",
    "N_FEATURES",
    "RIDGE_ALPHAS",
    "FlightSamples",
    "LearnedDelayRule",
    "RecordingRule",
    "collect_flights",
    "flight_features",
    "train_delay_rule",
]

#: Training rows: samples with at most this many flights; the count feature is clipped here.
N_CAP = 10
#: The normalised residual curves are clipped at this value (``inf`` becomes it).
CURVE_CLIP = 10.0
#: Features per sample (module docstring).
N_FEATURES = len(DELAY_GRID) + 7
#: Ridge penalties tried (on standardised features).
RIDGE_ALPHAS: tuple[float, ...] = (0.1, 1.0, 10.0, 100.0, 1000.0)
#: The MLP's weight decays and epoch counts tried; its width and learning rate.
MLP_DECAYS: tuple[float, ...] = (1e-4, 1e-2)
MLP_EPOCHS: tuple[int, ...] = (100, 300, 600)
MLP_HIDDEN = 32
MLP_LR = 3e-3
#: The model kinds a file may hold.
KINDS = ("delay-rule-ridge", "delay-rule-mlp")
_SHAPES: dict[str, Callable[[int, int], dict[str, tuple[int, ...]]]] = {
    "delay-rule-ridge": lambda p, h: {
        "x_mean": (p,),
        "x_scale": (p,),
        "coef": (p,),
        "intercept": (1,),
    },
    "delay-rule-mlp": lambda p, h: {
        "x_mean": (p,),
        "x_scale": (p,),
        "W1": (p, h),
        "b1": (h,),
        "W2": (h,),
        "b2": (1,),
        "y_scale": (1,),
    },
}


def _refined(r: NDArray[np.float64]) -> float:
    """The least-residual grid delay of ``r`` refined below the grid by the parabola
    through it and its neighbours (:func:`~motion_envs.models.juggling.parabolic_minimum`;
    ``r`` has a finite entry)."""
    d = parabolic_minimum(DELAY_GRID, r)
    assert d is not None
    return d


def flight_features(
    flights: Sequence[AnchoredFlight], gravity: float
) -> tuple[NDArray[np.float64], float] | None:
    """``(features (N_FEATURES,), base)`` of an episode's anchored flights (module
    docstring), or None when no flight tells a delay."""
    curves, grid_d, fine_d, logs, raws = [], [], [], [], []
    for s0, q in flights:
        r = _residuals(s0, q, gravity)
        ok = np.isfinite(r)
        if not ok.any():
            continue
        k = int(np.argmin(r))
        rel = r - r[k]
        scale = float(rel[ok].mean())
        c = np.where(ok, rel / (scale if scale > 0 else 1.0), CURVE_CLIP)
        curves.append(np.minimum(c, CURVE_CLIP))
        grid_d.append(float(DELAY_GRID[k]))
        fine_d.append(_refined(r))
        logs.append(math.log10(float(r[k]) + 1e-12))
        raws.append(r)
    if not curves:
        return None
    n = len(curves)
    base = float(np.mean(grid_d))
    pooled = np.sum(raws, axis=0)
    if np.isfinite(pooled).any():
        kp = int(np.argmin(pooled))
        pooled_d, pooled_fine = float(DELAY_GRID[kp]) - base, _refined(pooled) - base
    else:
        pooled_d = pooled_fine = 0.0
    x = np.concatenate(
        [
            np.mean(curves, axis=0),
            [
                float(np.mean(fine_d)) - base,
                float(np.std(grid_d)),
                pooled_d,
                pooled_fine,
                float(min(n, N_CAP)),
                1.0 / n,
                float(np.mean(logs)),
            ],
        ]
    )
    return x, base


@dataclass
class FlightSamples:
    """Recorded calls of a delay rule: per sample the episode's reset seed, the flights
    it was given and the env's true delay then (s); ``gravity`` the env's."""

    gravity: float
    episode: list[int] = field(default_factory=list)
    flights: list[tuple[AnchoredFlight, ...]] = field(default_factory=list)
    delay: list[float] = field(default_factory=list)

    def n_flights(self) -> NDArray[np.int64]:
        """The number of flights of every sample."""
        return np.array([len(f) for f in self.flights], dtype=np.int64)

    def table(self) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.float64],
                             NDArray[np.int64], NDArray[np.int64]]:  # fmt: skip
        """``(X, base, true delay, episode, n flights)`` of the samples that tell a delay."""
        rows, bases, keep = [], [], []
        for i, fl in enumerate(self.flights):
            got = flight_features(fl, self.gravity)
            if got is not None:
                rows.append(got[0])
                bases.append(got[1])
                keep.append(i)
        idx = np.array(keep, dtype=np.int64)
        X = np.array(rows, dtype=np.float64).reshape(len(keep), N_FEATURES)
        return (
            X,
            np.array(bases, dtype=np.float64),
            np.asarray(self.delay, dtype=np.float64)[idx],
            np.asarray(self.episode, dtype=np.int64)[idx],
            self.n_flights()[idx],
        )


class RecordingRule:
    """A :class:`~motion_envs.models.juggling.DelayRule` that stores every call's flights
    (copied) with the env's true delay in :attr:`samples` (once per episode and number of
    flights) and returns the default rule's value. Set :attr:`env` (the unwrapped env,
    read for its ``delay``) and :attr:`episode` (the seed) before each episode."""

    def __init__(self, gravity: float) -> None:
        self.samples = FlightSamples(gravity)
        self.env: Any = None
        self.episode: int = -1
        self._seen: set[tuple[int, int]] = set()

    def __call__(self, flights: Sequence[AnchoredFlight], gravity: float) -> float | None:
        key = (self.episode, len(flights))
        self.samples.gravity = float(gravity)
        if flights and key not in self._seen:
            self._seen.add(key)
            self.samples.episode.append(self.episode)
            self.samples.flights.append(tuple((s.copy(), q.copy()) for s, q in flights))
            self.samples.delay.append(float(self.env.delay))
        return mean_flight_delay(flights, gravity)


#: The controller the samples are recorded with (the row's own).
CONTROLLER = "juggler_delay_estimator_catch"


def collect_flights(
    env_id: str,
    env_kwargs: Mapping[str, Any],
    split: str,
    n: int,
    first: int = 0,
    progress: bool = True,
) -> FlightSamples:
    """The samples of episodes ``first .. first + n - 1`` of ``split`` played by
    ``juggler_delay_estimator_catch`` (the zero action) with a :class:`RecordingRule`
    (``env_kwargs``: the env's other keywords, e.g. ``level``, ``pattern``)."""
    import gymnasium as gym
    from tqdm import tqdm

    import motion_envs  # noqa: F401  (registers the ids)

    if n < 1 or first < 0:
        raise ValueError(f"n must be >= 1 and first >= 0; got n={n!r}, first={first!r}")
    kwargs = {**env_kwargs, "controller": CONTROLLER}
    rec = RecordingRule(math.nan)  # the gravity the estimators give it, at the first call
    env = gym.make(env_id, delay_rule=rec, **kwargs).unwrapped
    rec.env = env
    play = getattr(env, "play", None) or env.nominal_episode  # type: ignore[attr-defined]
    seeds = episode_seeds(split, first + n)[first:]
    for seed in tqdm(seeds.tolist(), desc=f"{split} flights", disable=not progress):
        rec.episode = int(seed)
        play(int(seed))
    env.close()
    return rec.samples


def _folds(groups: NDArray[np.int64], k: int, seed: int) -> list[tuple[NDArray[Any], NDArray[Any]]]:
    from sklearn.model_selection import GroupKFold

    k = min(k, np.unique(groups).size)
    if k < 2:
        raise ValueError(f"grouped K-fold needs at least 2 episodes; got {np.unique(groups).size}")
    cv = GroupKFold(n_splits=k, shuffle=True, random_state=seed)
    return list(cv.split(np.zeros(groups.size), groups=groups))


def _standardise(X: NDArray[np.float64]) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    mean = X.mean(axis=0)
    sd = X.std(axis=0)
    return mean, np.where(sd > 1e-12, sd, 1.0)


def _fit_ridge(X: NDArray[np.float64], y: NDArray[np.float64], alpha: float) -> dict[str, Any]:
    from sklearn.linear_model import Ridge

    mean, sd = _standardise(X)
    m = Ridge(alpha=alpha).fit((X - mean) / sd, y)
    return {"x_mean": mean, "x_scale": sd, "coef": np.asarray(m.coef_, np.float64),
            "intercept": np.array([float(m.intercept_)])}  # fmt: skip


def _fit_mlp(
    X: NDArray[np.float64], y: NDArray[np.float64], decay: float, epochs: Sequence[int], seed: int
) -> dict[int, dict[str, Any]]:
    """The MLP's parameters after each of ``epochs`` (full-batch Adam, MSE in units of
    the target's sd plus ``decay`` times the weights' squared norm)."""
    import torch

    from baselines.learned.batched_mlp import deterministic_torch

    mean, sd = _standardise(X)
    ys = float(y.std()) or 1.0
    out: dict[int, dict[str, Any]] = {}
    with deterministic_torch():
        g = torch.Generator().manual_seed(seed)
        p = X.shape[1]
        W1 = torch.randn(p, MLP_HIDDEN, generator=g, dtype=torch.float64) / math.sqrt(p)
        b1 = torch.zeros(MLP_HIDDEN, dtype=torch.float64)
        W2 = torch.zeros(MLP_HIDDEN, dtype=torch.float64)  # starts at the mean correction
        b2 = torch.zeros(1, dtype=torch.float64)
        params = [t.requires_grad_() for t in (W1, b1, W2, b2)]
        xt = torch.from_numpy((X - mean) / sd)
        yt = torch.from_numpy((y - y.mean()) / ys)
        opt = torch.optim.Adam(params, lr=MLP_LR)
        for epoch in range(1, max(epochs) + 1):
            opt.zero_grad()
            pred = torch.tanh(xt @ W1 + b1) @ W2 + b2
            loss = ((pred - yt) ** 2).mean() + decay * ((W1**2).sum() + (W2**2).sum())
            loss.backward()  # type: ignore[no-untyped-call]
            opt.step()
            if epoch in epochs:
                out[epoch] = {
                    "x_mean": mean, "x_scale": sd,
                    "W1": W1.detach().numpy().copy(), "b1": b1.detach().numpy().copy(),
                    "W2": W2.detach().numpy().copy(),
                    "b2": b2.detach().numpy() * ys + float(y.mean()),
                    "y_scale": np.array([ys]),
                }  # fmt: skip
    return out


def _predict(kind: str, t: Mapping[str, NDArray[np.float64]], X: NDArray[np.float64]) -> Any:
    z = (X - t["x_mean"]) / t["x_scale"]
    if kind == "delay-rule-ridge":
        return z @ t["coef"] + t["intercept"][0]
    return (np.tanh(z @ t["W1"] + t["b1"]) @ t["W2"]) * t["y_scale"][0] + t["b2"][0]


def _candidates() -> list[tuple[str, dict[str, Any]]]:
    out: list[tuple[str, dict[str, Any]]] = [
        ("delay-rule-ridge", {"alpha": a}) for a in RIDGE_ALPHAS
    ]
    out += [("delay-rule-mlp", {"decay": d, "epochs": e}) for d in MLP_DECAYS for e in MLP_EPOCHS]
    return out


def _name(kind: str, hp: Mapping[str, Any]) -> str:
    return (
        kind.removeprefix("delay-rule-") + "(" + ", ".join(f"{k}={v}" for k, v in hp.items()) + ")"
    )


class LearnedDelayRule:
    """The learned :class:`~motion_envs.models.juggling.DelayRule` (module docstring).

    ``rule(flights, gravity)`` -> the delay (s), or None when no flight tells one.
    Fitted attributes: ``kind`` (one of :data:`KINDS`), ``tensors`` (name -> float64
    array), ``info`` (the CV table, the choice, the training data's hash).
    """

    def __init__(self, kind: str, tensors: Mapping[str, NDArray[np.float64]],
                 info: Mapping[str, Any] | None = None) -> None:  # fmt: skip
        if kind not in KINDS:
            raise ValueError(f"kind must be one of {list(KINDS)}; got {kind!r}")
        self.kind = kind
        self.tensors = {k: np.ascontiguousarray(v, dtype=np.float64) for k, v in tensors.items()}
        self.info = dict(info or {})

    @classmethod
    def fit(cls, samples: FlightSamples, seed: int = 0, folds: int = 5) -> LearnedDelayRule:
        """Choose the model by grouped K-fold CV over ``samples``' episodes, refit on all
        (module docstring)."""
        X, base, delay, episode, n = samples.table()
        keep = n <= N_CAP
        X, y, groups, n = X[keep], (delay - base)[keep], episode[keep], n[keep]
        splits = _folds(groups, folds, seed)
        cands = _candidates()
        sq = {i: np.zeros(y.size) for i in range(len(cands))}
        for train, held in splits:
            for i, (kind, hp) in enumerate(cands):
                if kind == "delay-rule-ridge":
                    t = _fit_ridge(X[train], y[train], hp["alpha"])
                    sq[i][held] = (_predict(kind, t, X[held]) - y[held]) ** 2
            for decay in MLP_DECAYS:
                fits = _fit_mlp(X[train], y[train], decay, MLP_EPOCHS, seed)
                for i, (kind, hp) in enumerate(cands):
                    if kind == "delay-rule-mlp" and hp["decay"] == decay:
                        t = fits[hp["epochs"]]
                        sq[i][held] = (_predict(kind, t, X[held]) - y[held]) ** 2
        table = {}
        for i, (kind, hp) in enumerate(cands):
            entry: dict[str, float | None] = {"rmse_ms": 1000 * float(np.sqrt(sq[i].mean()))}
            for k in (1, 2, 3):
                at = sq[i][n == k]
                entry[f"rmse_ms_{k}"] = 1000 * float(np.sqrt(at.mean())) if at.size else None
            table[_name(kind, hp)] = entry
        default = {"rmse_ms": 1000 * float(np.sqrt((y**2).mean()))}
        best = min(range(len(cands)), key=lambda i: (float(sq[i].mean()), i))
        kind, hp = cands[best]
        if kind == "delay-rule-ridge":
            tensors = _fit_ridge(X, y, hp["alpha"])
        else:
            tensors = _fit_mlp(X, y, hp["decay"], (hp["epochs"],), seed)[hp["epochs"]]
        info = {
            "chosen": _name(kind, hp),
            "hyperparameters": hp,
            "cv_folds": len(splits),
            "cv_rmse": table,
            "cv_default_rule_rmse_ms": default["rmse_ms"],
            "seed": seed,
            "training_rows": int(y.size),
            "training_episodes": int(np.unique(groups).size),
            "training_data_sha256": data_hash(X, y),
        }
        return cls(kind, tensors, info)

    def correction(self, X: NDArray[np.float64]) -> NDArray[np.float64]:
        """The predicted corrections (s) of feature rows ``X (N, N_FEATURES)``."""
        X = np.asarray(X, dtype=np.float64)
        if X.ndim != 2 or X.shape[1] != N_FEATURES:
            raise ValueError(f"X must have shape (N, {N_FEATURES}); got {X.shape}")
        return np.asarray(_predict(self.kind, self.tensors, X), dtype=np.float64)

    def __call__(self, flights: Sequence[AnchoredFlight], gravity: float) -> float | None:
        got = flight_features(flights, gravity)
        if got is None:
            return None
        x, base = got
        d = base + float(self.correction(x[None])[0])
        return float(np.clip(d, DELAY_GRID[0], DELAY_GRID[-1]))

    def save(self, path: str | os.PathLike[str]) -> Path:
        """Write the model file (atomic); returns the path."""
        W1 = self.tensors.get("W1")
        header = {
            "architecture": {
                "kind": self.kind,
                "n_inputs": N_FEATURES,
                "hidden": 0 if W1 is None else int(W1.shape[1]),
            },
            "features": {"grid_s": DELAY_GRID.tolist(), "n_cap": N_CAP, "curve_clip": CURVE_CLIP},
            "normalisation": {"inputs": "(x - x_mean) / x_scale", "output": "base + correction"},
            "training_data_sha256": self.info.get("training_data_sha256", ""),
            "extra": {k: v for k, v in self.info.items() if k != "training_data_sha256"},
        }
        return write_model_file(path, self.tensors, header)

    @classmethod
    def load(cls, path: str | os.PathLike[str]) -> LearnedDelayRule:
        """Read a file written by :meth:`save`; a one-line error naming the file else."""
        p = str(path)
        tensors, header = read_model_file(path)
        arch = header["architecture"]
        kind = arch.get("kind")
        if kind not in KINDS:
            raise model_file_error(
                p, f"field 'architecture.kind' is {kind!r}, expected one of {list(KINDS)}"
            )
        feats = header.get("features", {})
        if (
            feats.get("grid_s") != DELAY_GRID.tolist()
            or feats.get("n_cap") != N_CAP
            or (feats.get("curve_clip") != CURVE_CLIP)
        ):
            raise model_file_error(p, "field 'features' does not match this motion-envs' features")
        hidden = arch.get("hidden")
        if arch.get("n_inputs") != N_FEATURES or not isinstance(hidden, int) or hidden < 0:
            raise model_file_error(
                p, f"field 'architecture' is {arch!r}, expected n_inputs {N_FEATURES}"
            )
        shapes = _SHAPES[kind](N_FEATURES, hidden)
        if set(tensors) != set(shapes):
            raise model_file_error(p, f"tensors {sorted(tensors)}, expected {sorted(shapes)}")
        for name, shape in shapes.items():
            t = tensors[name]
            if t.shape != shape or t.dtype != np.float64:
                raise model_file_error(
                    p, f"tensor {name!r} is {t.dtype}{list(t.shape)}, expected float64{list(shape)}"
                )
        if not (tensors["x_scale"] > 0).all():
            raise model_file_error(p, "tensor 'x_scale' must be positive")
        info = {**header.get("extra", {})}
        info["training_data_sha256"] = header.get("training_data_sha256", "")
        return cls(kind, tensors, info)


def train_delay_rule(
    env_id: str,
    env_kwargs: Mapping[str, Any],
    episodes: int,
    seed: int = 0,
    first: int = 0,
    progress: bool = True,
) -> tuple[LearnedDelayRule, FlightSamples]:
    """Record TRAINING episodes ``first .. first + episodes - 1`` (:func:`collect_flights`
    on split ``"train"``) and fit the rule on them (:meth:`LearnedDelayRule.fit`)."""
    samples = collect_flights(env_id, env_kwargs, "train", episodes, first, progress)
    return LearnedDelayRule.fit(samples, seed), samples
