"""The learned rows given the person's calibration summary: ``ridge_person_k{K}_loso`` and
``mlp_person_k{K}_loso`` of ``motion-bench orientation --calibration``.

The learned rows of :mod:`baselines.learned.rows` (``ridge_loso``, ``mlp_loso``: the
path-frame residual's sine coefficients regressed on the pre-movement conditions,
observed timing, leave one person out) with the calibration summary of ``K`` of the
person's other reaches appended to the conditions: the summary of
:func:`motion_envs.models.person_calibration.calibration_summaries` (the one the
environments' ``calibration=K`` observation holds), of the calibration reaches' own
observed-timing residuals in their path frames
(:func:`~motion_envs.models.person_calibration.calibration_features`).

The calibration reaches are the draws of the ``person_k{K}_loso`` rows
(:func:`~motion_envs.models.person_calibration.calibration_draws`, ``n_draws`` per
trajectory, generator ``default_rng([seed, K])``): never the scored trajectory, only the
scored person's ``K`` drawn trajectories. Training rows are the training people's
trajectories, each with the summaries of its own draws among *its own person's* other
reaches (one row per draw: the model learns what a summary of ``K`` reaches is worth);
the held-out person's rows are predicted once per draw, and a trajectory's error is its
max error averaged over the draws (as the ``person_k`` rows). Every hyper-parameter
(ridge penalty; the MLP's weight decay, base and epochs) is chosen by inner folds over the
training people (:mod:`baselines.learned.nested`), never on the held-out person.

Cost: the ridge rows use every draw for training. The MLP trains ``mlp_train_draws``
draws per training trajectory (the first ones) and only for the ``K`` of ``mlp_ks``,
to keep ``motion-bench orientation`` cheap (the other ``K`` are left out with the reason
in ``skipped``); its predictions still average all ``n_draws`` draws.
"""

from __future__ import annotations

import time
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import NDArray

from motion_envs._typing import FloatArray
from motion_envs.datasets import OrientationDataset
from motion_envs.models.criteria import max_errors
from motion_envs.models.path_frame import from_path_frame, to_path_frame
from motion_envs.models.person_calibration import (
    DEFAULT_N_DRAWS,
    DEFAULT_SEED,
    calibration_draws,
    calibration_features,
    calibration_summaries,
)
from motion_envs.models.slerp_residual import DEFAULT_N_POINTS, slerp_residuals

__all__ = [
    "DEFAULT_MLP_KS",
    "DEFAULT_MLP_TRAIN_DRAWS",
    "LearnedPersonRows",
    "learned_person_row_names",
    "learned_person_rows",
    "mlp_predict",
    "ridge_nested_closed",
    "ridge_predictions",
    "stacked_design",
    "summary_predictions",
]

IntArray = NDArray[np.int64]

#: The ``K`` of the MLP rows in ``motion-bench orientation`` (the issue's target K).
DEFAULT_MLP_KS: tuple[int, ...] = (5,)
#: Calibration draws per training trajectory of the MLP rows.
DEFAULT_MLP_TRAIN_DRAWS = 2


def learned_person_row_names(ks: Sequence[int]) -> list[str]:
    """Row names of :func:`learned_person_rows`, in print order."""
    return [f"{m}_person_k{k}_loso" for m in ("ridge", "mlp") for k in ks]


@dataclass
class LearnedPersonRows:
    """Result of :func:`learned_person_rows`.

    Attributes
    ----------
    criteria:
        Row name -> criterion (radians); NaN for rows not computed.
    errors:
        Row name -> ``(L,)`` draw-averaged per-trajectory max errors.
    chosen:
        Row name -> the hyper-parameters each outer fold chose.
    seconds:
        Wall-clock seconds of the ridge and MLP rows (``mlp_cpu``: CPU seconds).
    skipped:
        Row name -> reason it was not computed.
    n_draws, seed, mlp_train_draws:
        The calibration draws (as the ``person_k`` rows) and the MLP's training draws.
    """

    criteria: dict[str, float]
    errors: dict[str, FloatArray]
    chosen: dict[str, list[dict[str, Any]]] = field(default_factory=dict)
    seconds: dict[str, float] = field(default_factory=dict)
    skipped: dict[str, str] = field(default_factory=dict)
    n_draws: int = DEFAULT_N_DRAWS
    seed: int = DEFAULT_SEED
    mlp_train_draws: int = DEFAULT_MLP_TRAIN_DRAWS


