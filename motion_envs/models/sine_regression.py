"""Sine-series regression of one movement phase (Lippi, Avizzano & Ruffaldi 2011).

Each example ``i`` of a phase (positions ``Y_i`` of ``D`` coordinates, duration ``T_i``)
becomes coefficients ``P_i`` of shape ``(N + 2, D)`` (see
:mod:`motion_envs.geometry.sine_series`), flattened row-major to ``p_i`` of length
``K = (N + 2) D`` (index ``j D + d`` is basis function ``j``, coordinate ``d``). With
user-chosen conditions ``Q_i`` (``q`` values: start, end, or anything known before the
phase starts) the regression of eq. 6 is::

    F = [p_1 .. p_n] pinv([Q_1 .. Q_n; 1 .. 1])            (K, q + 1), intercept last

and generation (eqs. 7-8) ``P = F [Q; 1]``, rows 0 and 1 then overwritten from the
requested start and end, ``Y(t) = Phi(t / T) . P``. ``F_Q`` is ``F`` without its
intercept column: moving ``Q`` by ``dQ`` moves ``p`` by ``F_Q dQ`` along the regression
hyperplane.

Final-velocity constraint (eq. 9), :func:`constrain_final_velocity`. With
``g = dPhi/dtau(1) / T`` the end velocity is ``v = G p``, ``G = g (x) I_D``. We add the
requirement that the start does not move (row 0 of ``dP`` is 0; ``g_0 = 0`` so this
does not compete with the velocity) and solve, with ``A`` these stacked linear
conditions and ``r`` what they lack:

* ``"hyperplane"``: ``dQ = pinv(A F_Q) r``, ``dP = F_Q dQ`` (the paper's text; its eq. 9
  prints the full ``F``, which would also move the constant 1 of ``[Q; 1]``);
* ``"free"``: ``dP = pinv(A) r``, the minimum-norm change of ``P`` (the paper's Fig. 4
  bottom), which for the velocity alone is ``pinv(g) (v_req - v_free)``.

The constraint is applied to the *generated* coefficients (after the start/end
overwrite), so the generated trajectory has exactly the requested end velocity. The safe
default of :meth:`SineSeriesRegression.plan`/``generate`` and of
:func:`constrain_final_velocity` is ``mode="free", fix_end=True``: start and end are held
and only the sine rows change (exact whenever ``N >= 1``). With ``fix_end=False`` the end
position moves (row 1 of ``dP``), as the paper says; ``plan`` reports that shift
(``return_end_shift=True``) and refuses one longer than ``max_end_shift`` (default
:data:`DEFAULT_MAX_END_SHIFT`, in the data's units) unless ``max_end_shift=None``. On the
hyperplane of ``Q = [start, end]`` fixing both ends fixes ``Q``, so
``mode="hyperplane"`` needs ``fix_end=False``.

Online correction (eq. 10), :func:`correct_online`: at ``tau_1`` the executed state is
``y_1`` (and optionally velocity ``v_1``), the target is now ``y_f``. The new ``P' = P +
dP`` satisfies, per coordinate, ``Phi(tau_1) P' = y_1``, ``Phi(1) P' = y_f`` and
optionally ``dPhi(tau_1) P' / T = v_1``, with the smallest ``dP`` (``"free"``, the
paper's eq. 10) or the smallest ``dQ`` with ``dP = F_Q dQ`` (``"hyperplane"``, raises
``ValueError`` when the hyperplane cannot meet the conditions). The executed past is
unchanged: the corrected plan is used only for ``tau >= tau_1``
(:func:`evaluate_corrected`).

Validation of the linear hypothesis (:func:`validate_linear_hypothesis`): per
coefficient, the ordinary least-squares fit of ``p_{i,k}`` on ``[Q_i, 1]`` (statsmodels),
the Lilliefors normality test of its residuals, the regression F-test, 95 % confidence
intervals of the row of ``F`` and its jackknife variance
``(n - 1)/n sum_i (F_(i) - mean F_(.))^2`` over leave-one-out fits.
"""

from __future__ import annotations

import warnings
from collections.abc import Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, Literal, overload

import numpy as np
from numpy.typing import ArrayLike, NDArray

from motion_envs._typing import FloatArray
from motion_envs.datasets.ragged import MIN_SAMPLES
from motion_envs.geometry import sine_series as ss
from motion_envs.geometry.resampling import recording_times
from motion_envs.models._sklearn import check_order, criterion_score, score_times
from motion_envs.models.estimator import check_is_fitted
from motion_envs.models.serialization import SerializableModel, State, StateSchema

__all__ = [
    "DEFAULT_MAX_END_SHIFT",
    "MIN_SAMPLES",
    "ExtrapolationWarning",
    "LinearHypothesisReport",
    "RankDeficientDesignWarning",
    "SineSeriesRegression",
    "constrain_final_velocity",
    "correct_online",
    "evaluate_corrected",
    "regression_matrix",
    "select_n_sines",
    "trajectory_coefficients",
    "validate_linear_hypothesis",
]

if TYPE_CHECKING:
    import pandas as pd

Mode = Literal["hyperplane", "free"]

#: Largest end-point shift (Euclidean, in the data's units: 1 mm for positions in metres)
#: that :meth:`SineSeriesRegression.plan` accepts from an eq. 9 correction with
#: ``fix_end=False`` unless the caller passes ``max_end_shift=None``.
DEFAULT_MAX_END_SHIFT = 1e-3


class RankDeficientDesignWarning(UserWarning):
    """The condition design ``[Q; 1]`` has lower rank than its number of rows."""


class ExtrapolationWarning(UserWarning):
    """A prediction from conditions outside the range of the training conditions."""


