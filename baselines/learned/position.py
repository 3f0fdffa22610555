"""The ``ridge`` and ``mlp`` columns of ``motion-bench position`` (LASA or a position CSV).

Both predict Lippi's residual ``D(tau) = y(tau) - y_0 - tau (y_1 - y_0)`` of a held-out
demonstration from its conditions (the same ``--conditions`` as the sine-series model:
start and end by default; columns constant over the training demonstrations are
dropped), and add it to the line from start to end:

* ``ridge``: shrinkage regression of the residual curve (every grid value) on the
  standardised conditions, ``alpha`` chosen by efficient leave-one-out cross-validation
  on the training demonstrations only (:class:`sklearn.linear_model.RidgeCV`); a large
  ``alpha`` is the ``null`` column (the mean residual);
* ``mlp``: the torch MLP of :mod:`baselines.learned.batched_mlp` on the residual's first
  ``n_sines`` sine coefficients per coordinate (zero at both ends by construction), its
  weight decay, base (``null`` or ``line``) and epochs chosen on inner folds of the
  training demonstrations (:func:`baselines.learned.nested.nested_mlp`).

The scored demonstration of a fold never enters its fit or its selection.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np
from numpy.typing import NDArray

from motion_envs._typing import FloatArray
from motion_envs.models.position_nominal import position_conditions, varying_columns

__all__ = ["LEARNED_POSITION_METHODS", "POSITION_ALPHAS", "learned_position_predictions"]

#: Columns this module adds to ``motion-bench position``.
LEARNED_POSITION_METHODS: tuple[str, ...] = ("ridge", "mlp")
#: Ridge penalties (standardised conditions) searched by leave-one-out.
POSITION_ALPHAS: tuple[float, ...] = tuple(float(a) for a in np.logspace(-3, 4, 15))
_N_SINES = 10


def _line(y: FloatArray) -> FloatArray:
    tau = np.linspace(0.0, 1.0, y.shape[1])[None, :, None]
    return y[:, :1] + tau * (y[:, -1:] - y[:, :1])


def learned_position_predictions(
    y_all: FloatArray,
    durations: FloatArray,
    folds: Sequence[tuple[Any, NDArray[np.int64], NDArray[np.int64]]],
    kinds: Sequence[str],
    methods: Sequence[str] = LEARNED_POSITION_METHODS,
    mlp_config: Any | None = None,
) -> tuple[dict[str, FloatArray], dict[str, list[dict[str, Any]]]]:
    """Predictions ``(m, K, D)`` of the scored demonstrations of ``folds`` (fold order).

    ``folds`` are ``(task, train, scored)`` index triples of **one** task (as
    :func:`motion_envs.datasets.splits.position_folds`). Returns ``method -> predictions``
    and ``method -> what each fold chose``.
    """
    from sklearn.linear_model import RidgeCV
    from sklearn.pipeline import make_pipeline
    from sklearn.preprocessing import StandardScaler

    scored_all = np.concatenate([s for _, _, s in folds])
    Q = position_conditions(y_all, durations, kinds)
    resid = y_all - _line(y_all)
    n, K, D = resid.shape
    out: dict[str, FloatArray] = {}
    chosen: dict[str, list[dict[str, Any]]] = {}
    if "ridge" in methods:
        pred = np.empty((scored_all.size, K, D))
        chosen["ridge"] = []
        row = 0
        for _, train, scored in folds:
            cols = varying_columns(Q[train])
            model = make_pipeline(StandardScaler(), RidgeCV(alphas=POSITION_ALPHAS))
            Xtr = Q[train][:, cols] if cols.any() else np.zeros((train.size, 1))
            Xsc = Q[scored][:, cols] if cols.any() else np.zeros((scored.size, 1))
            model.fit(Xtr, resid[train].reshape(train.size, -1))
            pred[row : row + scored.size] = model.predict(Xsc).reshape(scored.size, K, D)
            chosen["ridge"].append({"alpha": float(model[-1].alpha_)})
            row += scored.size
        out["ridge"] = pred + _line(y_all[scored_all])
    if "mlp" in methods:
        from baselines.learned.batched_mlp import MLPConfig
        from baselines.learned.nested import nested_mlp

        config = mlp_config if mlp_config is not None else MLPConfig()
        members = np.unique(np.concatenate([np.concatenate([t, s]) for _, t, s in folds]))
        local = np.full(n, -1, dtype=np.int64)
        local[members] = np.arange(members.size)
        tau = np.linspace(0.0, 1.0, K)
        basis = np.sin(np.pi * tau[:, None] * np.arange(1, _N_SINES + 1))
        R = resid[members]
        coef = np.linalg.lstsq(basis, R.transpose(1, 0, 2).reshape(K, -1), rcond=None)[0]
        Y = coef.reshape(_N_SINES, members.size, D).transpose(1, 0, 2).reshape(members.size, -1)
        local_folds = [(local[t], local[s]) for _, t, s in folds]
        res = nested_mlp(Q[members], Y, np.arange(members.size), local_folds, config)
        c = res.predictions[local[scored_all]].reshape(scored_all.size, _N_SINES, D)
        curves = np.einsum("tk,lkd->ltd", basis, c)
        curves[:, 0] = 0.0
        curves[:, -1] = 0.0
        out["mlp"] = curves + _line(y_all[scored_all])
        chosen["mlp"] = res.chosen
    return out, chosen
