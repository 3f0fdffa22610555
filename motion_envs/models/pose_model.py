"""A hand's position and orientation, fitted together and predicted together.

:class:`PoseModel` fits, from one set of recordings (positions ``(n_l, 3)`` and unit
quaternions ``(n_l, 4)`` sampled at the same times):

* the position with Lippi et al.'s sine series regressed on the movement's start and end
  (:class:`~motion_envs.models.sine_regression.SineSeriesRegression`, eq. 6 with
  conditions ``Q_l = [y_l(0), y_l(T_l)]``); prediction by eqs. 7-8 with the asked start
  and end held;
* the orientation with Faraway & Choe's slerp + Bézier residual model
  (:class:`~motion_envs.models.orientation_model.OrientationModel`):
  ``q(t) = slerp(q_s, q_e, alpha_bar(t / T)) expmap(C(t / T; P))``.

Both answer at the same times (seconds since the movement start). ``fit(X, y)`` takes
scikit-learn's order: ``X`` what the orientation residual is predicted from (as
:class:`~motion_envs.models.orientation_model.OrientationModel`), ``y`` the poses, one
``(n_l, D + 4)`` array per recording: the position columns, then the quaternion
``(w, x, y, z)``.
"""

from __future__ import annotations

import re
from collections.abc import Callable, Mapping, Sequence
from typing import Any, TypeVar

import numpy as np
from numpy.typing import ArrayLike, NDArray

from motion_envs._typing import FloatArray
from motion_envs.datasets.ragged import DEFAULT_N_POINTS
from motion_envs.geometry import quaternion as quat
from motion_envs.geometry.resampling import recording_times
from motion_envs.models._sklearn import (
    batch_row,
    check_order,
    criterion_score,
    score_times,
)
from motion_envs.models.estimator import check_is_fitted
from motion_envs.models.orientation_model import OrientationModel
from motion_envs.models.serialization import SerializableModel, StateSchema
from motion_envs.models.sine_regression import SineSeriesRegression

__all__ = ["PoseModel"]

M = TypeVar("M", bound=SerializableModel)

_PARTS: tuple[tuple[str, type[SerializableModel]], ...] = (
    ("position", SineSeriesRegression),
    ("orientation", OrientationModel),
)


def _prefixed(prefix: str, mapping: Mapping[str, Any]) -> dict[str, Any]:
    return {f"{prefix}_{k}": v for k, v in mapping.items()}


def _rebuilt(prefix: str, build: Callable[[], M]) -> M:
    """``build()``, its errors naming the field as stored (``arrays.position_F``)."""
    try:
        return build()
    except ValueError as exc:
        raise ValueError(
            re.sub(r"field (arrays|attributes)\.", rf"field \1.{prefix}_", str(exc))
        ) from None


def _unprefixed(prefix: str, mapping: Mapping[str, Any]) -> dict[str, Any]:
    start = f"{prefix}_"
    return {k[len(start) :]: v for k, v in mapping.items() if k.startswith(start)}