def _as_conditions(conditions: ArrayLike, name: str = "conditions") -> FloatArray:
    q = np.asarray(conditions, dtype=np.float64)
    if q.ndim == 1:
        q = q[:, None]
    if q.ndim != 2:
        raise ValueError(f"{name} must be (n, q) (one row per example); got shape {q.shape}")
    if not np.all(np.isfinite(q)):
        raise ValueError(f"{name} contains NaN or infinite values")
    return q


def _time_base(
    positions: Sequence[ArrayLike],
    times: Sequence[ArrayLike] | Literal["normalised"] | None,
    rate: float | None,
    caller: str,
) -> Sequence[ArrayLike] | None:
    """``times`` in seconds (from ``times`` or ``rate``), or None for ``"normalised"``."""
    if isinstance(times, str):
        if times != "normalised" or rate is not None:
            raise ValueError(
                f"times must be arrays in seconds or 'normalised' (without rate); got {times!r}"
            )
        return None
    if times is None and rate is None:
        raise ValueError(
            f"{caller} needs the time base: times= (seconds, one array per trajectory) "
            "or rate= (Hz); times='normalised' fits on normalised time with unit "
            "durations"
        )
    return recording_times(positions, times, rate)


def trajectory_coefficients(
    positions: Sequence[ArrayLike],
    n_sines: int,
    times: Sequence[ArrayLike] | Literal["normalised"] | None = None,
    min_samples: int = MIN_SAMPLES,
    *,
    rate: float | None = None,
) -> tuple[FloatArray, FloatArray]:
    """Coefficients ``(n, N + 2, D)`` and durations ``(n,)`` of a list of trajectories.

    ``positions[i]`` is ``(n_i, D)``. The time base is required, as in
    :meth:`SineSeriesRegression.fit`: ``times[i]`` ``(n_i,)`` strictly increasing
    seconds, or ``rate`` (Hz), or ``times="normalised"`` (uniform samples of unit
    duration). Uniform samples use the DST, others least squares.
    """
    if len(positions) == 0:
        raise ValueError("positions must contain at least one trajectory")
    times = _time_base(positions, times, rate, "trajectory_coefficients")
    if times is not None and len(times) != len(positions):
        raise ValueError(
            f"times must have one array per trajectory; got {len(times)} for {len(positions)}"
        )
    coefs, durations = [], []
    dims = None
    for i, y in enumerate(positions):
        y = np.asarray(y, dtype=np.float64)
        if y.ndim != 2:
            raise ValueError(f"positions[{i}] must be (n, D); got shape {y.shape}")
        if dims is None:
            dims = y.shape[1]
        elif y.shape[1] != dims:
            raise ValueError(f"positions[{i}] has {y.shape[1]} coordinates, expected {dims}")
        if y.shape[0] < min_samples:
            raise ValueError(
                f"positions[{i}] has {y.shape[0]} samples, at least {min_samples} needed"
            )
        if not np.all(np.isfinite(y)):
            raise ValueError(f"positions[{i}] contains NaN or infinite values")
        if times is None:
            tau, duration = np.linspace(0.0, 1.0, y.shape[0]), 1.0
        else:
            t = np.asarray(times[i], dtype=np.float64)
            if t.shape != (y.shape[0],):
                raise ValueError(f"times[{i}] must have shape ({y.shape[0]},); got {t.shape}")
            try:
                tau = ss.normalised_time(t)
            except ValueError as exc:
                raise ValueError(f"times[{i}]: {exc}") from None
            duration = float(t[-1] - t[0])
        try:
            coefs.append(ss.fit_coefficients(tau, y, n_sines))
        except ValueError as exc:
            raise ValueError(f"positions[{i}]: {exc}") from None
        durations.append(duration)
    return np.stack(coefs), np.asarray(durations)


def regression_matrix(
    coefficients: ArrayLike, conditions: ArrayLike, warn: bool = True
) -> tuple[FloatArray, int]:
    """``F = [p_1 .. p_n] pinv([Q; 1])`` (eq. 6) and the rank of ``[Q; 1]``.

    ``coefficients`` is ``(n, ...)`` (flattened to ``(n, K)``), ``conditions`` ``(n, q)``;
    returns ``F`` of shape ``(K, q + 1)`` (intercept last). Warns with
    :class:`RankDeficientDesignWarning` when ``rank([Q; 1]) < q + 1`` (e.g. a condition
    constant over the examples, or fewer examples than ``q + 1``): ``F`` is then the
    minimum-norm solution and its columns are not individually identifiable.
    """
    p = np.asarray(coefficients, dtype=np.float64)
    q = _as_conditions(conditions)
    if p.shape[0] != q.shape[0]:
        raise ValueError(
            f"coefficients and conditions must have one row per example; got {p.shape[0]} "
            f"and {q.shape[0]}"
        )
    p = p.reshape(p.shape[0], -1)
    design = np.column_stack([q, np.ones(q.shape[0])])
    rank = int(np.linalg.matrix_rank(design))
    if warn and rank < design.shape[1]:
        constant = [j for j in range(q.shape[1]) if np.ptp(q[:, j]) == 0.0]
        why = f"; condition columns {constant} are constant" if constant else ""
        warnings.warn(
            f"rank-deficient regression: the design [Q; 1] of {q.shape[0]} examples x "
            f"{q.shape[1] + 1} columns has rank {rank}{why}. F is the minimum-norm "
            "pseudo-inverse solution; drop redundant conditions for identifiable F.",
            RankDeficientDesignWarning,
            stacklevel=2,
        )
    return p.T @ np.linalg.pinv(design.T), rank


