"""The error criteria of Faraway & Choe's Table 1, and their out-of-sample versions.

Every criterion is a median over trajectories of the maximum over time of the tangent
space distance between a residual curve and a prediction of it::

    criterion = median_l  max_t  | r_l(t) - rhat_l(t) |

with ``r_l`` the slerp residual of trajectory ``l`` on the 50-point normalised grid
(:mod:`motion_envs.models.slerp_residual`) and ``|.|`` the Euclidean norm in R^3.
Subject ``i``, task ``j``, replicate ``k``; a bullet is a mean over that index.

================================  ==================================================================
name                              prediction ``rhat``
================================  ==================================================================
``within_subject``                ``mean_k r_ijk`` over the replicates of (i, j); groups with >= 2
``within_subject_loo``            ``mean_{k' != k} r_ijk'``: the *other* replicates of (i, j)
``within_subject_path_loo``       the same mean taken in the path frame, mapped back with ``l``'s
``predictive_floor``              ``within_subject_loo``'s errors times ``sqrt((n_ij - 1) / n_ij)``
``predictive_floor_path``         ``within_subject_path_loo``'s errors, the same correction
``between_subject``               ``mean_{i,k} r_ijk``; median over (i, k) in a task, then over j
``slerp_empirical``               0 (slerp with the trajectory's own speed profile)
``slerp_average``                 0, residuals recomputed against the average speed profile
``null_average``                  ``mean_l r_l``
``approximation_d{d}``            each curve's own Bézier fit of degree ``d``
``null_d{d}``                     :class:`NullBezierModel` (``P`` = mean of all ``P_l``)
``subject_predictor_d{d}``        :class:`SubjectBezierModel` (in sample)
``task_predictor_d{d}``           :class:`TaskBezierModel` (in sample)
``null_d{d}_loso``                null model fitted without the trajectory's subject
``task_predictor_d{d}_loso``      task means over the *other* subjects
``subject_predictor_d{d}_loro``   subject means without the trajectory itself
================================  ==================================================================

The predictive floor. ``within_subject`` is the paper's in-sample measure: the scored
reach is inside the mean it is scored against, so its deviation is ``(n - 1) / n`` times
its deviation from the mean of the *other* replicates (half of it for pairs). As a floor
for predictors it is optimistic. ``within_subject_loo`` predicts each reach from the
other replicates of its person and task (leave one out; a real predictor, but one whose
mean of ``n - 1`` replicates carries their noise: with replicates ``r = m + e``,
``e`` independent with one covariance, ``r_l - mean_{others}`` has ``n / (n - 1)`` times
the covariance of ``e``). ``predictive_floor`` scales each of those deviations by
``sqrt((n - 1) / n)``: for Gaussian replicate noise it is then distributed as ``e_l``
itself, so its median max error is that of a predictor that knew the person's mean for
the task, the floor no prediction from a movement's conditions goes below. The ``_path``
rows average the other replicates in the path frame (:mod:`motion_envs.models.path_frame`,
the frame of the path-frame rows), each reach's prediction mapped back with its own frame
(the error is ``s_l max_t |p_l - mean p|``, scored in radians in the body frame as every
row). Reaches whose (i, j) has a single replicate are left out of these four rows.

The paper's predictor rows are in-sample averages; the ``_loso`` (leave one subject
out) and ``_loro`` (leave one replicate out) rows judge the same models on data they
were not fitted to. Where a held-out group has no training data (a task only the
held-out subject performed, a subject with a single trajectory) the null model fitted
on the same training data is used; the number of such fallbacks is reported.
"""

from __future__ import annotations