def stacked_design(
    X: FloatArray, summaries: FloatArray, subjects: NDArray[np.str_], n_train_draws: int
) -> tuple[FloatArray, NDArray[np.str_], list[tuple[IntArray, IntArray]], IntArray]:
    """Conditions with the summary appended, one block of ``L`` rows per draw.

    Returns the design ``(R L, p + f + 1)`` (``R`` = ``summaries.shape[0]``), the group
    of every row, the outer folds (one per person: the training people's rows of the
    first ``n_train_draws`` draws, the held-out person's rows of every draw) and the draw
    of every row.
    """
    R, L = summaries.shape[:2]
    design = np.concatenate([np.broadcast_to(X, (R, *X.shape)), summaries], axis=2)
    groups = np.tile(subjects, R)
    draw = np.repeat(np.arange(R), L)
    folds = []
    for s in np.unique(subjects):
        train = np.flatnonzero((groups != s) & (draw < n_train_draws))
        folds.append((train, np.flatnonzero(groups == s)))
    return design.reshape(R * L, -1), groups, folds, draw


def _moments(X: FloatArray, Y: FloatArray) -> tuple[FloatArray, ...]:
    """Row count, sums and cross products of ``X``, ``Y`` (additive over row sets)."""
    return (np.array(float(X.shape[0])), X.sum(axis=0), Y.sum(axis=0), X.T @ X, X.T @ Y)


def _ridge_from_moments(
    moments: Sequence[FloatArray], alphas: Sequence[float]
) -> tuple[FloatArray, FloatArray, FloatArray, FloatArray]:
    """``(mu, sd, ym, B)``: the standardisation and the coefficients ``B`` ``(A, p, m)``
    of scikit-learn's ``make_pipeline(StandardScaler(), Ridge(alpha))`` for each alpha,
    from :func:`_moments` (closed form, one eigen-decomposition)."""
    n, sx, sy, xtx, xty = moments
    mu, ym = sx / n, sy / n
    var = np.maximum(np.diag(xtx) / n - mu * mu, 0.0)
    sd = np.sqrt(var)
    sd = np.where(sd > 10 * np.finfo(np.float64).eps * np.maximum(np.abs(mu), 1.0), sd, 1.0)
    G = (xtx - n * np.outer(mu, mu)) / np.outer(sd, sd)
    c = (xty - n * np.outer(mu, ym)) / sd[:, None]
    w, V = np.linalg.eigh(G)
    Vc = V.T @ c
    B = np.stack([V @ (Vc / np.maximum(w + a, 1e-300)[:, None]) for a in alphas])
    return mu, sd, ym, B


def ridge_predictions(
    X: FloatArray, Y: FloatArray, X_new: FloatArray, alphas: Sequence[float]
) -> FloatArray:
    """``(len(alphas), N_new, m)`` predictions of ridge regressions fitted on ``X``, ``Y``
    (features standardised, intercept unpenalised: scikit-learn's
    ``make_pipeline(StandardScaler(), Ridge(alpha))``), in closed form."""
    mu, sd, ym, B = _ridge_from_moments(_moments(X, Y), alphas)
    out: FloatArray = ((X_new - mu) / sd) @ B + ym
    return out