def _solve(
    a: FloatArray, r: FloatArray, f_q: FloatArray | None, mode: Mode, what: str
) -> FloatArray:
    """Smallest ``x`` (``dP``, or ``dQ`` mapped through ``F_Q``) with ``a x = r``; checks it."""
    if mode == "free":
        dp = np.linalg.pinv(a) @ r
    elif mode == "hyperplane":
        if f_q is None:
            raise ValueError("mode='hyperplane' needs the regression's F_Q (f_q)")
        dp = f_q @ (np.linalg.pinv(a @ f_q) @ r)
    else:
        raise ValueError(f"mode must be 'hyperplane' or 'free'; got {mode!r}")
    miss = np.max(np.abs(a @ dp - r), initial=0.0)
    scale = max(1.0, float(np.max(np.abs(r), initial=0.0)))
    if miss > 1e-9 * scale:
        raise ValueError(
            f"{what}: the {mode} correction cannot meet the conditions "
            f"(residual {miss:.3g}); the hyperplane has too few directions "
            "(use mode='free' or more conditions Q)"
        )
    return dp


def _check_p(coefficients: ArrayLike) -> FloatArray:
    p = np.asarray(coefficients, dtype=np.float64)
    if p.ndim != 2 or p.shape[0] < 2:
        raise ValueError(f"coefficients must be (N + 2, D); got shape {p.shape}")
    if not np.all(np.isfinite(p)):
        raise ValueError("coefficients contains NaN or infinite values")
    return p


def _check_fq(f_q: ArrayLike | None, k: int) -> FloatArray | None:
    if f_q is None:
        return None
    f_q = np.asarray(f_q, dtype=np.float64)
    if f_q.ndim != 2 or f_q.shape[0] != k:
        raise ValueError(f"f_q must be (K, q) with K = {k}; got shape {f_q.shape}")
    return f_q


def _check_duration(duration: float) -> float:
    duration = float(duration)
    if not np.isfinite(duration) or duration <= 0:
        raise ValueError(f"duration must be finite and > 0; got {duration}")
    return duration


def _vector(value: ArrayLike, dims: int, name: str) -> FloatArray:
    v = np.asarray(value, dtype=np.float64)
    if v.shape != (dims,):
        raise ValueError(f"{name} must have shape ({dims},); got {v.shape}")
    if not np.all(np.isfinite(v)):
        raise ValueError(f"{name} contains NaN or infinite values")
    return v


def constrain_final_velocity(
    coefficients: ArrayLike,
    velocity: ArrayLike,
    duration: float,
    f_q: ArrayLike | None = None,
    mode: Mode = "free",
    axes: Sequence[int] | None = None,
    fix_end: bool = True,
) -> FloatArray:
    """Eq. 9: change ``P`` so that ``dPhi/dtau(1) . P / T = v_req`` on ``axes``.

    ``coefficients`` ``(N + 2, D)`` are the generated ones (start/end already set);
    ``velocity`` is ``(D,)`` (only ``axes`` are used; default all). The start never moves;
    ``fix_end=True`` (default) also keeps the end position, ``fix_end=False`` lets it
    move (the paper's form). ``mode="free"`` (default): ``dP = pinv(A) r``, the
    minimum-norm change; ``mode="hyperplane"``: ``dP = F_Q pinv(A F_Q) r`` (needs
    ``f_q``, ``(K, q)``, and in general ``fix_end=False``). Returns the new coefficients;
    raises ``ValueError`` if the conditions cannot be met.
    """
    p = _check_p(coefficients)
    n_basis, dims = p.shape
    f_q = _check_fq(f_q, p.size)
    duration = _check_duration(duration)
    v_req = _vector(velocity, dims, "velocity")
    axes = list(range(dims)) if axes is None else [int(a) for a in axes]
    if not axes or any(a < 0 or a >= dims for a in axes):
        raise ValueError(f"axes must be coordinate indices in [0, {dims}); got {axes}")
    eye = np.eye(dims)
    g = ss.basis_derivative(1.0, n_basis - 2) / duration
    rows = [np.kron(g[None, :], eye)[axes], np.kron(np.eye(n_basis)[:1], eye)]
    if fix_end:
        rows.append(np.kron(np.eye(n_basis)[1:2], eye))
    a = np.concatenate(rows)
    v_free = (g @ p)[axes]
    r = np.concatenate([v_req[axes] - v_free, np.zeros(a.shape[0] - len(axes))])
    dp = _solve(a, r, f_q, mode, "constrain_final_velocity")
    return p + dp.reshape(n_basis, dims)


def correct_online(
    coefficients: ArrayLike,
    tau1: float,
    position: ArrayLike,
    target: ArrayLike,
    duration: float,
    velocity: ArrayLike | None = None,
    f_q: ArrayLike | None = None,
    mode: Mode = "free",
) -> FloatArray:
    """Eq. 10: the smallest change of the plan ``P`` that restarts from the executed state.

    Conditions on ``P' = P + dP`` (per coordinate): ``Phi(tau1) P' = position``,
    ``Phi(1) P' = target`` and, if ``velocity`` is given, ``dPhi(tau1) P' / T = velocity``.
    ``mode="free"``: ``dP = pinv(A) r`` (paper's eq. 10); ``"hyperplane"``:
    ``dP = F_Q pinv(A F_Q) r`` with ``A = [rows] (x) I_D`` (needs ``f_q``). Use the result
    only for ``tau >= tau1`` (:func:`evaluate_corrected`).
    """
    p = _check_p(coefficients)
    n_basis, dims = p.shape
    f_q = _check_fq(f_q, p.size)
    duration = _check_duration(duration)
    tau1 = float(tau1)
    if not 0.0 <= tau1 < 1.0:
        raise ValueError(f"tau1 must be in [0, 1); got {tau1}")
    n = n_basis - 2
    rows = [ss.basis(tau1, n), ss.basis(1.0, n)]
    wanted = [_vector(position, dims, "position"), _vector(target, dims, "target")]
    if velocity is not None:
        rows.append(ss.basis_derivative(tau1, n) / duration)
        wanted.append(_vector(velocity, dims, "velocity"))
    a1 = np.stack(rows)
    if a1.shape[0] > n_basis:
        raise ValueError(f"{a1.shape[0]} conditions need N + 2 >= {a1.shape[0]} basis functions")
    r = np.stack(wanted) - a1 @ p  # (c, D)
    if mode == "free":
        dp = _solve(a1, r, None, "free", "correct_online")
    else:
        a = np.kron(a1, np.eye(dims)).astype(np.float64, copy=False)
        dp = _solve(a, r.reshape(-1), f_q, mode, "correct_online").reshape(n_basis, dims)
    return p + dp