import os
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from motion_envs._typing import FloatArray
from motion_envs.datasets.cohort_config import DEFAULT_COHORT
from motion_envs.datasets.ragged import DEFAULT_N_POINTS, RaggedTrajectories, normalised_grid
from motion_envs.geometry import bezier
from motion_envs.models.bezier_models import (
    NullBezierModel,
    SubjectBezierModel,
    TaskBezierModel,
    fit_control_points,
)
from motion_envs.models.path_frame import DEFAULT_UP, path_frames, to_path_frame
from motion_envs.models.slerp_residual import slerp_residuals
from motion_envs.models.speed_profile import average_speed_profile, speed_fractions_on_grid

if TYPE_CHECKING:
    from motion_envs.datasets.cohort_config import CohortConfig
    from motion_envs.datasets.orientation import OrientationDataset

__all__ = [
    "CRITERIA_DEGREES",
    "Table1Result",
    "between_subject_error",
    "criterion_names",
    "floor_row_names",
    "max_errors",
    "median_max_error",
    "predictive_floor_errors",
    "replicate_loo_errors",
    "score_cohort",
    "table1",
    "within_subject_error",
]

#: Bézier degrees reported in Table 1.
CRITERIA_DEGREES: tuple[int, ...] = (2, 3, 4)


def criterion_names(degrees: Sequence[int] = CRITERIA_DEGREES) -> list[str]:
    """Names of every criterion :func:`table1` reports, in table order."""
    names = ["within_subject", *floor_row_names(), "between_subject", "slerp_empirical"]
    names.append("slerp_average")
    for d in degrees:
        names.append(f"approximation_d{d}")
    for d in degrees:
        names.append(f"null_d{d}")
    names.append("null_average")
    for kind in ("subject_predictor", "task_predictor"):
        names.extend(f"{kind}_d{d}" for d in degrees)
    for d in degrees:
        names += [f"null_d{d}_loso", f"task_predictor_d{d}_loso", f"subject_predictor_d{d}_loro"]
    return names


def floor_row_names() -> list[str]:
    """The leave-one-out and predictive-floor rows, body frame then path frame."""
    return [
        "within_subject_loo",
        "within_subject_path_loo",
        "predictive_floor",
        "predictive_floor_path",
    ]


def max_errors(residuals: ArrayLike, predictions: ArrayLike | float = 0.0) -> FloatArray:
    """``max_t |r_l(t) - rhat_l(t)|`` for every curve: ``(L, n, 3)`` -> ``(L,)``."""
    R = np.asarray(residuals, dtype=np.float64)
    if R.ndim != 3:
        raise ValueError(f"residuals must have shape (L, n, 3); got {R.shape}")
    diff = R - np.asarray(predictions, dtype=np.float64)
    return np.sqrt(np.einsum("ltc,ltc->lt", diff, diff)).max(axis=1)


def median_max_error(residuals: ArrayLike, predictions: ArrayLike | float = 0.0) -> float:
    """The papers' criterion: ``median_l max_t |r_l(t) - rhat_l(t)|``."""
    return float(np.median(max_errors(residuals, predictions)))


def _group_means(R: FloatArray, keys: NDArray[Any]) -> tuple[FloatArray, NDArray[np.int64]]:
    """Per-curve mean of the curves sharing its key; also the group size of each curve."""
    _, inverse, counts = np.unique(keys, return_inverse=True, return_counts=True)
    sums = np.zeros((counts.size, *R.shape[1:]))
    np.add.at(sums, inverse, R)
    return (sums / counts[:, None, None])[inverse], counts[inverse]


def within_subject_error(residuals: ArrayLike, subjects: ArrayLike, tasks: ArrayLike) -> float:
    """``median max_t |r_ijk - mean_k r_ijk|`` over curves whose (i, j) has >= 2 replicates."""
    R = np.asarray(residuals, dtype=np.float64)
    keys = np.char.add(
        np.char.add(np.asarray(subjects).astype(str), "\x1f"), np.asarray(tasks).astype(str)
    )
    means, sizes = _group_means(R, keys)
    errors = max_errors(R, means)[sizes >= 2]
    if errors.size == 0:
        raise ValueError("within_subject needs at least one (subject, task) pair with 2 replicates")
    return float(np.median(errors))