def ridge_nested_closed(
    X: FloatArray,
    Y: FloatArray,
    groups: NDArray[Any],
    folds: Sequence[tuple[IntArray, IntArray]],
    alphas: Sequence[float],
    inner_splits: int = 4,
) -> tuple[FloatArray, list[dict[str, Any]]]:
    """:func:`baselines.learned.orientation.ridge_nested` in closed form: per outer fold,
    the ``alpha`` with the least mean over the inner group folds
    (:func:`baselines.learned.nested.inner_folds`, training rows only) of the validation
    mean squared error (first on ties), refitted on the training rows. The fits add up
    per-group moments of the training rows (:func:`_moments`)."""
    from baselines.learned.nested import inner_folds

    g_all = np.asarray(groups)
    pred = np.full((X.shape[0], Y.shape[-1]), np.nan)
    chosen = []
    for train, scored in folds:
        per_group = {
            str(g): _moments(X[rows], Y[rows])
            for g in np.unique(g_all[train])
            for rows in [train[g_all[train] == g]]
        }

        def moments_of(rows: IntArray, per: dict[str, tuple[FloatArray, ...]] = per_group) -> Any:
            parts = [per[str(g)] for g in np.unique(g_all[rows])]
            return [sum(p[i] for p in parts) for i in range(5)]

        score = np.zeros(len(alphas))
        splits = inner_folds(train, g_all, inner_splits)
        for fit, val in splits:
            mu, sd, ym, B = _ridge_from_moments(moments_of(fit), alphas)
            P = ((X[val] - mu) / sd) @ B + ym
            score += ((P - Y[val]) ** 2).mean(axis=(1, 2)) / len(splits)
        best = float(alphas[int(np.argmin(score))])
        mu, sd, ym, B = _ridge_from_moments(moments_of(train), [best])
        pred[scored] = ((X[scored] - mu) / sd) @ B[0] + ym
        chosen.append({"alpha": best})
    return pred, chosen


def mlp_predict(params: dict[str, Any], X: FloatArray) -> FloatArray:
    """Outputs ``(N, m)`` of one trained network (``params`` as
    :attr:`baselines.learned.nested.NestedResult.params` holds them) on rows ``X``."""
    import torch

    from baselines.learned.batched_mlp import deterministic_torch, forward

    with deterministic_torch(), torch.no_grad():
        p = {k: torch.from_numpy(np.array(v, dtype=np.float32))[None] for k, v in params.items()}
        p["y_scale"] = p["y_scale"].reshape(1)
        out = forward(p, torch.from_numpy(np.asarray(X, dtype=np.float32))[None])
    return np.asarray(out[0].numpy(), dtype=np.float64)


def summary_predictions(
    X: FloatArray,
    Y: FloatArray,
    features: FloatArray,
    subjects: NDArray[np.str_],
    draws: IntArray,
    mlp_config: Any | None = None,
    mlp_train_draws: int = DEFAULT_MLP_TRAIN_DRAWS,
) -> tuple[FloatArray, list[dict[str, Any]]]:
    """Leave-one-person-out predictions ``(R, L, m)`` of targets ``Y`` ``(L, m)`` from the
    conditions ``X`` ``(L, p)`` and the calibration summary of every draw (``draws``
    ``(R, L, K)``, :func:`~motion_envs.models.person_calibration.calibration_draws`, of
    ``features`` ``(L, f)``), and what each outer fold chose.

    ``mlp_config`` None: the ridge (closed form, penalty among ``RIDGE_ALPHAS`` times
    ``R`` by inner folds over the training people, every draw a training row); else the
    batched MLP (:func:`baselines.learned.nested.nested_mlp`) selected and fitted on the
    first ``mlp_train_draws`` draws, then applied to every draw. For the held-out person,
    only ``X`` of the scored row and ``features`` of its drawn rows are read.
    """
    from baselines.learned.orientation import RIDGE_ALPHAS

    R, L, k = draws.shape
    design, groups, folds, _ = stacked_design(
        X, calibration_summaries(features, draws, k), subjects, R
    )
    Ys = np.tile(Y, (R, 1))
    if mlp_config is None:
        alphas = [a * R for a in RIDGE_ALPHAS]  # the penalty per trajectory of ridge_loso
        coef, chosen = ridge_nested_closed(design, Ys, groups, folds, alphas)
        return coef.reshape(R, L, -1), chosen
    from baselines.learned.nested import nested_mlp

    if not 1 <= mlp_train_draws <= R:
        raise ValueError(f"mlp_train_draws must be in [1, {R}]; got {mlp_train_draws}")
    n = mlp_train_draws * L
    small = [(train[train < n], test[test < n]) for train, test in folds]
    res = nested_mlp(design[:n], Ys[:n], groups[:n], small, mlp_config)
    coef = np.full(Ys.shape, np.nan)
    for (_, test), params in zip(folds, res.params, strict=True):
        coef[test] = mlp_predict(params, design[test])
    return coef.reshape(R, L, -1), res.chosen


