"""The path-frame, predicted-timing and learned rows of ``motion-bench orientation``.

All rows leave one subject out (LOSO): each subject's trajectories are predicted by
models fitted on the other subjects only; every hyper-parameter is chosen inside those
training subjects (nested folds by subject, :mod:`baselines.learned.nested`). The
criterion is the paper's ``median_l max_t |r_l(t) - rhat_l(t)|`` (radians).

Observed timing (the residual is taken against the slerp traversed with the held-out
trajectory's own speed profile, as the paper's rows; unknown before the movement):

* ``null_d2_path_loso``: the null Bézier model (d = 2) fitted in the path frame;
* ``task_predictor_d2_path_loso``: the task predictor (d = 2) fitted in the path frame
  (unseen task: the path-frame null);
* ``ridge_loso``: ridge regression of the path-frame residual's sine coefficients on the
  pre-movement conditions (:mod:`baselines.learned.orientation`);
* ``mlp_loso``: the torch MLP of the same targets (:mod:`baselines.learned.batched_mlp`).

Predicted timing (a prediction made before the movement; the residual is taken against
a slerp traversed with a *predicted* speed profile):

* analytic rows use the training subjects' mean speed profile ``alpha_bar`` (the
  paper's average profile, as the environments do); residuals of training and held-out
  trajectories are both taken against the slerp with that profile:
  ``slerp_loso_predicted_timing`` (residual predicted as 0),
  ``null_d2_loso_predicted_timing``, ``task_predictor_d2_loso_predicted_timing``
  (unseen task: null), ``null_d2_path_loso_predicted_timing``;
* learned rows use a speed-profile model fitted on the training subjects
  (:class:`motion_envs.models.timing_model.SpeedProfileModel` on log duration and
  rotation angle, penalty by leave-one-out within them); training residuals are taken
  against its in-sample predictions, held-out ones against its predictions:
  ``ridge_loso_predicted_timing``, ``mlp_loso_predicted_timing``.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import NDArray

from baselines.learned.reading import (
    bootstrap_ratio,
    bootstrap_ratio_power,
    format_comparison,
    plot_ratios,
)
from motion_envs._typing import FloatArray
from motion_envs.datasets import OrientationDataset
from motion_envs.geometry import quaternion as quat
from motion_envs.models.bezier_models import NullBezierModel, TaskBezierModel
from motion_envs.models.criteria import max_errors
from motion_envs.models.path_frame import from_path_frame, path_frames, to_path_frame
from motion_envs.models.slerp_residual import (
    DEFAULT_N_POINTS,
    normalised_grid,
    resample_orientations,
    slerp_residuals,
)
from motion_envs.models.speed_profile import speed_fractions_on_grid
from motion_envs.models.timing_model import SpeedProfileModel, timing_features

__all__ = [
    "ANALYTIC_OBSERVED",
    "ANALYTIC_PREDICTED",
    "LEARNED_ROWS",
    "PATH_OBSERVED",
    "PATH_PREDICTED",
    "ROW_LABELS",
    "LearnedRows",
    "bootstrap_ratio",
    "compare",
    "format_comparison",
    "format_reading",
    "learned_orientation_rows",
    "plot_ratios",
]

#: Rows with observed timing (existing analytic ones first, then the new ones).
ANALYTIC_OBSERVED = (
    "null_d2_loso",
    "task_predictor_d2_loso",
    "null_d2_path_loso",
    "task_predictor_d2_path_loso",
)
#: Analytic rows with predicted timing.
ANALYTIC_PREDICTED = (
    "slerp_loso_predicted_timing",
    "null_d2_loso_predicted_timing",
    "task_predictor_d2_loso_predicted_timing",
    "null_d2_path_loso_predicted_timing",
)
#: Every row this module adds, in print order.
LEARNED_ROWS = (
    "null_d2_path_loso",
    "task_predictor_d2_path_loso",
    "ridge_loso",
    "mlp_loso",
    *ANALYTIC_PREDICTED,
    "ridge_loso_predicted_timing",
    "mlp_loso_predicted_timing",
)


@dataclass
class LearnedRows:
    """Result of :func:`learned_orientation_rows`.

    Attributes
    ----------
    criteria:
        Row name -> criterion (radians); NaN for rows not computed (no torch).
    errors:
        Row name -> ``(L,)`` per-trajectory max errors (for per-subject counts and the
        bootstrap); includes ``null_d2_loso``, ``task_predictor_d2_loso`` and the diagnostic
        ``slerp_timing_model_loso`` (slerp with the speed-profile model, no residual).
    chosen:
        Hyper-parameters each outer fold chose (per model).
    seconds:
        Wall-clock seconds per part (``mlp_training`` is all torch training of both MLP rows;
        ``mlp_training_cpu`` its CPU seconds).
    skipped:
        Row name -> reason it was not computed.
    """

    criteria: dict[str, float]
    errors: dict[str, FloatArray]
    chosen: dict[str, list[dict[str, Any]]] = field(default_factory=dict)
    seconds: dict[str, float] = field(default_factory=dict)
    skipped: dict[str, str] = field(default_factory=dict)


def _residuals_against(
    q_grid: FloatArray, starts: FloatArray, ends: FloatArray, alpha: FloatArray
) -> FloatArray:
    """``logmap(conj(slerp(q_s, q_e, alpha(tau))) q(tau))`` with per-trajectory ``alpha``."""
    a = np.broadcast_to(alpha, q_grid.shape[:2])
    e = quat.slerp(starts[:, None, :], ends[:, None, :], a, validate=False)
    out = quat.logmap(quat.multiply(quat.conjugate(e), q_grid), validate=False)
    out[:, 0] = 0.0
    out[:, -1] = 0.0
    return out


def _subject_folds(
    subjects: NDArray[np.str_],
) -> list[tuple[NDArray[np.int64], NDArray[np.int64]]]:
    return [
        (np.flatnonzero(subjects != s), np.flatnonzero(subjects == s)) for s in np.unique(subjects)
    ]


def learned_orientation_rows(
    dataset: OrientationDataset,
    degree: int = 2,
    n_points: int = DEFAULT_N_POINTS,
    mlp_config: Any | None = None,
    use_torch: bool = True,
    n_sines: int | None = None,
    select_on: str = "mse",
) -> LearnedRows:
    """Compute every row of :data:`LEARNED_ROWS` (definitions in the module docstring).

    ``use_torch=False`` (or torch missing) leaves the ``mlp`` rows NaN with the reason in
    ``skipped``. Needs at least 3 subjects (2 training subjects for the inner folds).
    ``select_on`` is what the MLP's inner validation folds minimise: ``"mse"`` (mean
    squared error of the targets, the default) or ``"criterion"`` (the papers' median of
    max errors; slower and, with few subjects, noisier).
    """
    if select_on not in ("mse", "criterion"):
        raise ValueError(f"select_on must be 'mse' or 'criterion'; got {select_on!r}")
    from baselines.learned import torch_missing_reason
    from baselines.learned.orientation import (
        DEFAULT_N_SINES,
        orientation_features,
        ridge_nested,
        sine_curves,
        sine_targets,
    )

    K = DEFAULT_N_SINES if n_sines is None else n_sines
    subjects = np.asarray(dataset.subjects).astype(str)
    tasks = np.asarray(dataset.tasks).astype(str)
    if np.unique(subjects).size < 3:
        raise ValueError(
            f"the learned rows need at least 3 subjects; {dataset.name!r} has "
            f"{np.unique(subjects).size}"
        )
    tr = dataset.ragged
    S, E, up = tr.starts, tr.ends, dataset.up
    L = tr.n_trajectories
    folds = _subject_folds(subjects)
    t_start = time.perf_counter()
    R = slerp_residuals(tr, n_points)
    q_grid = resample_orientations(tr, normalised_grid(n_points))
    A = speed_fractions_on_grid(tr, n_points)
    levels = sorted(set(tasks.tolist()))
    X = orientation_features(S, E, tr.durations, tasks, levels)
    Xt = timing_features(tr.durations, quat.angle(S, E))
    errors: dict[str, FloatArray] = {}
    chosen: dict[str, list[dict[str, Any]]] = {}
    seconds: dict[str, float] = {}
    skipped: dict[str, str] = {}

    def empty() -> FloatArray:
        return np.empty((L, n_points, 3))

    # -- analytic, observed timing ---------------------------------------------------
    pred = {k: empty() for k in ANALYTIC_OBSERVED}
    # -- analytic, predicted timing (training subjects' mean profile) -----------------
    pred_pt = {k: empty() for k in ANALYTIC_PREDICTED}
    R_pt = empty()
    # -- learned targets per fold ------------------------------------------------------
    P_obs = to_path_frame(R, S, E, up)
    Y_obs = sine_targets(P_obs, K)
    Y_pt = np.empty((len(folds), L, Y_obs.shape[1]))
    P_pt = np.empty((len(folds), L, n_points, 3))
    R_hat_timing = empty()
    timing_chosen = []

    def bezier_rows(
        res: FloatArray, train: NDArray[Any], test: NDArray[Any], out: dict[str, FloatArray]
    ) -> None:
        """The Bézier rows among ``out``'s keys (``NAME_loso[_predicted_timing]``): fitted
        on the residuals ``res[train]``, predicted for ``test``."""
        fit, at = {"starts": S[train], "ends": E[train]}, {"starts": S[test], "ends": E[test]}
        predicted = {
            "null_d2": NullBezierModel(degree).fit(res[train]).predict(n=test.size),
            "task_predictor_d2": TaskBezierModel(degree, unseen="global")
            .fit(res[train], tasks=tasks[train])
            .predict(tasks=tasks[test]),
            "null_d2_path": NullBezierModel(degree, frame="path", up=up)
            .fit(res[train], **fit)
            .predict(**at),
            "task_predictor_d2_path": TaskBezierModel(degree, unseen="global", frame="path", up=up)
            .fit(res[train], tasks=tasks[train], **fit)
            .predict(tasks=tasks[test], **at),
        }
        for name, values in predicted.items():
            for key in (f"{name}_loso", f"{name}_loso_predicted_timing"):
                if key in out:
                    out[key][test] = values

    for o, (train, test) in enumerate(folds):
        bezier_rows(R, train, test, pred)
        Ro = _residuals_against(q_grid, S, E, A[train].mean(axis=0))
        R_pt[test] = Ro[test]
        pred_pt["slerp_loso_predicted_timing"][test] = 0.0
        bezier_rows(Ro, train, test, pred_pt)

        timing = SpeedProfileModel().fit(Xt[train], A[train])
        timing_chosen.append({"lam": timing.lam_})
        Rh = _residuals_against(q_grid, S, E, timing.predict(Xt))
        R_hat_timing[test] = Rh[test]
        P_pt[o] = to_path_frame(Rh, S, E, up)
        Y_pt[o] = sine_targets(P_pt[o], K)
    chosen["timing_model"] = timing_chosen
    # diagnostic (not a row): the slerp with the speed-profile model, no residual
    errors["slerp_timing_model_loso"] = max_errors(R_hat_timing)
    for k in ANALYTIC_OBSERVED:
        errors[k] = max_errors(R, pred[k])
    for k in ANALYTIC_PREDICTED:
        errors[k] = max_errors(R_pt, pred_pt[k])
    seconds["analytic"] = time.perf_counter() - t_start

    def to_body(coef: FloatArray) -> FloatArray:
        return from_path_frame(sine_curves(coef, n_points), S, E, up)

    t0 = time.perf_counter()
    coef, chosen["ridge_loso"] = ridge_nested(X, Y_obs, subjects, folds)
    errors["ridge_loso"] = max_errors(R, to_body(coef))
    coef, chosen["ridge_loso_predicted_timing"] = ridge_nested(X, Y_pt, subjects, folds)
    errors["ridge_loso_predicted_timing"] = max_errors(R_hat_timing, to_body(coef))
    seconds["ridge"] = time.perf_counter() - t0

    reason = torch_missing_reason() or (None if use_torch else "disabled (use_torch=False)")
    if reason is None:
        from baselines.learned.batched_mlp import CurveCriterion, MLPConfig
        from baselines.learned.nested import nested_mlp
        from baselines.learned.orientation import sine_basis

        config = mlp_config if mlp_config is not None else MLPConfig()
        scale = path_frames(S, E, up)[1]
        basis = sine_basis(n_points, K)
        t0 = time.perf_counter()
        c0 = time.process_time()
        crit = CurveCriterion(basis, P_obs, scale) if select_on == "criterion" else None
        res = nested_mlp(X, Y_obs, subjects, folds, config, crit)
        errors["mlp_loso"] = max_errors(R, to_body(res.predictions))
        chosen["mlp_loso"] = res.chosen
        crit = CurveCriterion(basis, P_pt, scale) if select_on == "criterion" else None
        res = nested_mlp(X, Y_pt, subjects, folds, config, crit)
        errors["mlp_loso_predicted_timing"] = max_errors(R_hat_timing, to_body(res.predictions))
        chosen["mlp_loso_predicted_timing"] = res.chosen
        seconds["mlp_training"] = time.perf_counter() - t0
        seconds["mlp_training_cpu"] = time.process_time() - c0
    else:
        for k in ("mlp_loso", "mlp_loso_predicted_timing"):
            skipped[k] = reason
    criteria = {
        k: (float(np.median(errors[k])) if k in errors else float("nan")) for k in LEARNED_ROWS
    }
    return LearnedRows(criteria, errors, chosen, seconds, skipped)


#: Printed labels of the rows.
ROW_LABELS: dict[str, str] = {
    "null_d2_path_loso": "Null (d=2), path frame, LOSO",
    "task_predictor_d2_path_loso": "Task predictor (d=2), path frame, LOSO",
    "ridge_loso": "Ridge (learned), path frame, LOSO",
    "mlp_loso": "MLP (learned, torch), path frame, LOSO",
    "slerp_loso_predicted_timing": "Slerp, predicted timing, LOSO",
    "null_d2_loso_predicted_timing": "Null (d=2), predicted timing, LOSO",
    "task_predictor_d2_loso_predicted_timing": "Task predictor (d=2), pred. timing, LOSO",
    "null_d2_path_loso_predicted_timing": "Null (d=2), path, predicted timing, LOSO",
    "ridge_loso_predicted_timing": "Ridge (learned), predicted timing, LOSO",
    "mlp_loso_predicted_timing": "MLP (learned), predicted timing, LOSO",
}

#: The analytic rows of the learned rows' frame (the path frame; the slerp row predicts a
#: zero residual, the same in every frame).
PATH_OBSERVED = ("null_d2_path_loso", "task_predictor_d2_path_loso")
PATH_PREDICTED = ("slerp_loso_predicted_timing", "null_d2_path_loso_predicted_timing")

#: (learned row, analytic rows it is compared with, target ratio or None): every learned
#: row (path frame) against the best analytic row *in the same frame*, so that a ratio
#: speaks of the learning, not of the frame (the path frame alone takes the null model
#: from ``null_d2_loso`` to ``null_d2_path_loso``; the reading prints that apart).
COMPARISONS: tuple[tuple[str, tuple[str, ...], float | None], ...] = (
    ("mlp_loso", PATH_OBSERVED, 0.90),
    ("mlp_loso_predicted_timing", PATH_PREDICTED, 0.95),
)


def _per_group_medians(errors: FloatArray, groups: NDArray[np.str_]) -> FloatArray:
    return np.array([np.median(errors[groups == g]) for g in np.unique(groups)])


def compare(rows: LearnedRows, subjects: NDArray[Any], n_boot: int = 2000) -> list[dict[str, Any]]:
    """The learned-vs-analytic readings: ratio, bootstrap interval, per-subject counts.

    For each of :data:`COMPARISONS` (and the same with ``ridge`` in place of ``mlp``):
    the best analytic row of the same frame (least criterion), the ratio
    ``learned / best``, its 95%
    interval from resampling subjects, and on how many subjects the learned row's
    median max error is below the best analytic row's.
    """
    subjects = np.asarray(subjects).astype(str)
    out: list[dict[str, Any]] = []
    for learned, analytic, target in COMPARISONS:
        for name in (learned, learned.replace("mlp", "ridge", 1)):
            if name not in rows.errors:
                continue
            best = min(analytic, key=lambda k: float(np.median(rows.errors[k])))
            if any(c["learned"] == name and c["best_analytic"] == best for c in out):
                continue  # the best analytic row is already the target's
            ratio, lo, hi, detectable = bootstrap_ratio_power(
                rows.errors[name], rows.errors[best], subjects, n_boot
            )
            a = _per_group_medians(rows.errors[name], subjects)
            b = _per_group_medians(rows.errors[best], subjects)
            out.append(
                {
                    "learned": name,
                    "best_analytic": best,
                    "analytic_rows": list(analytic),
                    "ratio": ratio,
                    "ratio_ci95": [lo, hi],
                    "detectable_ratios": list(detectable),
                    "target_ratio": target if name == learned else None,
                    "met": bool(ratio <= target) if name == learned and target else None,
                    "subjects_better": int(np.sum(a < b)),
                    "n_subjects": int(a.size),
                    "per_group_ratio": dict(
                        zip(np.unique(subjects).tolist(), (a / b).tolist(), strict=True)
                    ),
                }
            )
    return out


def format_reading(rows: LearnedRows, comparisons: list[dict[str, Any]]) -> str:
    """A short honest reading of the learned rows against the analytic ones."""
    lines = ["", "learned vs analytic, leave one subject out (ratio < 1: learned is better):"]
    lines += [format_comparison(c, "subjects", (28, 40)) for c in comparisons]
    crit = rows.criteria
    if np.isfinite(crit.get("null_d2_path_loso", np.nan)):
        lines.append(
            "  a frame, not a method: the path frame alone takes the null model from "
            f"{np.median(rows.errors['null_d2_loso']):.3f} to "
            f"{crit['null_d2_path_loso']:.3f} rad; the learned rows work in that frame and "
            "are compared with its analytic rows only."
        )
    lines.append(
        "  predicted timing: the slerp with the training subjects' mean speed profile scores "
        f"{crit['slerp_loso_predicted_timing']:.3f} rad; timing, not the residual shape, "
        "dominates the error of a prediction made before the movement; the speed-profile "
        "model alone (slerp, no residual) scores "
        f"{np.median(rows.errors['slerp_timing_model_loso']):.3f} rad."
    )
    for k, why in rows.skipped.items():
        lines.append(f"  {k}: skipped ({why})")
    if "mlp_training" in rows.seconds:
        lines.append(
            f"  torch training of both MLP rows (all folds, nested): "
            f"{rows.seconds['mlp_training']:.1f} s wall, "
            f"{rows.seconds['mlp_training_cpu']:.1f} s CPU (one thread)"
        )
    return "\n".join(lines)