def replicate_loo_errors(
    curves: ArrayLike, subjects: ArrayLike, tasks: ArrayLike
) -> tuple[FloatArray, NDArray[np.int64]]:
    """``max_t |c_l - mean_{k != l} c_k|`` over the other curves of ``l``'s (subject, task),
    ``(L,)`` (NaN where ``l`` is alone), and the size ``n`` of each curve's group."""
    C = np.asarray(curves, dtype=np.float64)
    if C.ndim != 3:
        raise ValueError(f"curves must have shape (L, n, 3); got {C.shape}")
    keys = np.char.add(
        np.char.add(np.asarray(subjects).astype(str), "\x1f"), np.asarray(tasks).astype(str)
    )
    means, sizes = _group_means(C, keys)
    n = sizes[:, None, None].astype(np.float64)
    others = np.divide(n * means - C, n - 1.0, out=np.zeros_like(C), where=n > 1)
    errors = max_errors(C, others)
    return np.where(sizes >= 2, errors, np.nan), sizes


def predictive_floor_errors(
    residuals: ArrayLike,
    subjects: ArrayLike,
    tasks: ArrayLike,
    frame: tuple[ArrayLike, ArrayLike, ArrayLike] | None = None,
) -> tuple[FloatArray, FloatArray]:
    """Per-reach errors of ``within_subject_loo`` and ``predictive_floor`` (NaN for a
    reach alone in its (subject, task)); with ``frame = (starts, ends, up)`` the path-frame
    rows (module docstring)."""
    R = np.asarray(residuals, dtype=np.float64)
    scale: FloatArray | float = 1.0
    if frame is not None:
        starts, ends, up = frame
        R = to_path_frame(R, starts, ends, up)
        scale = path_frames(starts, ends, up)[1]
    loo, sizes = replicate_loo_errors(R, subjects, tasks)
    loo = loo * scale
    n = sizes.astype(np.float64)
    return loo, loo * np.sqrt(np.divide(n - 1.0, n, out=np.zeros_like(n), where=n > 1))


def between_subject_error(residuals: ArrayLike, tasks: ArrayLike) -> float:
    """``median_j median_{i,k} max_t |r_ijk - mean_{i,k} r_ijk|``."""
    R = np.asarray(residuals, dtype=np.float64)
    tasks = np.asarray(tasks).astype(str)
    means, _ = _group_means(R, tasks)
    errors = max_errors(R, means)
    per_task = [np.median(errors[tasks == j]) for j in np.unique(tasks)]
    return float(np.median(per_task))


@dataclass(frozen=True)
class Table1Result:
    """Criteria of Table 1 for one dataset.

    Attributes
    ----------
    criteria:
        name -> value in radians (names from :func:`criterion_names`).
    residuals:
        ``(L, n_points, 3)`` empirical slerp residuals the criteria were computed on.
    average_alpha:
        ``(n_points,)`` the average speed profile.
    fallbacks:
        name -> number of trajectories scored with the null-model fallback (out-of-
        sample rows only; see the module docstring).
    """

    criteria: dict[str, float]
    residuals: FloatArray
    average_alpha: FloatArray
    fallbacks: dict[str, int] = field(default_factory=dict)


def _leave_one_subject_out(
    R: FloatArray, subjects: NDArray[np.str_], tasks: NDArray[np.str_], degree: int
) -> tuple[FloatArray, FloatArray, int]:
    """Predictions of the null and task models for each curve, fitted without its subject."""
    grid = normalised_grid(R.shape[1])
    null_pred = np.empty_like(R)
    task_pred = np.empty_like(R)
    fallbacks = 0
    for s in np.unique(subjects):
        test = subjects == s
        train = ~test
        if not np.any(train):
            raise ValueError("leave-one-subject-out needs at least two subjects")
        null = NullBezierModel(degree).fit(R[train])
        task = TaskBezierModel(degree, unseen="global").fit(R[train], tasks=tasks[train])
        null_pred[test] = null.predict(n=int(test.sum()))
        P = task.predict_control_points(tasks=tasks[test])
        task_pred[test] = bezier.evaluate(P, grid, degree)
        fallbacks += int(np.count_nonzero(~np.isin(tasks[test], task.groups_)))
    return null_pred, task_pred, fallbacks