def learned_person_rows(
    dataset: OrientationDataset,
    ks: Sequence[int],
    mlp_config: Any | None = None,
    use_torch: bool = True,
    n_draws: int = DEFAULT_N_DRAWS,
    seed: int = DEFAULT_SEED,
    mlp_ks: Sequence[int] | None = DEFAULT_MLP_KS,
    mlp_train_draws: int = DEFAULT_MLP_TRAIN_DRAWS,
    n_points: int = DEFAULT_N_POINTS,
) -> LearnedPersonRows:
    """The rows of :func:`learned_person_row_names` (definitions in the module docstring).

    ``mlp_ks`` (None: every ``K`` of ``ks``) limits the MLP rows; ``use_torch=False`` (or
    torch missing) leaves them out with the reason in ``skipped``. Needs at least 3
    subjects.
    """
    from baselines.learned import torch_missing_reason
    from baselines.learned.orientation import (
        DEFAULT_N_SINES,
        orientation_features,
        sine_curves,
        sine_targets,
    )

    if not 1 <= mlp_train_draws <= n_draws:
        raise ValueError(f"mlp_train_draws must be in [1, {n_draws}]; got {mlp_train_draws}")
    subjects = np.asarray(dataset.subjects).astype(str)
    if np.unique(subjects).size < 3:
        raise ValueError(
            f"the learned person rows need at least 3 subjects; got {np.unique(subjects).size}"
        )
    tr = dataset.ragged
    S, E, up = tr.starts, tr.ends, dataset.up
    R = slerp_residuals(tr, n_points)
    P = to_path_frame(R, S, E, up)
    Y = sine_targets(P, DEFAULT_N_SINES)
    tasks = np.asarray(dataset.tasks).astype(str)
    X = orientation_features(S, E, tr.durations, tasks, sorted(set(tasks.tolist())))
    features = calibration_features(P)

    def draw_errors(coef: FloatArray) -> FloatArray:
        """Draw-averaged max errors of predictions ``(R, L, m)``."""
        curves = [from_path_frame(sine_curves(c, n_points), S, E, up) for c in coef]
        out: FloatArray = np.mean([max_errors(R, c) for c in curves], axis=0)
        return out

    errors: dict[str, FloatArray] = {}
    chosen: dict[str, list[dict[str, Any]]] = {}
    seconds: dict[str, float] = {"ridge": 0.0}
    skipped: dict[str, str] = {}
    reason = torch_missing_reason() or (None if use_torch else "disabled (use_torch=False)")
    mlp_set = set(ks if mlp_ks is None else mlp_ks)
    config = None
    if reason is None:
        from baselines.learned.batched_mlp import MLPConfig

        config = mlp_config if mlp_config is not None else MLPConfig()
        seconds["mlp"] = seconds["mlp_cpu"] = 0.0
    for k in ks:
        draws = calibration_draws(subjects, int(k), n_draws, seed)
        t0 = time.perf_counter()
        name = f"ridge_person_k{k}_loso"
        coef, chosen[name] = summary_predictions(X, Y, features, subjects, draws)
        errors[name] = draw_errors(coef)
        seconds["ridge"] += time.perf_counter() - t0
        name = f"mlp_person_k{k}_loso"
        if reason is not None:
            skipped[name] = reason
            continue
        if int(k) not in mlp_set:
            skipped[name] = f"MLP person rows only for K in {sorted(mlp_set)} (cost)"
            continue
        t0, c0 = time.perf_counter(), time.process_time()
        coef, chosen[name] = summary_predictions(
            X, Y, features, subjects, draws, config, mlp_train_draws
        )
        errors[name] = draw_errors(coef)
        seconds["mlp"] += time.perf_counter() - t0
        seconds["mlp_cpu"] += time.process_time() - c0
    criteria = {
        name: float(np.median(errors[name])) if name in errors else float("nan")
        for name in learned_person_row_names(ks)
    }
    return LearnedPersonRows(
        criteria, errors, chosen, seconds, skipped, n_draws, seed, mlp_train_draws
    )