def evaluate_corrected(
    original: ArrayLike, corrected: ArrayLike, tau1: float, tau: ArrayLike
) -> FloatArray:
    """Executed, then corrected: ``Phi(tau) P`` for ``tau < tau1``, ``Phi(tau) P'`` after."""
    tau = np.asarray(tau, dtype=np.float64)
    before = ss.evaluate(original, tau)
    after = ss.evaluate(corrected, tau)
    return np.where((tau < tau1)[:, None], before, after)


class SineSeriesRegression(SerializableModel):
    """Lippi et al.'s model of one phase: sine series + linear regression on conditions.

    Parameters
    ----------
    n_sines:
        Number ``N`` of sine terms (choose it with :func:`select_n_sines`).

    Fitted attributes
    -----------------
    ``coefficients_`` ``(n, N + 2, D)``, ``conditions_`` ``(n, q)``, ``durations_``
    ``(n,)``, ``F_`` ``((N + 2) D, q + 1)`` (intercept last), ``rank_`` (rank of
    ``[Q; 1]``).
    """

    def __init__(self, n_sines: int = 8) -> None:
        self.n_sines = n_sines

    def fit(
        self,
        X: ArrayLike,
        y: Sequence[ArrayLike],
        times: Sequence[ArrayLike] | Literal["normalised"] | None = None,
        *,
        rate: float | None = None,
    ) -> SineSeriesRegression:
        """Fit eq. 6: conditions ``X`` ``(n, q)`` and trajectories ``y[i]`` ``(n_i, D)``.

        scikit-learn's order: ``X`` the conditions ``Q`` (one row per trajectory), ``y``
        the trajectories. The time base is required: ``times`` (seconds, one ``(n_i,)``
        float array per trajectory) or ``rate`` (Hz, ``t_k = k / rate``); ``durations_``
        are then in seconds and :meth:`plan` velocities per second.
        ``times="normalised"`` fits on normalised time ``tau_k = k / (n_i - 1)`` with
        unit durations (for data already time-normalised). Integer ``times`` (sample
        indices) are refused. Returns ``self``.
        """
        check_order(X, y, type(self).__name__, "the conditions (n, q)")
        ts = _time_base(y, times, rate, "fit")
        coefs, durations = trajectory_coefficients(
            y, self.n_sines, "normalised" if ts is None else ts
        )
        return self.fit_coefficients(coefs, X, durations)

    def score(
        self,
        X: ArrayLike,
        y: Sequence[ArrayLike],
        times: Sequence[ArrayLike] | None = None,
        *,
        rate: float | None = None,
    ) -> float:
        """``-median_l max_t |y_l(t) - yhat_l(t)|``: the negative of the papers' criterion.

        ``yhat_l = predict(X[l], duration=T_l, times=t - t_0, start=y_l(t_0),
        end=y_l(t_end))`` (eqs. 7-8 with the trajectory's own end points and duration,
        as :func:`~motion_envs.models.fit_errors.position_fit_errors`); greater is
        better (scikit-learn's model selection). Without ``times`` and ``rate`` the
        samples are taken as uniform (the criterion is the same for any rate).
        """
        check_order(X, y, type(self).__name__, "the conditions (n, q)")
        q = _as_conditions(X)
        ts = score_times(y, times, rate)
        self._warn_extrapolation(q)  # one warning for all the movements scored

        def errors(i: int, t0: FloatArray) -> FloatArray:
            v = np.asarray(y[i], dtype=np.float64)
            fit = self.predict(q[i], duration=float(t0[-1]), times=t0, start=v[0], end=v[-1])
            return np.linalg.norm(fit - v, axis=1)

        with warnings.catch_warnings():
            warnings.simplefilter("ignore", ExtrapolationWarning)
            return criterion_score(ts, errors)

    def fit_coefficients(
        self, coefficients: ArrayLike, conditions: ArrayLike, durations: ArrayLike | None = None
    ) -> SineSeriesRegression:
        """Fit the regression (eq. 6) from precomputed coefficients ``(n, N + 2, D)``."""
        p = np.asarray(coefficients, dtype=np.float64)
        if p.ndim != 3 or p.shape[1] != self.n_sines + 2:
            raise ValueError(
                f"coefficients must be (n, N + 2 = {self.n_sines + 2}, D); got {p.shape}"
            )
        q = _as_conditions(conditions)
        f, rank = regression_matrix(p, q)
        self.coefficients_ = p
        self.conditions_ = q
        self.durations_ = (
            np.ones(p.shape[0]) if durations is None else np.asarray(durations, dtype=np.float64)
        )
        self.F_ = f
        self.rank_ = rank
        return self

    # -- fitted shape helpers -------------------------------------------------------
    def _fitted(self) -> None:
        check_is_fitted(self, "F_")

    @property
    def n_dims_(self) -> int:
        self._fitted()
        return int(self.coefficients_.shape[2])

    @property
    def F_Q_(self) -> FloatArray:
        """``F`` without its intercept column: the hyperplane directions."""
        self._fitted()
        return self.F_[:, :-1]

    # -- generation -----------------------------------------------------------------
    def predict_coefficients(
        self,
        conditions: ArrayLike,
        start: ArrayLike | None = None,
        end: ArrayLike | None = None,
    ) -> FloatArray:
        """``P = F [Q; 1]`` (eq. 7), rows 0/1 overwritten from ``start``/``end`` if given.

        ``conditions`` ``(q,)`` gives ``(N + 2, D)``; ``(m, q)`` gives ``(m, N + 2, D)``
        (``start``/``end`` then ``(m, D)``).
        """
        self._fitted()
        q = np.asarray(conditions, dtype=np.float64)
        single = q.ndim == 1
        q = _as_conditions(q[None, :] if single else q)
        if q.shape[1] != self.conditions_.shape[1]:
            raise ValueError(
                f"conditions must have {self.conditions_.shape[1]} values; got {q.shape[1]}"
            )
        p = (np.column_stack([q, np.ones(q.shape[0])]) @ self.F_.T).reshape(
            q.shape[0], self.n_sines + 2, self.n_dims_
        )
        shape = (q.shape[0], self.n_dims_)
        if start is not None:
            s = np.broadcast_to(np.asarray(start, dtype=np.float64), shape)
            if not np.all(np.isfinite(s)):
                raise ValueError("start contains NaN or infinite values")
            end_now = p[:, 0] + p[:, 1]
            p[:, 0] = s
            p[:, 1] = end_now - s
        if end is not None:
            e = np.broadcast_to(np.asarray(end, dtype=np.float64), shape)
            if not np.all(np.isfinite(e)):
                raise ValueError("end contains NaN or infinite values")
            p[:, 1] = e - p[:, 0]
        return p[0] if single else p

    def predict(
        self,
        conditions: ArrayLike,
        duration: ArrayLike,
        times: ArrayLike | None = None,
        *,
        start: ArrayLike | None = None,
        end: ArrayLike | None = None,
        final_velocity: ArrayLike | None = None,
        mode: Mode = "free",
        axes: Sequence[int] | None = None,
        fix_end: bool = True,
        max_end_shift: float | None = DEFAULT_MAX_END_SHIFT,
    ) -> FloatArray:
        """Positions predicted from conditions at ``times`` (s since the phase start).

        ``conditions`` ``(q,)`` gives ``(K, D)``; ``(m, q)`` gives ``(m, K, D)`` (then
        ``duration`` is a scalar or ``(m,)``, ``start``/``end`` ``(m, D)``). ``times``
        ``(K,)`` lie in ``[0, T]``; default 100 uniform samples. Each phase is planned by
        :meth:`plan` (eqs. 7-9, same keywords) and evaluated at ``tau = t / T`` (eq. 8).

        A condition outside the range ``[min, max]`` of the training conditions (a column
        of ``conditions_``) raises an :class:`ExtrapolationWarning` naming the column,
        its value, the range and how many training SD it lies from their mean: eq. 7 is
        linear, so such a prediction extrapolates (:meth:`plan` and
        :meth:`predict_coefficients`, the controllers' calls, do not warn).
        """
        q = np.asarray(conditions, dtype=np.float64)
        single = q.ndim == 1
        q2 = q[None] if single else q
        self._warn_extrapolation(q2)
        m = q2.shape[0]
        durations = np.broadcast_to(np.asarray(duration, dtype=np.float64), (m,))
        starts = None if start is None else np.broadcast_to(start, (m, self.n_dims_))
        ends = None if end is None else np.broadcast_to(end, (m, self.n_dims_))
        out = []
        for i in range(m):
            p = self.plan(
                q2[i], float(durations[i]),
                None if starts is None else starts[i], None if ends is None else ends[i],
                final_velocity, mode, axes, fix_end=fix_end, max_end_shift=max_end_shift,
            )  # fmt: skip
            if times is None:
                tau = np.linspace(0.0, 1.0, 100)
            else:
                t = np.asarray(times, dtype=np.float64)
                if t.ndim != 1 or np.any(t < 0) or np.any(t > durations[i] * (1 + 1e-12)):
                    raise ValueError(
                        f"times must be (K,) seconds within [0, duration = {durations[i]:g}]"
                    )
                tau = np.minimum(t / durations[i], 1.0)
            out.append(ss.evaluate(p, tau))
        return out[0] if single else np.stack(out)

    def _warn_extrapolation(self, q: FloatArray) -> None:
        """:class:`ExtrapolationWarning` when a row of ``q`` lies outside the range of the
        training conditions: the worst column, how many SD from the training mean."""
        self._fitted()
        train = self.conditions_
        if q.ndim != 2 or q.shape[1] != train.shape[1] or not np.all(np.isfinite(q)):
            return  # predict_coefficients reports the bad shape or value
        lo, hi = train.min(axis=0), train.max(axis=0)
        tol = 1e-9 * np.maximum(np.maximum(np.abs(lo), np.abs(hi)), 1.0)
        outside = (q < lo - tol) | (q > hi + tol)
        if not outside.any():
            return
        mean = train.mean(axis=0)
        sd = train.std(axis=0, ddof=1) if train.shape[0] > 1 else np.zeros_like(mean)
        with np.errstate(divide="ignore", invalid="ignore"):
            z = np.where(sd > 0, np.abs(q - mean) / np.where(sd > 0, sd, 1.0), np.inf)
        i, j = np.unravel_index(np.argmax(np.where(outside, z, -1.0)), q.shape)
        rows = int(outside.any(axis=1).sum())
        how = f"{z[i, j]:.1f} SD from their mean {mean[j]:.4g}" if sd[j] > 0 else "constant"
        warnings.warn(
            f"{type(self).__name__}: condition {j} (column {j} of the conditions) = "
            f"{q[i, j]:.4g} is outside the range of the training conditions "
            f"[{lo[j]:.4g}, {hi[j]:.4g}], {how} (training SD {sd[j]:.4g}); "
            f"{rows} of {q.shape[0]} movement(s) outside the range: eq. 7 is linear in the "
            "conditions, so the prediction extrapolates",
            ExtrapolationWarning,
            stacklevel=3,
        )

    def generate(
        self,
        conditions: ArrayLike,
        duration: float,
        n_points: int = 100,
        start: ArrayLike | None = None,
        end: ArrayLike | None = None,
        final_velocity: ArrayLike | None = None,
        mode: Mode = "free",
        axes: Sequence[int] | None = None,
        *,
        fix_end: bool = True,
        max_end_shift: float | None = DEFAULT_MAX_END_SHIFT,
    ) -> tuple[FloatArray, FloatArray]:
        """Times ``(n_points,)`` and positions ``(n_points, D)`` of one generated phase.

        ``Y(t) = Phi(t / T) . P`` (eq. 8) with ``P`` from :meth:`plan` (same
        ``final_velocity``/``mode``/``axes``/``fix_end``/``max_end_shift``, eq. 9).
        Like :meth:`predict`, warns (:class:`ExtrapolationWarning`) for conditions
        outside the range of the training conditions.
        """
        self._warn_extrapolation(np.atleast_2d(np.asarray(conditions, dtype=np.float64)))
        p = self.plan(
            conditions,
            duration,
            start,
            end,
            final_velocity,
            mode,
            axes,
            fix_end=fix_end,
            max_end_shift=max_end_shift,
        )
        tau = np.linspace(0.0, 1.0, int(n_points))
        return tau * duration, ss.evaluate(p, tau)

    @overload
    def plan(
        self,
        conditions: ArrayLike,
        duration: float,
        start: ArrayLike | None = ...,
        end: ArrayLike | None = ...,
        final_velocity: ArrayLike | None = ...,
        mode: Mode = ...,
        axes: Sequence[int] | None = ...,
        *,
        fix_end: bool = ...,
        max_end_shift: float | None = ...,
        return_end_shift: Literal[False] = ...,
    ) -> FloatArray: ...

    @overload
    def plan(
        self,
        conditions: ArrayLike,
        duration: float,
        start: ArrayLike | None = ...,
        end: ArrayLike | None = ...,
        final_velocity: ArrayLike | None = ...,
        mode: Mode = ...,
        axes: Sequence[int] | None = ...,
        *,
        fix_end: bool = ...,
        max_end_shift: float | None = ...,
        return_end_shift: Literal[True],
    ) -> tuple[FloatArray, FloatArray]: ...

    def plan(
        self,
        conditions: ArrayLike,
        duration: float,
        start: ArrayLike | None = None,
        end: ArrayLike | None = None,
        final_velocity: ArrayLike | None = None,
        mode: Mode = "free",
        axes: Sequence[int] | None = None,
        *,
        fix_end: bool = True,
        max_end_shift: float | None = DEFAULT_MAX_END_SHIFT,
        return_end_shift: bool = False,
    ) -> FloatArray | tuple[FloatArray, FloatArray]:
        """Coefficients ``(N + 2, D)`` of one phase (eq. 7), with the optional eq. 9 constraint.

        Parameters
        ----------
        conditions:
            ``Q`` of this phase, ``(q,)``.
        duration:
            ``T`` in seconds.
        start, end:
            ``(D,)`` positions that overwrite rows 0/1 of ``P`` (else predicted from ``Q``).
        final_velocity:
            ``(D,)`` end velocity to impose (eq. 9; only ``axes`` are used, default all).
        mode:
            ``"free"`` (default, minimum-norm change of ``P``) or ``"hyperplane"``
            (change along ``F_Q``, the paper's text; needs ``fix_end=False`` and the start
            among the conditions).
        fix_end:
            Hold the end point (default). ``False`` lets eq. 9 move it.
        max_end_shift:
            Refuse (``ValueError``) a plan whose end point moved farther than this
            (Euclidean, data units; default :data:`DEFAULT_MAX_END_SHIFT`); ``None``
            accepts any shift.
        return_end_shift:
            Also return the end-point shift ``(D,)`` caused by eq. 9.
        """
        _check_duration(duration)
        q = np.asarray(conditions, dtype=np.float64)
        if q.ndim != 1:
            raise ValueError(f"conditions must be (q,) for one phase; got shape {q.shape}")
        if max_end_shift is not None and not (
            np.isfinite(max_end_shift) and float(max_end_shift) >= 0
        ):
            raise ValueError(f"max_end_shift must be >= 0 or None; got {max_end_shift!r}")
        p0 = self.predict_coefficients(q, start, end)
        p = p0
        if final_velocity is not None:
            try:
                p = constrain_final_velocity(
                    p0, final_velocity, duration, f_q=self.F_Q_, mode=mode, axes=axes,
                    fix_end=fix_end,
                )  # fmt: skip
            except ValueError as exc:
                if mode == "hyperplane" and fix_end and "cannot meet" in str(exc):
                    raise ValueError(
                        f"{exc}; on the hyperplane pass fix_end=False to let the end move "
                        "(the shift is checked against max_end_shift)"
                    ) from None
                raise
        shift = (p[0] + p[1]) - (p0[0] + p0[1])
        size = float(np.linalg.norm(shift))
        if max_end_shift is not None and size > float(max_end_shift):
            raise ValueError(
                f"final_velocity: the {mode} eq. 9 correction moves the end point by "
                f"{np.array2string(shift, precision=4)} (|shift| = {size:.4g} > "
                f"max_end_shift = {float(max_end_shift):g}); pass fix_end=True to hold the "
                "end, or max_end_shift=None to accept the shift"
            )
        return (p, shift) if return_end_shift else p

    def correct(
        self,
        coefficients: ArrayLike,
        tau1: float,
        position: ArrayLike,
        target: ArrayLike,
        duration: float,
        velocity: ArrayLike | None = None,
        mode: Mode = "free",
    ) -> FloatArray:
        """Eq. 10 with this model's hyperplane (see :func:`correct_online`)."""
        self._fitted()
        return correct_online(
            coefficients, tau1, position, target, duration, velocity, self.F_Q_, mode
        )

    def validate(self) -> LinearHypothesisReport:
        """The paper's validation of the linear hypothesis on the training examples."""
        self._fitted()
        return validate_linear_hypothesis(self.coefficients_, self.conditions_)

    # -- serialization --------------------------------------------------------------
    def _get_state(self) -> State:
        self._fitted()
        arrays = {
            "coefficients": self.coefficients_,
            "conditions": self.conditions_,
            "durations": self.durations_,
            "F": self.F_,
        }
        return {"n_sines": int(self.n_sines)}, arrays, {"rank": self.rank_}

    state_schema = StateSchema(
        params={"n_sines": "int"},
        arrays={
            "coefficients": ("float64", 3),
            "conditions": ("float64", 2),
            "durations": ("float64", 1),
            "F": ("float64", 2),
        },
        attributes={"rank": "int"},
    )

    @classmethod
    def _from_params(cls, params: dict[str, Any]) -> SineSeriesRegression:
        n_sines = params["n_sines"]
        if n_sines < 0:
            raise ValueError(f"field params.n_sines: must be >= 0; got {n_sines}")
        return cls(n_sines=int(n_sines))

    def _set_state(self, arrays: dict[str, NDArray[Any]], attributes: dict[str, Any]) -> None:
        p, q, f = arrays["coefficients"], arrays["conditions"], arrays["F"]
        d = arrays["durations"]
        if p.shape[0] < 1 or p.shape[1] != self.n_sines + 2 or p.shape[2] < 1:
            raise ValueError(
                f"field arrays.coefficients: shape {list(p.shape)} does not match "
                f"(n >= 1, n_sines + 2 = {self.n_sines + 2}, D >= 1)"
            )
        if q.shape[0] != p.shape[0]:
            raise ValueError(
                f"field arrays.conditions: {q.shape[0]} rows; coefficients has {p.shape[0]}"
            )
        if d.shape != (p.shape[0],):
            raise ValueError(
                f"field arrays.durations: shape {list(d.shape)} does not match ({p.shape[0]},)"
            )
        if f.shape != (p.shape[1] * p.shape[2], q.shape[1] + 1):
            raise ValueError(
                f"field arrays.F: shape {list(f.shape)} does not match "
                f"({p.shape[1] * p.shape[2]}, {q.shape[1] + 1})"
            )
        rank = attributes["rank"]
        if not 0 <= rank <= q.shape[1] + 1:
            raise ValueError(f"field attributes.rank: must be in [0, {q.shape[1] + 1}]; got {rank}")
        self.coefficients_, self.conditions_ = p, q
        self.durations_, self.F_ = d, f
        self.rank_ = int(rank)