def _leave_one_replicate_out(
    R: FloatArray, subjects: NDArray[np.str_], degree: int
) -> tuple[FloatArray, int]:
    """Subject-model prediction of each curve from the subject's other curves.

    Uses the closed form ``(sum_subject P - P_l) / (n_subject - 1)`` (the mean of the
    other curves' control points); a subject with a single curve falls back to the null
    model of all other curves.
    """
    points = fit_control_points(R, degree)
    _, inverse, counts = np.unique(subjects, return_inverse=True, return_counts=True)
    sums = np.zeros((counts.size, *points.shape[1:]))
    np.add.at(sums, inverse, points)
    n = counts[inverse]
    others = (sums[inverse] - points) / np.maximum(n - 1, 1)[:, None, None]
    lonely = n < 2
    if np.any(lonely):
        total = points.sum(axis=0)
        others[lonely] = (total - points[lonely]) / max(points.shape[0] - 1, 1)
    return bezier.evaluate(others, normalised_grid(R.shape[1]), degree), int(lonely.sum())


def table1(
    traj: RaggedTrajectories,
    subjects: ArrayLike,
    tasks: ArrayLike,
    degrees: Sequence[int] = CRITERIA_DEGREES,
    n_points: int = DEFAULT_N_POINTS,
    up: ArrayLike | None = None,
) -> Table1Result:
    """Compute every criterion of Table 1 (and the out-of-sample rows) for a dataset.

    Parameters
    ----------
    traj:
        The trajectories (:class:`RaggedTrajectories`).
    subjects, tasks:
        ``(L,)`` labels of each trajectory.
    degrees:
        Bézier degrees of the approximation/null/predictor rows.
    n_points:
        Size of the normalised-time grid (the paper's 50).
    up:
        The data's vertical axis (the path frame of ``*_path_loo`` rows; default
        :data:`motion_envs.models.path_frame.DEFAULT_UP`).
    """
    L = traj.n_trajectories
    subjects = np.asarray(subjects).astype(str)
    tasks = np.asarray(tasks).astype(str)
    if subjects.shape != (L,) or tasks.shape != (L,):
        raise ValueError(
            f"subjects and tasks must have shape ({L},); got {subjects.shape} and {tasks.shape}"
        )
    R = slerp_residuals(traj, n_points)
    abar = average_speed_profile(traj, n_points)
    R_avg = slerp_residuals(traj, n_points, average_alpha=abar)
    c: dict[str, float] = {}
    fallbacks: dict[str, int] = {}
    c["within_subject"] = within_subject_error(R, subjects, tasks)
    frame = (traj.starts, traj.ends, DEFAULT_UP if up is None else up)
    for suffix, f in (("", None), ("_path", frame)):
        loo, floor = predictive_floor_errors(R, subjects, tasks, f)
        c[f"within_subject{suffix}_loo"] = float(np.nanmedian(loo))
        c[f"predictive_floor{suffix}"] = float(np.nanmedian(floor))
    c["between_subject"] = between_subject_error(R, tasks)
    c["slerp_empirical"] = median_max_error(R)
    c["slerp_average"] = median_max_error(R_avg)
    grid = normalised_grid(n_points)
    for d in degrees:
        P = fit_control_points(R, d)
        c[f"approximation_d{d}"] = median_max_error(R, bezier.evaluate(P, grid, d))
    for d in degrees:
        c[f"null_d{d}"] = median_max_error(R, NullBezierModel(d).fit(R).predict(n=L))
    c["null_average"] = median_max_error(R, R.mean(axis=0))
    for d in degrees:
        by_subject = SubjectBezierModel(d).fit(R, subjects=subjects)
        c[f"subject_predictor_d{d}"] = median_max_error(R, by_subject.predict(subjects=subjects))
    for d in degrees:
        by_task = TaskBezierModel(d).fit(R, tasks=tasks)
        c[f"task_predictor_d{d}"] = median_max_error(R, by_task.predict(tasks=tasks))
    for d in degrees:
        if np.unique(subjects).size >= 2:
            null_pred, task_pred, n_fb = _leave_one_subject_out(R, subjects, tasks, d)
            c[f"null_d{d}_loso"] = median_max_error(R, null_pred)
            c[f"task_predictor_d{d}_loso"] = median_max_error(R, task_pred)
            fallbacks[f"task_predictor_d{d}_loso"] = n_fb
        else:
            c[f"null_d{d}_loso"] = float("nan")
            c[f"task_predictor_d{d}_loso"] = float("nan")
        loro_pred, n_fb = _leave_one_replicate_out(R, subjects, d)
        c[f"subject_predictor_d{d}_loro"] = median_max_error(R, loro_pred)
        fallbacks[f"subject_predictor_d{d}_loro"] = n_fb
    ordered = {name: c[name] for name in criterion_names(degrees)}
    return Table1Result(criteria=ordered, residuals=R, average_alpha=abar, fallbacks=fallbacks)


