"""Nested cross-validation by group: hyper-parameters chosen inside the training folds.

For every outer fold (training rows, scored rows) the training *groups* (subjects, or
demonstrations) are split again into ``k`` inner folds
(:class:`sklearn.model_selection.GroupKFold`, ``k = min(inner_splits, n_groups)``).
Each candidate is trained on the inner training rows and scored on the inner validation
rows; the candidate with the least mean validation error is refitted on all the outer
training rows and predicts the scored rows. The scored rows are never used to fit or to
choose anything: :func:`inner_folds` only ever sees the outer training indices.

For the MLP, the candidates are the triples (weight decay, base nominal, number of
epochs): the inner validation curves pick all three (early stopping on the inner
validation folds; with a criterion, selection is on the papers' criterion), then one
network per outer fold is trained on the outer training rows for the chosen epochs.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import NDArray

from motion_envs._typing import FloatArray

if TYPE_CHECKING:  # torch is imported only when the MLP runs
    from baselines.learned.batched_mlp import CurveCriterion, MLPConfig

__all__ = ["Fold", "NestedResult", "inner_folds", "nested_mlp"]

IntArray = NDArray[np.int64]

#: One outer fold: (training row indices, scored row indices).
Fold = tuple[IntArray, IntArray]


def inner_folds(train: IntArray, groups: NDArray[Any], n_splits: int) -> list[Fold]:
    """Inner ``(fit, validation)`` row indices by group, from the training rows only.

    ``GroupKFold`` over the groups of ``train``; ``k = min(n_splits, n_groups)``; raises
    ``ValueError`` with fewer than 2 groups.
    """
    from sklearn.model_selection import GroupKFold

    train = np.asarray(train, dtype=np.int64)
    g = np.asarray(groups)[train]
    n_groups = np.unique(g).size
    if n_groups < 2:
        raise ValueError(f"nested selection needs at least 2 training groups; got {n_groups}")
    k = min(n_splits, n_groups)
    return [(train[a], train[b]) for a, b in GroupKFold(n_splits=k).split(train, groups=g)]


@dataclass
class NestedResult:
    """Predictions of the scored rows of every outer fold, and what each fold chose.

    Attributes
    ----------
    predictions:
        ``(N, m)``; rows never scored are NaN.
    chosen:
        Per outer fold: ``{"weight_decay": ..., "epochs": ...}`` (or the model's own keys).
    params:
        Per outer fold, the trained network's parameters (name -> array).
    """

    predictions: FloatArray
    chosen: list[dict[str, Any]] = field(default_factory=list)
    params: list[dict[str, FloatArray]] = field(default_factory=list)


def nested_mlp(
    X: FloatArray,
    Y: FloatArray,
    groups: NDArray[Any],
    folds: Sequence[Fold],
    config: MLPConfig,
    criterion: CurveCriterion | None = None,
) -> NestedResult:
    """Nested selection and prediction with the batched MLP (see the module docstring).

    ``Y`` is ``(N, m)``, or ``(n_folds, N, m)`` when the targets depend on the outer fold
    (residuals against a timing model fitted on that fold's training rows); likewise the
    target of ``criterion`` (a :class:`~baselines.learned.batched_mlp.CurveCriterion`)
    may be ``(n_folds, N, T, D)``.

    Two batched trainings: every (outer fold, weight decay, base, inner fold) network with
    its validation curve; then one network per outer fold, on all its training rows, with
    the chosen weight decay and base for the chosen number of epochs.
    """
    from dataclasses import replace

    from baselines.learned.batched_mlp import train_networks

    N = X.shape[0]
    cands = [(wd, base) for wd in config.weight_decays for base in config.bases]
    wds = np.asarray([c[0] for c in cands], dtype=np.float64)
    base_of = np.asarray([c[1] for c in cands])
    per_fold = Y.ndim == 3
    if per_fold and Y.shape[0] != len(folds):
        raise ValueError(f"Y must be (N, m) or ({len(folds)}, N, m); got {Y.shape}")
    masks_t, masks_v, decay, owner = [], [], [], []
    for o, (train, _) in enumerate(folds):
        for c, wd in enumerate(wds):
            for fit_rows, val_rows in inner_folds(train, groups, config.inner_splits):
                mt = np.zeros(N, bool)
                mt[fit_rows] = True
                mv = np.zeros(N, bool)
                mv[val_rows] = True
                masks_t.append(mt)
                masks_v.append(mv)
                decay.append(wd)
                owner.append((o, c, val_rows.size))
    fold_of = [o for o, _, _ in owner]
    Yi = Y[fold_of] if per_fold else Y
    crit = criterion
    if criterion is not None and np.ndim(criterion.target) == 4:
        crit = replace(criterion, target=np.asarray(criterion.target)[fold_of])
    inner = train_networks(
        X,
        Yi,
        np.array(masks_t),
        np.array(masks_v),
        np.array(decay),
        config,
        bases=base_of[[c for _, c, _ in owner]],
        criterion=crit,
    )
    # pooled validation error per (outer fold, candidate, epoch): weighted by val rows
    n_folds, n_c = len(folds), wds.size
    sums = np.zeros((n_folds, n_c, config.max_epochs + 1))
    counts = np.zeros((n_folds, n_c, 1))
    for b, (o, c, n_val) in enumerate(owner):
        sums[o, c] += inner.val_loss[b] * n_val
        counts[o, c] += n_val
    score = sums / counts
    final_masks, final_wd, final_base, stops, chosen = [], [], [], [], []
    for o, (train, _) in enumerate(folds):
        # ties: the first candidate in config order, then the fewest epochs
        c_, e_ = np.unravel_index(np.argmin(score[o]), score[o].shape)
        c, e = int(c_), int(e_)
        mt = np.zeros(N, bool)
        mt[train] = True
        final_masks.append(mt)
        final_wd.append(wds[c])
        final_base.append(base_of[c])
        stops.append(int(e))
        chosen.append({"weight_decay": float(wds[c]), "base": str(base_of[c]), "epochs": int(e)})
    final = train_networks(
        X,
        Y,
        np.array(final_masks),
        None,
        np.array(final_wd),
        config,
        np.array(stops),
        bases=np.array(final_base),
    )
    pred = np.full((N, Y.shape[-1]), np.nan)
    params = []
    for o, (_, scored) in enumerate(folds):
        pred[scored] = final.predictions[o, scored]
        params.append({k: v[o] for k, v in final.params.items()})
    return NestedResult(predictions=pred, chosen=chosen, params=params)