class PoseModel(SerializableModel):
    """Position (sine series on start/end) and orientation (slerp + Bézier) of a hand.

    Parameters
    ----------
    n_sines:
        Number ``N`` of sine terms of the position model.
    degree:
        Bézier degree ``d`` of the orientation residual.
    by:
        What the orientation residual is predicted from: ``"null"``, ``"subject"``,
        ``"task"`` or ``"linear"`` (:class:`OrientationModel`).
    unseen:
        ``"global"`` or ``"error"`` for a subject/task label not seen in ``fit``.
    n_points:
        Size of the orientation model's normalised-time grid.
    normalize:
        Renormalise input quaternions instead of requiring unit norm.

    Attributes
    ----------
    position_model_ : SineSeriesRegression
        The fitted position model (conditions: start and end positions, 6 columns).
    orientation_model_ : OrientationModel
        The fitted orientation model.
    durations_ : ndarray of shape (L,)
        Recording durations (s).
    """

    def __init__(
        self,
        n_sines: int = 8,
        degree: int = 2,
        by: str = "null",
        unseen: str = "global",
        n_points: int = DEFAULT_N_POINTS,
        normalize: bool = False,
    ) -> None:
        SineSeriesRegression(n_sines)
        OrientationModel(degree, by, unseen, n_points, normalize)  # validates the rest
        self.n_sines = n_sines
        self.degree = degree
        self.by = by
        self.unseen = unseen
        self.n_points = n_points
        self.normalize = normalize

    def _orientation(self) -> OrientationModel:
        return OrientationModel(self.degree, self.by, self.unseen, self.n_points, self.normalize)

    @staticmethod
    def split_poses(y: Sequence[ArrayLike]) -> tuple[list[FloatArray], list[FloatArray]]:
        """Poses ``y[l]`` ``(n_l, D + 4)`` as positions ``(n_l, D)`` and quaternions
        ``(n_l, 4)`` (the last four columns, ``(w, x, y, z)``)."""
        positions, quaternions = [], []
        for i, pose in enumerate(y):
            v = np.asarray(pose, dtype=np.float64)
            if v.ndim != 2 or v.shape[1] < 5:
                raise ValueError(
                    f"y[{i}] must be (n, D + 4): positions, then the quaternion (w, x, y, z); "
                    f"got shape {v.shape}"
                )
            positions.append(v[:, :-4])
            quaternions.append(v[:, -4:])
        return positions, quaternions

    def fit(
        self,
        X: Any,
        y: Sequence[ArrayLike],
        times: Sequence[ArrayLike] | None = None,
        *,
        rate: float | None = None,
    ) -> PoseModel:
        """Fit to poses ``y[l]`` ``(n_l, D + 4)`` (positions, then the quaternion) sampled
        at ``times`` (s) or ``rate`` (Hz); returns ``self``.

        ``X``: what the orientation model's ``by`` predicts from (None for ``"null"``,
        labels ``(L,)``, predictors ``(L, p)``; :meth:`OrientationModel.labels`).
        """
        check_order(X, y, type(self).__name__, f"what by={self.by!r} predicts from")
        ys, quaternions = self.split_poses(y)
        ts = recording_times(ys, times, rate)
        conditions = np.stack([np.concatenate([v[0], v[-1]]) for v in ys])
        position = SineSeriesRegression(self.n_sines).fit(conditions, ys, ts)
        orientation = self._orientation().fit(X, quaternions, ts)
        self.position_model_ = position
        self.orientation_model_ = orientation
        self.durations_ = np.array([t[-1] - t[0] for t in ts])
        return self

    def predict(
        self,
        start: ArrayLike,
        end: ArrayLike,
        start_orientation: ArrayLike,
        end_orientation: ArrayLike,
        times: ArrayLike,
        *,
        duration: ArrayLike | None = None,
        subjects: ArrayLike | None = None,
        tasks: ArrayLike | None = None,
        predictors: Mapping[str, ArrayLike] | ArrayLike | None = None,
    ) -> tuple[FloatArray, FloatArray]:
        """Positions and quaternions at ``times`` (s since the movement start).

        ``start``/``end`` ``(D,)`` positions and ``start_orientation``/
        ``end_orientation`` ``(4,)`` give ``((K, D), (K, 4))``; ``(m, D)`` and ``(m, 4)``
        give ``((m, K, D), (m, K, 4))``. ``times`` ``(K,)`` lie in ``[0, T]``, ``T`` =
        ``duration`` (scalar or ``(m,)``; default ``times[-1]``). The position starts
        and ends at ``start``/``end``, the orientation at the given quaternions.
        """
        check_is_fitted(self, "orientation_model_")
        s = np.asarray(start, dtype=np.float64)
        e = np.asarray(end, dtype=np.float64)
        if s.shape != e.shape or s.ndim not in (1, 2):
            raise ValueError(f"start and end must both be (D,) or (m, D); got {s.shape}, {e.shape}")
        t = np.asarray(times, dtype=np.float64)
        if t.ndim != 1 or t.size == 0:
            raise ValueError(f"times must be (K,) seconds; got shape {t.shape}")
        span = t[-1] if duration is None else duration
        positions = self.position_model_.predict(
            np.concatenate([s, e], axis=-1), span, t, start=s, end=e
        )
        quaternions = self.orientation_model_.predict(
            start_orientation, end_orientation, t, duration=span,
            subjects=subjects, tasks=tasks, predictors=predictors,
        )  # fmt: skip
        if positions.shape[:-1] != quaternions.shape[:-1]:
            raise ValueError(
                "start/end and start_orientation/end_orientation must describe the same "
                f"movements; got {s.shape} and {np.shape(start_orientation)}"
            )
        return positions, quaternions

    def score(
        self,
        X: Any,
        y: Sequence[ArrayLike],
        times: Sequence[ArrayLike] | None = None,
        *,
        rate: float | None = None,
        lever: float = 0.1,
    ) -> float:
        """``-median_l max_t (|p_l(t) - phat_l(t)| + lever angle(q_l(t), qhat_l(t)))``.

        The papers' criterion of the hand's pose: the term is a bound on how far a point
        ``lever`` (the positions' unit; 0.1 m: a point of the hand 10 cm from the tracked
        one) from the tracked point lies from its prediction (rotating it by ``theta``
        moves it by ``2 lever sin(theta / 2) <= lever theta``). Each recording is
        predicted from its own first and last pose over its own duration; greater is
        better. Without ``times`` and ``rate`` the samples are taken as uniform.
        """
        check_order(X, y, type(self).__name__, f"what by={self.by!r} predicts from")
        if not (np.isfinite(lever) and lever >= 0):
            raise ValueError(f"lever must be a finite length >= 0; got {lever!r}")
        check_is_fitted(self, "orientation_model_")
        ys, quaternions = self.split_poses(y)
        labels = self.orientation_model_.labels(X)

        def errors(i: int, t0: FloatArray) -> FloatArray:
            p, q = ys[i], quaternions[i]
            row = {k: batch_row(v, i) for k, v in labels.items()}
            p_hat, q_hat = self.predict(p[0], p[-1], q[0], q[-1], t0, duration=float(t0[-1]), **row)
            return np.linalg.norm(p_hat - p, axis=1) + lever * quat.angle(q_hat, q)

        return criterion_score(score_times(ys, times, rate), errors)

    # -- serialization: the two parts' states, prefixed ------------------------------
    state_schema = StateSchema(
        params={"n_sines": "int", "degree": "int", "by": "str", "unseen": "str",
                "n_points": "int", "normalize": "bool"},
        arrays={k: v for prefix, cls in _PARTS for k, v in _prefixed(
            prefix, cls.state_schema.arrays if cls.state_schema else {}).items()},
        attributes={k: v for prefix, cls in _PARTS for k, v in _prefixed(
            prefix, cls.state_schema.attributes if cls.state_schema else {}).items()},
    )  # fmt: skip

    def _get_state(self) -> tuple[dict[str, Any], dict[str, NDArray[Any]], dict[str, Any]]:
        check_is_fitted(self, "orientation_model_")
        arrays: dict[str, NDArray[Any]] = {}
        attributes: dict[str, Any] = {}
        for prefix, model in (("position", self.position_model_),
                              ("orientation", self.orientation_model_)):  # fmt: skip
            _, part_arrays, part_attributes = model._get_state()
            arrays.update(_prefixed(prefix, part_arrays))
            attributes.update(_prefixed(prefix, part_attributes))
        return dict(self.get_params(deep=False)), arrays, attributes

    @classmethod
    def _from_state(
        cls,
        params: dict[str, Any],
        arrays: dict[str, NDArray[Any]],
        attributes: dict[str, Any],
    ) -> PoseModel:
        model = cls(**params)
        own = model.get_params(deep=False)
        position = _rebuilt("position", lambda: SineSeriesRegression._from_state(
            {"n_sines": own["n_sines"]},
            _unprefixed("position", arrays),
            _unprefixed("position", attributes),
        ))  # fmt: skip
        if position.conditions_.shape[1] != 2 * position.n_dims_:
            raise ValueError("field arrays.position_conditions: must hold start and end")
        orientation = _rebuilt("orientation", lambda: OrientationModel._from_state(
            {k: own[k] for k in ("degree", "by", "unseen", "n_points", "normalize")},
            _unprefixed("orientation", arrays),
            _unprefixed("orientation", attributes),
        ))  # fmt: skip
        model.position_model_ = position
        model.orientation_model_ = orientation
        model.durations_ = orientation.durations_
        return model