def _add_groups(
    sums: FloatArray, counts: NDArray[np.int64], keys: NDArray[np.int64], values: FloatArray
) -> None:
    np.add.at(sums, keys, values)
    np.add.at(counts, keys, 1)


def score_cohort(
    config: CohortConfig | str | os.PathLike[str] = DEFAULT_COHORT,
    chunk_subjects: int = 64,
    degrees: tuple[int, ...] = (2, 3, 4),
    progress: bool = False,
) -> dict[str, float]:
    """The in-sample rows of Table 1 of a cohort, streamed chunk by chunk.

    ``config`` is a :class:`~motion_envs.datasets.cohort_config.CohortConfig`, a cohort
    name or a YAML path (:mod:`motion_envs.datasets.cohort`; simulated data). Gives the
    same values as :func:`table1` (rows
    ``within_subject`` .. ``task_predictor_d{d}`` with the predictive floors; not the
    leave-one-subject-out rows) without
    holding the cohort in memory: two passes over the chunks (the second regenerates
    them, bit-identical), keeping only running sums (mean control points overall, per
    subject and per task; mean curves overall and per task; the mean speed profile) and
    one float per trajectory and criterion for the medians. Memory is
    ``O(chunk + L)`` floats instead of ``O(samples)``.
    """
    from tqdm.auto import tqdm

    from motion_envs.datasets.cohort import CohortGenerator

    gen = CohortGenerator(config)
    n_sub = int(gen.config.get("design.n_subjects"))
    if chunk_subjects < 1:
        raise ValueError(f"chunk_subjects must be >= 1; got {chunk_subjects}")
    chunks = [range(a, min(n_sub, a + chunk_subjects)) for a in range(0, n_sub, chunk_subjects)]
    n_pts = DEFAULT_N_POINTS
    grid = normalised_grid(n_pts)
    J = len(gen.all_tasks)
    subj_of = {name: i for i, name in enumerate(gen.subject_names)}
    task_of = {name: j for j, name in enumerate(gen.all_tasks)}
    P_sum = {d: np.zeros((d - 1, 3)) for d in degrees}
    P_subj = {d: np.zeros((n_sub, d - 1, 3)) for d in degrees}
    P_task = {d: np.zeros((J, d - 1, 3)) for d in degrees}
    n_subj = np.zeros(n_sub, dtype=np.int64)
    n_task = np.zeros(J, dtype=np.int64)
    curve_task = np.zeros((J, n_pts, 3))
    curve_sum = np.zeros((n_pts, 3))
    alpha_sum = np.zeros(n_pts)
    errors: dict[str, list[FloatArray]] = {}
    task_labels: list[NDArray[np.int64]] = []
    L = 0

    def keep(name: str, values: FloatArray) -> None:
        errors.setdefault(name, []).append(values)

    def labels(ds: OrientationDataset) -> tuple[NDArray[np.int64], NDArray[np.int64]]:
        si = np.array([subj_of[s] for s in ds.subjects], dtype=np.int64)
        tj = np.array([task_of[t] for t in ds.tasks], dtype=np.int64)
        return si, tj

    bar = tqdm(total=2 * len(chunks), desc="score cohort", unit="chunk", disable=not progress)
    for chunk in chunks:  # pass 1: sums and the curve-wise criteria
        ds = gen.generate(chunk)
        traj = ds.ragged
        si, tj = labels(ds)
        R = slerp_residuals(traj, n_pts)
        L += R.shape[0]
        alpha_sum += speed_fractions_on_grid(traj, n_pts).sum(axis=0)
        curve_sum += R.sum(axis=0)
        _add_groups(curve_task, n_task, tj, R)
        np.add.at(n_subj, si, 1)
        pair = si * J + tj  # subjects are whole within a chunk, so pairs are too
        _, inv, cnt = np.unique(pair, return_inverse=True, return_counts=True)
        means = np.zeros((cnt.size, n_pts, 3))
        np.add.at(means, inv, R)
        means /= cnt[:, None, None]
        keep("within_subject", max_errors(R, means[inv])[cnt[inv] >= 2])
        for suffix, f in (("", None), ("_path", (traj.starts, traj.ends, ds.up))):
            loo, floor = predictive_floor_errors(R, si, tj, f)
            keep(f"within_subject{suffix}_loo", loo[np.isfinite(loo)])
            keep(f"predictive_floor{suffix}", floor[np.isfinite(floor)])
        keep("slerp_empirical", max_errors(R))
        for d in degrees:
            P = fit_control_points(R, d)
            keep(f"approximation_d{d}", max_errors(R, bezier.evaluate(P, grid, d)))
            P_sum[d] += P.sum(axis=0)
            np.add.at(P_subj[d], si, P)
            np.add.at(P_task[d], tj, P)
        bar.update(1)
    abar = alpha_sum / L
    curve_mean = curve_sum / L
    task_curve = curve_task / np.maximum(n_task, 1)[:, None, None]
    for chunk in chunks:  # pass 2: errors against the global, subject and task means
        ds = gen.generate(chunk)
        traj = ds.ragged
        si, tj = labels(ds)
        R = slerp_residuals(traj, n_pts)
        keep("slerp_average", max_errors(slerp_residuals(traj, n_pts, average_alpha=abar)))
        keep("null_average", max_errors(R, curve_mean))
        keep("between_subject", max_errors(R, task_curve[tj]))
        task_labels.append(tj)
        for d in degrees:
            null = bezier.evaluate(P_sum[d] / L, grid, d)
            keep(f"null_d{d}", max_errors(R, null))
            Ps = P_subj[d][si] / n_subj[si][:, None, None]
            keep(f"subject_predictor_d{d}", max_errors(R, bezier.evaluate(Ps, grid, d)))
            Pt = P_task[d][tj] / n_task[tj][:, None, None]
            keep(f"task_predictor_d{d}", max_errors(R, bezier.evaluate(Pt, grid, d)))
        bar.update(1)
    bar.close()
    out: dict[str, float] = {}
    between = np.concatenate(errors.pop("between_subject"))
    tasks = np.concatenate(task_labels)
    out_between = float(np.median([np.median(between[tasks == j]) for j in np.unique(tasks)]))
    for name in criterion_names(degrees):
        if name == "between_subject":
            out[name] = out_between
        elif name in errors:
            out[name] = float(np.median(np.concatenate(errors[name])))
    out["n_trajectories"] = float(L)
    return out
