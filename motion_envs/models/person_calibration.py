"""Person calibration: a held-out person's reach predicted from K of their other reaches.

Leave one person (subject) out. For every scored trajectory ``l`` of the held-out person
``s``, ``K`` *other* trajectories of ``s`` are drawn at random (never ``l`` itself): the
calibration reaches. A person with fewer than ``K + 1`` trajectories gives all of their
``K_l = n_s - 1`` others. Four rows per ``K``:

``person_k{K}_loso`` (body frame, Bézier degree ``d = 2``, observed timing)
    The shrinkage blend of the person's mean Bézier residual with the population's::

        P_l = w P_cal + (1 - w) P_pop,   w = K_l / (K_l + k0)

    ``P_cal`` is the mean of the fitted control points of the calibration reaches,
    ``P_pop`` the mean over the training people's trajectories (the null model of
    ``null_d2_loso``; ``k0 -> inf`` gives that row). ``k0`` is chosen among
    :data:`K0_GRID` by leave one person out *within the training people only*: each
    training person in turn is predicted from their own calibration draws and the
    population of the other training people; the ``k0`` with the least criterion
    (median over those trajectories of the draw-averaged max error) wins (first on ties).
``person_k{K}_path_loso`` (the same blend in the path frame)
    The blend of the path-frame control points (:mod:`motion_envs.models.path_frame`,
    the frame of ``null_d2_path_loso`` and the learned rows), each reach's prediction
    mapped back with its own frame; ``k0`` chosen the same way on the path-frame errors.
    Its reference is ``null_d2_path_loso`` (``k0 -> inf``), so that calibration is
    compared with the null *of its own frame*.
``person_k{K}_loso_predicted_timing``
    The same blend (``k0`` chosen the same way) on residuals taken against the slerp
    traversed with the training people's mean speed profile, as
    ``slerp_loso_predicted_timing`` and ``null_d2_loso_predicted_timing`` of
    :mod:`baselines.learned.rows` (its reference, ``k0 -> inf``); the inner choice of
    ``k0`` uses the same residuals (the profile of all training people of the fold).
``slerp_person_timing_k{K}_predicted_timing``
    The slerp traversed with the mean speed profile of the calibration reaches (residual
    predicted as 0).

The calibration *summary* (:func:`calibration_features`, :func:`calibration_summaries`) is
what a learned model or an agent is given of the ``K`` calibration reaches: the mean over
them of each reach's own path-frame residual's first :data:`SUMMARY_SINES` sine
coefficients per axis, clipped to ``[-SUMMARY_BOUND, SUMMARY_BOUND]``, then the share
drawn ``m / K`` (``K_l / K``). The coefficient and reaching environments' ``calibration=K``
observation and the ``ridge_person_k{K}_loso``/``mlp_person_k{K}_loso`` rows
(:mod:`baselines.learned.person_rows`) use these two functions.

Calibration draws are repeated ``n_draws`` times (:func:`calibration_draws`, seeded;
the same draws serve all four rows and the inner selection). A trajectory's error is
its max error over time averaged over the draws (the expected error under a random
calibration set); a row's criterion is the median over trajectories of that, the
papers' criterion. Nothing of the held-out person other than the ``K`` drawn
trajectories enters the prediction of ``l``, and nothing of it enters the choice of
``k0`` (tests/test_person_calibration.py poisons the rest to check).
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import ArrayLike, NDArray

from motion_envs._typing import FloatArray
from motion_envs.datasets.ragged import DEFAULT_N_POINTS, RaggedTrajectories, normalised_grid
from motion_envs.geometry import bezier
from motion_envs.geometry.sine_series import basis
from motion_envs.models.bezier_models import fit_control_points
from motion_envs.models.criteria import max_errors
from motion_envs.models.path_frame import DEFAULT_UP, path_frames, to_path_frame
from motion_envs.models.slerp_residual import (
    resample_orientations,
    residuals_against_profiles,
    slerp_residuals,
)
from motion_envs.models.speed_profile import speed_fractions_on_grid

__all__ = [
    "DEFAULT_CALIBRATION",
    "DEFAULT_N_DRAWS",
    "DEFAULT_SEED",
    "K0_GRID",
    "SUMMARY_BOUND",
    "SUMMARY_SINES",
    "PersonCalibration",
    "calibration_draws",
    "calibration_features",
    "calibration_row_names",
    "calibration_summaries",
    "person_blend_loso",
    "person_calibration_rows",
    "person_timing_loso",
]

IntArray = NDArray[np.int64]

#: The K of ``motion-bench orientation --calibration`` in ``motion-bench all``.
DEFAULT_CALIBRATION: tuple[int, ...] = (1, 3, 5, 10)
#: Calibration draws per trajectory (averaged).
DEFAULT_N_DRAWS = 20
#: Seed of the draws (``numpy.random.default_rng([seed, K])``).
DEFAULT_SEED = 0
#: Candidates of the shrinkage constant ``k0`` (0: the person's mean alone).
K0_GRID: tuple[float, ...] = (0.0, 0.5, 1.0, 2.0, 4.0, 8.0, 16.0, 32.0, 64.0, 128.0)
#: Sine terms per path axis of the calibration summary (9 values).
SUMMARY_SINES = 3
#: The summary's mean coefficients are clipped to ``[-SUMMARY_BOUND, SUMMARY_BOUND]``.
SUMMARY_BOUND = 3.0


def calibration_features(path_residuals: ArrayLike) -> FloatArray:
    """``(L, 3 SUMMARY_SINES)`` least-squares coefficients of ``sin(k pi tau)``,
    ``k = 1..SUMMARY_SINES``, of each path-frame residual curve ``(L, n, 3)`` (uniform
    grid; ordered ``(k, axis)``): one row per trajectory, from that trajectory alone."""
    C = np.asarray(path_residuals, dtype=np.float64)
    L, n, w = C.shape
    B = basis(np.linspace(0.0, 1.0, n), SUMMARY_SINES)[:, 2:]
    coef = np.linalg.lstsq(B, C.transpose(1, 0, 2).reshape(n, -1), rcond=None)[0]
    out: FloatArray = coef.reshape(SUMMARY_SINES, L, w).transpose(1, 0, 2).reshape(L, -1)
    return out


def calibration_summaries(features: ArrayLike, draws: IntArray, k: int) -> FloatArray:
    """The calibration summary of every draw: ``(..., f + 1)`` for ``draws`` ``(..., k)``.

    ``features`` ``(L, f)`` (:func:`calibration_features`); ``draws`` holds indices into
    its rows, ``-1`` for none (:func:`calibration_draws`: ``(n_draws, L, k)``; an
    environment's one episode: ``(k,)``). Entry: the mean of the drawn rows' features
    (0 when none is drawn) clipped to ``[-SUMMARY_BOUND, SUMMARY_BOUND]``, then the
    share drawn ``m / k``. Rows not drawn are never read.
    """
    F = np.asarray(features, dtype=np.float64)
    d = np.asarray(draws, dtype=np.int64)
    if d.shape[-1] != k or k < 1:
        raise ValueError(f"draws must end in k = {k} >= 1 entries; got shape {d.shape}")
    valid = d >= 0
    picked = F[np.where(valid, d, 0)]  # (..., k, f)
    counts = valid.sum(axis=-1)
    sums = np.where(valid[..., None], picked, 0.0).sum(axis=-2)
    mean = sums / np.maximum(counts, 1)[..., None]
    summary = np.clip(mean, -SUMMARY_BOUND, SUMMARY_BOUND)
    out: FloatArray = np.concatenate([summary, (counts / k)[..., None]], axis=-1)
    return out


def calibration_row_names(ks: Sequence[int]) -> list[str]:
    """Row names of :func:`person_calibration_rows`, in print order."""
    names = [f"person_k{k}_loso" for k in ks]
    names += [f"person_k{k}_path_loso" for k in ks]
    names += [f"person_k{k}_loso_predicted_timing" for k in ks]
    names += [f"slerp_person_timing_k{k}_predicted_timing" for k in ks]
    return names


def calibration_draws(subjects: ArrayLike, k: int, n_draws: int, seed: int) -> IntArray:
    """Indices ``(n_draws, L, k)`` of the calibration reaches of every trajectory.

    Row ``[r, l]`` holds ``min(k, n_s - 1)`` distinct trajectories of ``l``'s subject,
    never ``l``, drawn uniformly without replacement; the rest is ``-1``. Generator:
    ``numpy.random.default_rng([seed, k])``; subjects in sorted order, one
    ``(n_draws, n_s, n_s)`` uniform block each, ranked per row with ``l`` itself last.
    """
    if k < 1 or n_draws < 1:
        raise ValueError(f"k and n_draws must be >= 1; got {k}, {n_draws}")
    labels = np.asarray(subjects).astype(str)
    rng = np.random.default_rng([seed, k])
    out = np.full((n_draws, labels.size, k), -1, dtype=np.int64)
    for s in np.unique(labels):
        rows = np.flatnonzero(labels == s)
        n = rows.size
        u = rng.random((n_draws, n, n))
        u[:, np.arange(n), np.arange(n)] = 2.0  # the scored trajectory ranks last
        take = min(k, n - 1)
        if take:
            out[:, rows, :take] = rows[np.argsort(u, axis=-1)[..., :take]]
    return out


def _calibration_means(values: FloatArray, draws: IntArray) -> tuple[FloatArray, IntArray]:
    """Mean of ``values[draws]`` over the drawn (non ``-1``) entries, ``(n_draws, L, ...)``,
    and the number drawn per trajectory ``(L,)`` (0 gives zeros)."""
    valid = draws >= 0
    picked = values[np.where(valid, draws, 0)]  # (R, L, k, ...)
    mask = valid.reshape(valid.shape + (1,) * (values.ndim - 1))
    counts = valid[0].sum(axis=-1)
    sums = np.where(mask, picked, 0.0).sum(axis=2)
    return sums / np.maximum(counts, 1).reshape((-1,) + (1,) * (values.ndim - 1)), counts


def _blend_errors(
    R: FloatArray,
    rows: IntArray,
    P_pop: FloatArray,
    P_cal: FloatArray,
    counts: IntArray,
    k0s: Sequence[float],
    degree: int,
    scale: FloatArray | None = None,
) -> FloatArray:
    """Draw-averaged max errors ``(len(k0s), rows.size)`` of the blend for ``rows``
    (times ``scale[rows]``: path-frame curves scored in radians)."""
    grid = normalised_grid(R.shape[1])
    n = counts[rows].astype(np.float64)
    out = np.empty((len(k0s), rows.size))
    for i, k0 in enumerate(k0s):
        w = np.divide(n, n + k0, out=np.zeros_like(n), where=(n + k0) > 0)[:, None, None]
        blend = w * P_cal[:, rows] + (1.0 - w) * P_pop  # (R, m, d-1, 3)
        curves = bezier.evaluate(blend, grid, degree)
        out[i] = np.mean([max_errors(R[rows], c) for c in curves], axis=0)
    return out if scale is None else out * scale[rows]


def person_blend_loso(
    residuals: Callable[[IntArray], FloatArray],
    subjects: ArrayLike,
    draws: IntArray,
    degree: int = 2,
    k0_grid: Sequence[float] = K0_GRID,
    scale: FloatArray | None = None,
) -> tuple[FloatArray, FloatArray, dict[str, float]]:
    """The shrinkage blend, leave one subject out (see the module docstring).

    Parameters
    ----------
    residuals:
        ``residuals(train)`` -> ``(L, n, 3)`` residual curves of every trajectory for the
        fold whose training trajectories are ``train`` (observed timing: the same curves
        for every fold; predicted timing: taken against the training mean profile).
        Only the training rows and the held-out subject's drawn rows are read.
    subjects:
        ``(L,)`` subject of every trajectory.
    draws:
        :func:`calibration_draws` ``(n_draws, L, K)``.
    scale:
        ``(L,)`` path-frame scales ``s`` when the curves are path-frame ones (the body
        error of a path-frame prediction is ``s max_t |p - p_hat|``); None: body frame.

    Returns
    -------
    (errors, predictions, chosen)
        ``(L,)`` draw-averaged max errors, ``(n_draws, L, n, 3)`` predicted curves, and
        the ``k0`` chosen in each held-out subject's fold.
    """
    labels = np.asarray(subjects).astype(str)
    grid_k0 = [float(v) for v in k0_grid]
    errors = np.empty(labels.size)
    predictions: FloatArray | None = None
    chosen: dict[str, float] = {}
    for s in np.unique(labels):
        test = np.flatnonzero(labels == s)
        train = np.flatnonzero(labels != s)
        R = residuals(train)
        if predictions is None:
            predictions = np.empty((draws.shape[0], *R.shape))
        P = fit_control_points(R, degree)
        P_cal, counts = _calibration_means(P, draws)
        # k0 by leave one person out within the training subjects
        inner = []
        for t in np.unique(labels[train]):
            rows = np.flatnonzero(labels == t)
            others = train[labels[train] != t]
            pop = P[others].mean(axis=0)
            inner.append(_blend_errors(R, rows, pop, P_cal, counts, grid_k0, degree, scale))
        scores = np.median(np.concatenate(inner, axis=1), axis=1)
        k0 = grid_k0[int(np.argmin(scores))]
        chosen[str(s)] = k0
        pop = P[train].mean(axis=0)
        errors[test] = _blend_errors(R, test, pop, P_cal, counts, [k0], degree, scale)[0]
        n = counts[test].astype(np.float64)
        w = np.divide(n, n + k0, out=np.zeros_like(n), where=(n + k0) > 0)[:, None, None]
        blend = w * P_cal[:, test] + (1.0 - w) * pop
        predictions[:, test] = bezier.evaluate(blend, normalised_grid(R.shape[1]), degree)
    assert predictions is not None
    return errors, predictions, chosen


def person_timing_loso(
    q_grid: ArrayLike, starts: ArrayLike, ends: ArrayLike, alpha: ArrayLike, draws: IntArray
) -> tuple[FloatArray, FloatArray]:
    """Slerp with the mean speed profile of the calibration reaches.

    ``alpha`` ``(L, n)`` are the observed speed profiles on the grid. Returns the
    draw-averaged max errors ``(L,)`` (residual predicted as 0) and the predicted
    profiles ``(n_draws, L, n)``. A trajectory with no calibration reach (a subject with
    a single trajectory) has NaN.
    """
    A = np.asarray(alpha, dtype=np.float64)
    profiles, counts = _calibration_means(A, draws)
    errs = np.mean(
        [max_errors(residuals_against_profiles(q_grid, starts, ends, p)) for p in profiles],
        axis=0,
    )
    return np.where(counts > 0, errs, np.nan), profiles


@dataclass(frozen=True)
class PersonCalibration:
    """Result of :func:`person_calibration_rows`.

    Attributes
    ----------
    criteria:
        Row name (:func:`calibration_row_names`) -> criterion (radians).
    errors:
        Row name -> ``(L,)`` draw-averaged per-trajectory max errors; also the reference
        rows ``null_d2_loso``, ``null_d2_path_loso``, ``null_d2_loso_predicted_timing``
        and ``slerp_loso_predicted_timing`` (same definitions as
        :mod:`motion_envs.models.criteria` and :mod:`baselines.learned.rows`).
    chosen_k0:
        Row name -> held-out subject -> the ``k0`` chosen on the training subjects.
    n_draws, seed:
        The calibration draws.
    short:
        ``K`` -> number of trajectories whose subject has fewer than ``K`` others.
    """

    criteria: dict[str, float]
    errors: dict[str, FloatArray]
    chosen_k0: dict[str, dict[str, float]] = field(default_factory=dict)
    n_draws: int = DEFAULT_N_DRAWS
    seed: int = DEFAULT_SEED
    short: dict[int, int] = field(default_factory=dict)


def person_calibration_rows(
    traj: RaggedTrajectories,
    subjects: ArrayLike,
    ks: Sequence[int] = DEFAULT_CALIBRATION,
    n_draws: int = DEFAULT_N_DRAWS,
    seed: int = DEFAULT_SEED,
    degree: int = 2,
    n_points: int = DEFAULT_N_POINTS,
    k0_grid: Sequence[float] = K0_GRID,
    up: ArrayLike = DEFAULT_UP,
) -> PersonCalibration:
    """The rows of :func:`calibration_row_names` for every ``K`` of ``ks``.

    Needs at least 3 subjects (2 training subjects for the inner choice of ``k0``);
    ``up`` is the data's vertical axis (the path frame).
    """
    labels = np.asarray(subjects).astype(str)
    levels = np.unique(labels)
    if levels.size < 3:
        raise ValueError(f"person calibration needs at least 3 subjects; got {levels.size}")
    if not ks or any(int(k) < 1 for k in ks):
        raise ValueError(f"ks must be integers >= 1; got {list(ks)}")
    R = slerp_residuals(traj, n_points)
    q_grid = resample_orientations(traj, normalised_grid(n_points))
    A = speed_fractions_on_grid(traj, n_points)
    S, E = traj.starts, traj.ends

    def observed(train: IntArray) -> FloatArray:
        return R

    def predicted(train: IntArray) -> FloatArray:
        return residuals_against_profiles(q_grid, S, E, A[train].mean(axis=0))

    R_path = to_path_frame(R, S, E, up)
    scale = path_frames(S, E, up)[1]

    def path(train: IntArray) -> FloatArray:
        return R_path

    errors: dict[str, FloatArray] = {}
    # the reference rows, on the same residuals (k0 -> infinity: the population alone)
    refs = ("null_d2_loso", "null_d2_path_loso", "null_d2_loso_predicted_timing")
    for name in (*refs, "slerp_loso_predicted_timing"):
        errors[name] = np.empty(labels.size)
    grid = normalised_grid(n_points)
    for s in levels:
        test, train = labels == s, labels != s
        R_pt = predicted(np.flatnonzero(train))
        for name, curves, weight in zip(
            refs, (R, R_path, R_pt), (1.0, scale[test], 1.0), strict=True
        ):
            pop = fit_control_points(curves[train], degree).mean(axis=0)
            pred = bezier.evaluate(pop, grid, degree)
            errors[name][test] = max_errors(curves[test], pred) * weight
        errors["slerp_loso_predicted_timing"][test] = max_errors(R_pt[test])
    chosen: dict[str, dict[str, float]] = {}
    short: dict[int, int] = {}
    for k in ks:
        draws = calibration_draws(labels, int(k), n_draws, seed)
        short[int(k)] = int(np.count_nonzero((draws[0] >= 0).sum(axis=-1) < k))
        name = f"person_k{k}_loso"
        errors[name], _, chosen[name] = person_blend_loso(observed, labels, draws, degree, k0_grid)
        name = f"person_k{k}_path_loso"
        errors[name], _, chosen[name] = person_blend_loso(
            path, labels, draws, degree, k0_grid, scale
        )
        name = f"person_k{k}_loso_predicted_timing"
        errors[name], _, chosen[name] = person_blend_loso(predicted, labels, draws, degree, k0_grid)
        errors[f"slerp_person_timing_k{k}_predicted_timing"] = person_timing_loso(
            q_grid, S, E, A, draws
        )[0]
    criteria = {name: float(np.nanmedian(errors[name])) for name in calibration_row_names(list(ks))}
    return PersonCalibration(criteria, errors, chosen, n_draws, seed, short)