@dataclass(frozen=True)
class LinearHypothesisReport:
    """Per-coefficient statistics of the regression ``p_k ~ [Q, 1]``.

    ``K = (N + 2) D`` rows, coefficient ``k`` is basis function ``basis_index[k]`` of
    coordinate ``coordinate[k]``. ``exact[k]`` marks coefficients that the conditions
    determine exactly (residuals ~ 0, e.g. start and end rows when ``Q`` is
    ``[start, end]``): their tests are NaN.
    """

    basis_index: NDArray[np.int64]
    coordinate: NDArray[np.int64]
    F: FloatArray  # (K, q + 1)
    ci_low: FloatArray  # (K, q + 1), 95 %
    ci_high: FloatArray
    jackknife_var: FloatArray  # (K, q + 1)
    lilliefors_stat: FloatArray  # (K,)
    lilliefors_p: FloatArray
    f_stat: FloatArray
    f_p: FloatArray
    exact: NDArray[np.bool_]

    def to_frame(self) -> pd.DataFrame:
        """One row per coefficient ``k``: ``basis_index``, ``coordinate``, ``exact``, the
        tests, and per column ``j`` of ``F`` (``q`` conditions, then ``intercept``)
        ``F_j``, ``ci_low_j``, ``ci_high_j``, ``jackknife_var_j``."""
        import pandas as pd

        cols: dict[str, Any] = {
            "basis_index": self.basis_index,
            "coordinate": self.coordinate,
            "exact": self.exact,
            "lilliefors_stat": self.lilliefors_stat,
            "lilliefors_p": self.lilliefors_p,
            "f_stat": self.f_stat,
            "f_p": self.f_p,
        }
        n_cond = self.F.shape[1] - 1
        for j in range(n_cond + 1):
            name = "intercept" if j == n_cond else f"q{j}"
            for what, values in (
                ("F", self.F),
                ("ci_low", self.ci_low),
                ("ci_high", self.ci_high),
                ("jackknife_var", self.jackknife_var),
            ):
                cols[f"{what}_{name}"] = values[:, j]
        return pd.DataFrame(cols)

    def summary(self, alpha: float = 0.05) -> list[dict[str, float | int]]:
        """One row per coordinate over its non-exact sine coefficients.

        ``normal_frac``: share with Lilliefors p > alpha (residuals Gaussian-like);
        ``ftest_frac``: share with F-test p < alpha (coefficient depends on ``Q``);
        ``ci_rel``: median CI half-width over ``|F|``; ``jack_rel``: median
        ``sqrt(jackknife var) / |F|`` (the paper: 1-2 orders of magnitude below 1).
        """
        out = []
        for d in np.unique(self.coordinate):
            sel = (self.coordinate == d) & ~self.exact & (self.basis_index >= 2)
            absf = np.abs(self.F[sel])
            nz = absf > 0
            half = (self.ci_high[sel] - self.ci_low[sel]) / 2
            out.append(
                {
                    "coordinate": int(d),
                    "n_coefficients": int(sel.sum()),
                    "normal_frac": float(np.mean(self.lilliefors_p[sel] > alpha))
                    if sel.any()
                    else float("nan"),
                    "ftest_frac": float(np.mean(self.f_p[sel] < alpha))
                    if sel.any()
                    else float("nan"),
                    "ci_rel": float(np.median(half[nz] / absf[nz])) if nz.any() else float("nan"),
                    "jack_rel": float(np.median(np.sqrt(self.jackknife_var[sel][nz]) / absf[nz]))
                    if nz.any()
                    else float("nan"),
                }
            )
        return out


