"""Bézier models of slerp residual curves (Faraway & Choe, section 3.4 and Table 1).

Every model describes a residual curve ``r(tau)`` (``n_points x 3``, zero at both ends,
on the uniform normalised-time grid) by a Bézier curve of degree ``d`` with ``P_0 = P_d = 0``
and interior control points ``P_1 .. P_{d-1}``; the models differ in how they *predict*
those control points:

* :class:`NullBezierModel`: one common ``P = mean_l P_l`` (the paper's preferred model
  for ``d = 2``: the downward tilt);
* :class:`SubjectBezierModel` / :class:`TaskBezierModel`: ``P`` = mean of the ``P_l``
  of the same subject / task;
* :class:`LinearBezierModel`: the multivariate linear model ``g(P) = f(x) + e`` with
  ``vec(P) = b_0 + B x`` on numeric predictors ``x`` (least squares).

``P_l`` is the least-squares fit of curve ``l`` (:func:`motion_envs.geometry.bezier.fit`).

Frames: with ``frame="body"`` (default, the paper's) the curves are modelled in the
slerp's body frame as given. With ``frame="path"`` they are first mapped to the path
frame of :mod:`motion_envs.models.path_frame` (start-to-goal rotation axis, the data's
``up`` made perpendicular to it, their cross product; divided by the rotation angle):
``p(tau) = F^T r(tau) / s``; the model is fitted to ``p`` and its predictions are mapped
back with the exact inverse ``r = s F p``. ``fit`` and ``predict`` then need each
curve's ``starts`` and ``ends`` (``(L, 4)`` quaternions ``(w, x, y, z)``).
Because least squares is linear and the grid is shared, the mean of fitted control
points equals the fit of the mean curve.

The estimators follow scikit-learn conventions: ``fit`` returns ``self``; fitted
attributes end in ``_``; ``save``/``load`` use the JSON model format of
:mod:`motion_envs.models.serialization`.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from typing import Any, ClassVar, TypeVar

import numpy as np
from numpy.typing import ArrayLike, NDArray

from motion_envs._typing import FloatArray
from motion_envs.datasets.ragged import normalised_grid
from motion_envs.geometry import bezier
from motion_envs.models.estimator import not_fitted_error
from motion_envs.models.path_frame import (
    DEFAULT_UP,
    FRAMES,
    check_up,
    from_path_frame,
    to_path_frame,
)
from motion_envs.models.serialization import SerializableModel, State, StateSchema

#: Parameters that model files written before the path frame existed lack (body frame).
_FRAME_PARAMS = frozenset({"frame", "up"})

__all__ = [
    "BezierResidualModel",
    "GroupBezierModel",
    "LinearBezierModel",
    "NullBezierModel",
    "SubjectBezierModel",
    "TaskBezierModel",
    "fit_control_points",
]

#: Curve labels (subjects or tasks) as passed, ``(L,)``, or None.
Labels = ArrayLike | None
#: Numeric predictors: a mapping name -> ``(L,)`` values, an ``(L, p)`` array, or None.
Predictors = Mapping[str, ArrayLike] | ArrayLike | None
#: Curve labels as checked by ``fit`` (strings), or None.
_Fitted = NDArray[np.str_] | None


def _check_curves(residuals: ArrayLike, name: str = "residuals") -> FloatArray:
    R = np.asarray(residuals, dtype=np.float64)
    if R.ndim != 3 or R.shape[2] != 3 or R.shape[1] < 3:
        raise ValueError(f"{name} must have shape (L, n_points >= 3, 3); got {R.shape}")
    if R.shape[0] < 1:
        raise ValueError(f"{name} must contain at least one curve")
    if not np.all(np.isfinite(R)):
        raise ValueError(f"{name} contains NaN or infinite values")
    return R


def fit_control_points(residuals: ArrayLike, degree: int) -> FloatArray:
    """Least-squares interior control points of every residual curve, ``(L, d - 1, 3)``.

    ``residuals`` is ``(L, n, 3)`` on the uniform grid of ``n`` points; one shared
    pseudo-inverse serves all curves (:func:`motion_envs.geometry.bezier.fit`).
    """
    R = _check_curves(residuals)
    return bezier.fit(R, normalised_grid(R.shape[1]), degree)


def _labels(values: ArrayLike | None, name: str, n: int) -> NDArray[np.str_]:
    if values is None:
        raise ValueError(f"{name} is required by this model")
    arr = np.asarray(values).astype(str)
    if arr.shape != (n,):
        raise ValueError(f"{name} must have shape ({n},); got {arr.shape}")
    return arr


def _state_array(
    arrays: Mapping[str, NDArray[Any]], name: str, shape: tuple[int, ...]
) -> FloatArray:
    """``arrays[name]`` checked against ``shape`` (-1: any size); ValueError naming the field."""
    arr = arrays[name]
    if arr.ndim != len(shape) or any(
        e not in (-1, a) for e, a in zip(shape, arr.shape, strict=True)
    ):
        want = "(" + ", ".join("n" if e == -1 else str(e) for e in shape) + ")"
        raise ValueError(f"field arrays.{name}: shape {list(arr.shape)} does not match {want}")
    return np.asarray(arr, dtype=np.float64)


def _state_n_points(attributes: Mapping[str, Any]) -> int:
    n = attributes["n_points_"]
    if n < 2:
        raise ValueError(f"field attributes.n_points_: must be >= 2; got {n}")
    return int(n)


B = TypeVar("B", bound="BezierResidualModel")


class BezierResidualModel(SerializableModel):
    """Base class: a Bézier model of slerp residual curves of one degree.

    Parameters
    ----------
    degree:
        Bézier degree ``d >= 1`` (``d - 1`` free interior control points in R^3).
    frame:
        ``"body"`` (the paper's) or ``"path"`` (see the module docstring).
    up:
        The data's vertical axis in the world frame (``frame="path"`` only); default
        :data:`motion_envs.models.path_frame.DEFAULT_UP` (``+z``); datasets carry theirs
        as ``OrientationDataset.up``.
    """

    def __init__(self, degree: int = 2, frame: str = "body", up: ArrayLike = DEFAULT_UP) -> None:
        bezier.check_degree(degree)
        if frame not in FRAMES:
            raise ValueError(f"frame must be one of {FRAMES}; got {frame!r}")
        check_up(up)
        self.degree = degree
        self.frame = frame
        self.up = up

    def _up(self) -> tuple[float, ...]:
        """``up`` as a unit float vector (the parameter is stored as given)."""
        return tuple(float(x) for x in check_up(self.up))

    def _frame_params(self) -> dict[str, Any]:
        return {"degree": int(self.degree), "frame": self.frame, "up": list(self._up())}

    def _ends(
        self, starts: ArrayLike | None, ends: ArrayLike | None, L: int
    ) -> tuple[FloatArray, FloatArray]:
        if starts is None or ends is None:
            raise ValueError("starts and ends (L, 4) are required with frame='path'")
        S = np.asarray(starts, dtype=np.float64)
        E = np.asarray(ends, dtype=np.float64)
        if S.shape != (L, 4) or E.shape != (L, 4):
            raise ValueError(
                f"starts and ends must have shape ({L}, 4); got {S.shape} and {E.shape}"
            )
        return S, E

    def to_model_frame(
        self, residuals: ArrayLike, starts: ArrayLike | None = None, ends: ArrayLike | None = None
    ) -> FloatArray:
        """Residual curves in the frame the model works in (identity for ``"body"``)."""
        return self._change_frame(to_path_frame, residuals, starts, ends)

    def from_model_frame(
        self, curves: ArrayLike, starts: ArrayLike | None = None, ends: ArrayLike | None = None
    ) -> FloatArray:
        """Inverse of :meth:`to_model_frame`: curves back in the body frame."""
        return self._change_frame(from_path_frame, curves, starts, ends)

    def _change_frame(
        self,
        transform: Callable[..., FloatArray],
        curves: ArrayLike,
        starts: ArrayLike | None,
        ends: ArrayLike | None,
    ) -> FloatArray:
        C = np.asarray(curves, dtype=np.float64)
        if self.frame == "body":
            return C
        S, E = self._ends(starts, ends, C.shape[0])
        return transform(C, S, E, self._up())

    # -- to implement -------------------------------------------------------------
    def _fit_points(
        self, points: FloatArray, subjects: _Fitted, tasks: _Fitted, predictors: FloatArray | None
    ) -> None:
        raise NotImplementedError

    def _predict_points(
        self, n: int | None, subjects: Labels, tasks: Labels, predictors: Predictors
    ) -> FloatArray:
        """The fitted model's control points for these curves (:meth:`predict_control_points`)."""
        raise NotImplementedError

    # -- shared -------------------------------------------------------------------
    def fit(
        self: B,
        residuals: ArrayLike,
        subjects: Labels = None,
        tasks: Labels = None,
        predictors: Predictors = None,
        starts: ArrayLike | None = None,
        ends: ArrayLike | None = None,
    ) -> B:
        """Fit to residual curves ``(L, n_points, 3)`` and their labels; returns ``self``.

        ``starts``/``ends`` (``(L, 4)``) are needed with ``frame="path"``. Sets
        ``n_points_`` and the model's own fitted attributes.
        """
        R = _check_curves(residuals)
        L = R.shape[0]
        R = self.to_model_frame(R, starts, ends)
        points = fit_control_points(R, self.degree)
        subj = None if subjects is None else _labels(subjects, "subjects", L)
        task = None if tasks is None else _labels(tasks, "tasks", L)
        X = None if predictors is None else self._predictor_matrix(predictors, L, fitting=True)
        self._fit_points(points, subj, task, X)
        self.n_points_ = int(R.shape[1])
        return self

    def _predictor_matrix(
        self, predictors: Mapping[str, ArrayLike] | ArrayLike, n: int, fitting: bool
    ) -> FloatArray:
        return np.zeros((n, 0))

    def _set_state(self, arrays: dict[str, NDArray[Any]], attributes: dict[str, Any]) -> None:
        self._set_points(arrays, attributes)
        self.n_points_ = _state_n_points(attributes)

    def _set_points(self, arrays: dict[str, NDArray[Any]], attributes: dict[str, Any]) -> None:
        """Set the fitted control-point attributes from a model file's state."""
        raise NotImplementedError

    def predict_control_points(
        self,
        n: int | None = None,
        subjects: Labels = None,
        tasks: Labels = None,
        predictors: Predictors = None,
    ) -> FloatArray:
        """Predicted interior control points, ``(L, d - 1, 3)``."""
        self._check_fitted()
        return self._predict_points(n, subjects, tasks, predictors)

    def _check_fitted(self) -> None:
        if not hasattr(self, "control_points_") and not hasattr(self, "intercept_"):
            raise not_fitted_error(self)

    def predict(
        self,
        n: int | None = None,
        subjects: Labels = None,
        tasks: Labels = None,
        predictors: Predictors = None,
        n_points: int | None = None,
        starts: ArrayLike | None = None,
        ends: ArrayLike | None = None,
    ) -> FloatArray:
        """Predicted residual curves ``(L, n_points, 3)`` on the uniform grid (body frame).

        With ``frame="path"`` the control points are path-frame ones (see
        :meth:`predict_control_points`) and ``starts``/``ends`` map the curves back.
        """
        if n is None and starts is not None:
            n = int(np.asarray(starts).shape[0])
        P = self.predict_control_points(n=n, subjects=subjects, tasks=tasks, predictors=predictors)
        grid = normalised_grid(n_points or self.n_points_)
        return self.from_model_frame(bezier.evaluate(P, grid, self.degree), starts, ends)


class NullBezierModel(BezierResidualModel):
    """One common residual: ``P = mean_l P_l`` (no predictors).

    Fitted attributes: ``control_points_`` ``(d - 1, 3)``.
    """

    def _fit_points(
        self, points: FloatArray, subjects: _Fitted, tasks: _Fitted, predictors: FloatArray | None
    ) -> None:
        self.control_points_ = points.mean(axis=0)

    def _predict_points(
        self, n: int | None, subjects: Labels, tasks: Labels, predictors: Predictors
    ) -> FloatArray:
        if n is None:
            for labels in (subjects, tasks):
                if labels is not None:
                    n = int(np.shape(labels)[0])
        if n is None:
            raise ValueError("n (the number of curves to predict) is required")
        return np.broadcast_to(self.control_points_, (n, *self.control_points_.shape)).copy()

    def _get_state(self) -> State:
        return (
            self._frame_params(),
            {"control_points_": self.control_points_},
            {"n_points_": self.n_points_},
        )

    state_schema = StateSchema(
        params={"degree": "int", "frame": "str", "up": "float_list"},
        optional_params=_FRAME_PARAMS,
        arrays={"control_points_": ("float64", 2)},
        attributes={"n_points_": "int"},
    )

    def _set_points(self, arrays: dict[str, NDArray[Any]], attributes: dict[str, Any]) -> None:
        self.control_points_ = _state_array(arrays, "control_points_", (self.degree - 1, 3))


class GroupBezierModel(BezierResidualModel):
    """``P`` = mean of the fitted ``P_l`` within a group (subject or task).

    Parameters
    ----------
    degree:
        Bézier degree.
    by:
        ``"subject"`` or ``"task"``: which label defines the groups.
    unseen:
        What to predict for a label not seen in ``fit``: ``"error"`` (raise
        ``ValueError``) or ``"global"`` (the mean over all training curves, i.e. the
        null model).

    Fitted attributes: ``groups_`` ``(G,)``, ``control_points_`` ``(G, d - 1, 3)``,
    ``global_control_points_`` ``(d - 1, 3)``, ``group_sizes_`` ``(G,)``.
    """

    def __init__(
        self,
        degree: int = 2,
        by: str = "task",
        unseen: str = "error",
        frame: str = "body",
        up: ArrayLike = DEFAULT_UP,
    ) -> None:
        super().__init__(degree, frame=frame, up=up)
        if by not in ("subject", "task"):
            raise ValueError(f"by must be 'subject' or 'task'; got {by!r}")
        if unseen not in ("error", "global"):
            raise ValueError(f"unseen must be 'error' or 'global'; got {unseen!r}")
        self.by = by
        self.unseen = unseen

    def _fit_points(
        self, points: FloatArray, subjects: _Fitted, tasks: _Fitted, predictors: FloatArray | None
    ) -> None:
        labels = subjects if self.by == "subject" else tasks
        if labels is None:
            raise ValueError(f"{self.by}s is required to fit a {type(self).__name__}")
        groups, inverse, counts = np.unique(labels, return_inverse=True, return_counts=True)
        sums = np.zeros((groups.size, *points.shape[1:]))
        np.add.at(sums, inverse, points)
        self.groups_ = groups
        self.group_sizes_ = counts.astype(np.int64)
        self.control_points_ = sums / counts[:, None, None]
        self.global_control_points_ = points.mean(axis=0)

    def _predict_points(
        self, n: int | None, subjects: Labels, tasks: Labels, predictors: Predictors
    ) -> FloatArray:
        labels = subjects if self.by == "subject" else tasks
        name = f"{self.by}s"
        if labels is None:
            raise ValueError(f"{name} is required to predict with a {type(self).__name__}")
        labels = np.asarray(labels).astype(str)
        pos = np.searchsorted(self.groups_, labels)
        pos = np.clip(pos, 0, self.groups_.size - 1)
        known = self.groups_[pos] == labels
        if not np.all(known) and self.unseen == "error":
            unknown = sorted(set(labels[~known].tolist()))
            raise ValueError(
                f"{name} contains label(s) not seen in fit: {unknown[:5]}; "
                f"pass unseen='global' to predict the null model for them"
            )
        out = self.control_points_[pos].copy()
        out[~known] = self.global_control_points_
        return out

    def _get_state(self) -> State:
        return (
            {**self._frame_params(), "by": self.by, "unseen": self.unseen},
            {
                "control_points_": self.control_points_,
                "global_control_points_": self.global_control_points_,
                "group_sizes_": self.group_sizes_,
            },
            {"groups_": self.groups_.tolist(), "n_points_": self.n_points_},
        )

    state_schema = StateSchema(
        params={
            "degree": "int",
            "frame": "str",
            "up": "float_list",
            "by": "str",
            "unseen": "str",
        },
        optional_params=_FRAME_PARAMS,
        arrays={
            "control_points_": ("float64", 3),
            "global_control_points_": ("float64", 2),
            "group_sizes_": ("int64", 1),
        },
        attributes={"groups_": "str_list", "n_points_": "int"},
    )

    @classmethod
    def _from_params(cls, params: dict[str, Any]) -> GroupBezierModel:
        model = cls.__new__(cls)
        GroupBezierModel.__init__(model, **params)
        fixed_by = getattr(cls, "grouped_by", None)
        if fixed_by is not None and model.by != fixed_by:
            raise ValueError(f"field params.by: a {cls.__name__} groups by {fixed_by!r}")
        return model

    def _set_points(self, arrays: dict[str, NDArray[Any]], attributes: dict[str, Any]) -> None:
        groups = attributes["groups_"]
        if not groups or sorted(set(groups)) != groups:
            raise ValueError("field attributes.groups_: must be sorted, unique and not empty")
        k = self.degree - 1
        self.control_points_ = _state_array(arrays, "control_points_", (len(groups), k, 3))
        self.global_control_points_ = _state_array(arrays, "global_control_points_", (k, 3))
        sizes = arrays["group_sizes_"]
        if sizes.shape != (len(groups),) or np.any(sizes < 1):
            raise ValueError(
                f"field arrays.group_sizes_: must be {len(groups)} integers >= 1; "
                f"got shape {list(sizes.shape)}"
            )
        self.group_sizes_ = sizes.astype(np.int64)
        self.groups_ = np.asarray(groups, dtype=str)


class _OneLabelBezierModel(GroupBezierModel):
    """A :class:`GroupBezierModel` whose ``by`` is fixed by the subclass (``grouped_by``)."""

    #: The label this class always groups by.
    grouped_by: ClassVar[str]

    def __init__(
        self,
        degree: int = 2,
        unseen: str = "error",
        frame: str = "body",
        up: ArrayLike = DEFAULT_UP,
    ) -> None:
        super().__init__(degree, by=self.grouped_by, unseen=unseen, frame=frame, up=up)


class SubjectBezierModel(_OneLabelBezierModel):
    """The subject predictor: ``P`` = mean of the ``P_l`` of the same subject."""

    grouped_by = "subject"


class TaskBezierModel(_OneLabelBezierModel):
    """The task predictor: ``P`` = mean of the ``P_l`` of the same task."""

    grouped_by = "task"


class LinearBezierModel(BezierResidualModel):
    """Multivariate linear model of the control points on numeric predictors.

    ``vec(P_l) = b_0 + B^T x_l + e_l`` with ``vec(P)`` the ``3 (d - 1)`` stacked
    control-point coordinates and ``x_l`` the ``p`` predictors of curve ``l``; ``b_0``
    and ``B`` minimise the summed squared error (``numpy.linalg.lstsq`` on the design
    ``[1, x]``). A design of rank below ``p + 1`` (a constant or collinear predictor,
    or fewer curves than ``p + 1``) raises ``ValueError``.

    Fitted attributes: ``predictor_names_`` (``p`` names), ``intercept_``
    ``(d - 1, 3)``, ``coef_`` ``(p, d - 1, 3)``.
    """

    predictor_names_: list[str]
    intercept_: FloatArray
    coef_: FloatArray

    def _predictor_matrix(
        self, predictors: Mapping[str, ArrayLike] | ArrayLike, n: int, fitting: bool
    ) -> FloatArray:
        if isinstance(predictors, Mapping):
            names = sorted(predictors)
            if not fitting:
                missing = [k for k in self.predictor_names_ if k not in predictors]
                if missing:
                    raise ValueError(f"predictors is missing {missing}")
                names = list(self.predictor_names_)
            cols = [np.asarray(predictors[k], dtype=np.float64) for k in names]
            X = np.stack(cols, axis=1) if cols else np.zeros((n, 0))
        else:
            X = np.asarray(predictors, dtype=np.float64)
            if X.ndim == 1:
                X = X[:, None]
            names = [f"x{i}" for i in range(X.shape[1])]
            if not fitting and X.shape[1] != len(self.predictor_names_):
                raise ValueError(
                    f"predictors must have {len(self.predictor_names_)} columns; got {X.shape[1]}"
                )
        if X.shape[0] != n:
            raise ValueError(f"predictors must have {n} rows (one per curve); got {X.shape[0]}")
        if not np.all(np.isfinite(X)):
            raise ValueError("predictors contains NaN or infinite values")
        if fitting:
            self.predictor_names_ = list(names)
        return X

    def _fit_points(
        self, points: FloatArray, subjects: _Fitted, tasks: _Fitted, predictors: FloatArray | None
    ) -> None:
        if predictors is None:
            raise ValueError("predictors is required to fit a LinearBezierModel")
        L, p = predictors.shape
        design = np.hstack([np.ones((L, 1)), predictors])
        rank = np.linalg.matrix_rank(design)
        if rank < p + 1:
            raise ValueError(
                f"degenerate regression: the design [1, predictors] has rank {rank} < {p + 1} "
                f"(constant or collinear predictors, or fewer than {p + 1} curves)"
            )
        Y = points.reshape(L, -1)
        beta, *_ = np.linalg.lstsq(design, Y, rcond=None)
        k = points.shape[1]
        self.intercept_ = np.asarray(beta[0], dtype=np.float64).reshape(k, 3)
        self.coef_ = np.asarray(beta[1:], dtype=np.float64).reshape(p, k, 3)

    def _predict_points(
        self, n: int | None, subjects: Labels, tasks: Labels, predictors: Predictors
    ) -> FloatArray:
        if predictors is None:
            raise ValueError("predictors is required to predict with a LinearBezierModel")
        if isinstance(predictors, Mapping):
            n = int(np.shape(next(iter(predictors.values())))[0]) if predictors else 0
        else:
            n = np.atleast_1d(np.asarray(predictors)).shape[0]
        X = self._predictor_matrix(predictors, n, fitting=False)
        return self.intercept_ + np.einsum("lp,pkc->lkc", X, self.coef_)

    def _get_state(self) -> State:
        return (
            self._frame_params(),
            {"intercept_": self.intercept_, "coef_": self.coef_},
            {"predictor_names_": list(self.predictor_names_), "n_points_": self.n_points_},
        )

    state_schema = StateSchema(
        params={"degree": "int", "frame": "str", "up": "float_list"},
        optional_params=_FRAME_PARAMS,
        arrays={"intercept_": ("float64", 2), "coef_": ("float64", 3)},
        attributes={"predictor_names_": "str_list", "n_points_": "int"},
    )

    def _set_points(self, arrays: dict[str, NDArray[Any]], attributes: dict[str, Any]) -> None:
        names = list(attributes["predictor_names_"])
        k = self.degree - 1
        self.intercept_ = _state_array(arrays, "intercept_", (k, 3))
        self.coef_ = _state_array(arrays, "coef_", (len(names), k, 3))
        self.predictor_names_ = names