def validate_linear_hypothesis(
    coefficients: ArrayLike, conditions: ArrayLike, alpha: float = 0.05
) -> LinearHypothesisReport:
    """Lilliefors, F-test, ``1 - alpha`` CIs and jackknife variance of every row of ``F``.

    ``coefficients`` ``(n, N + 2, D)``, ``conditions`` ``(n, q)``; needs ``n > q + 2``.
    """
    import statsmodels.api as sm
    from statsmodels.stats.diagnostic import lilliefors

    p3 = np.asarray(coefficients, dtype=np.float64)
    if p3.ndim != 3:
        raise ValueError(f"coefficients must be (n, N + 2, D); got shape {p3.shape}")
    q = _as_conditions(conditions)
    n, n_basis, dims = p3.shape
    if q.shape[0] != n:
        raise ValueError(f"conditions must have {n} rows; got {q.shape[0]}")
    if n <= q.shape[1] + 2:
        raise ValueError(f"need more than q + 2 = {q.shape[1] + 2} examples; got {n}")
    p = p3.reshape(n, -1)
    design = np.column_stack([q, np.ones(n)])
    f, _ = regression_matrix(p, q, warn=False)
    k_total = p.shape[1]
    # jackknife: leave-one-out F
    loo = np.stack(
        [regression_matrix(np.delete(p, i, 0), np.delete(q, i, 0), warn=False)[0] for i in range(n)]
    )
    jack_var = (n - 1) / n * np.sum((loo - loo.mean(axis=0)) ** 2, axis=0)
    ci_low = np.full_like(f, np.nan)
    ci_high = np.full_like(f, np.nan)
    lil_stat = np.full(k_total, np.nan)
    lil_p = np.full(k_total, np.nan)
    f_stat = np.full(k_total, np.nan)
    f_p = np.full(k_total, np.nan)
    exact = np.zeros(k_total, dtype=bool)
    for k in range(k_total):
        y = p[:, k]
        res = sm.OLS(y, design, hasconst=True).fit()
        scale = max(np.max(np.abs(y)), 1e-300)
        if np.max(np.abs(res.resid)) <= 1e-9 * scale:
            exact[k] = True
            continue
        ci = res.conf_int(alpha)
        ci_low[k], ci_high[k] = ci[:, 0], ci[:, 1]
        lil_stat[k], lil_p[k] = lilliefors(res.resid, dist="norm", pvalmethod="table")
        if q.shape[1]:
            f_stat[k], f_p[k] = float(res.fvalue), float(res.f_pvalue)
    return LinearHypothesisReport(
        basis_index=np.repeat(np.arange(n_basis), dims),
        coordinate=np.tile(np.arange(dims), n_basis),
        F=f,
        ci_low=ci_low,
        ci_high=ci_high,
        jackknife_var=jack_var,
        lilliefors_stat=lil_stat,
        lilliefors_p=lil_p,
        f_stat=f_stat,
        f_p=f_p,
        exact=exact,
    )


def select_n_sines(
    positions: Sequence[ArrayLike],
    conditions: ArrayLike,
    candidates: Sequence[int] = tuple(range(0, 16)),
    times: Sequence[ArrayLike] | Literal["normalised"] | None = None,
    n_folds: int | None = None,
    *,
    rate: float | None = None,
) -> tuple[int, FloatArray]:
    """Choose ``N`` by cross-validation; returns the best ``N`` and the CV score per candidate.

    The time base is required, as in :meth:`SineSeriesRegression.fit`: ``times``
    (seconds, one array per trajectory), ``rate`` (Hz) or ``times="normalised"``.
    For each fold (leave-one-out when ``n_folds`` is None) the regression is fitted on the
    other examples and the held-out trajectory is generated from its conditions, with its
    own start and end; the score is the mean over trajectories of the RMS position error
    at the held-out samples. Ties go to the smallest ``N``.
    """
    ts = _time_base(positions, times, rate, "select_n_sines")
    q = _as_conditions(conditions)
    n = q.shape[0]
    if n < 3:
        raise ValueError(f"cross-validation needs at least 3 trajectories; got {n}")
    k = n if n_folds is None else int(n_folds)
    if not 2 <= k <= n:
        raise ValueError(f"n_folds must be in [2, {n}]; got {n_folds}")
    if len(candidates) == 0:
        raise ValueError("candidates must not be empty")
    folds = np.arange(n) % k
    taus = [
        np.linspace(0.0, 1.0, np.shape(y)[0]) if ts is None else ss.normalised_time(ts[i])
        for i, y in enumerate(positions)
    ]
    ys = [np.asarray(y, dtype=np.float64) for y in positions]
    scores = np.empty(len(candidates))
    for c, n_sines in enumerate(candidates):
        coefs, _ = trajectory_coefficients(
            positions, int(n_sines), "normalised" if ts is None else ts
        )
        errors = np.empty(n)
        for fold in range(k):
            test = folds == fold
            with warnings.catch_warnings():
                warnings.simplefilter("ignore", RankDeficientDesignWarning)
                f, _ = regression_matrix(coefs[~test], q[~test])
            for i in np.flatnonzero(test):
                p = (f @ np.append(q[i], 1.0)).reshape(coefs.shape[1:])
                p[0], p[1] = ys[i][0], ys[i][-1] - ys[i][0]
                diff = ss.evaluate(p, taus[i]) - ys[i]
                errors[i] = np.sqrt(np.mean(np.sum(diff**2, axis=1)))
        scores[c] = errors.mean()
    return int(candidates[int(np.argmin(scores))]), scores
