"""The leave-out folds of ``motion-bench position``: every method fitted on the training
demonstrations of a shape and scored on the held-out ones (:func:`run_benchmark`)."""

from __future__ import annotations

import sys
import time
from collections import Counter, defaultdict
from collections.abc import Sequence
from typing import Any

import numpy as np
from numpy.typing import NDArray

from baselines.learned import LEARNED_MODES
from baselines.peers import DMPPeer, ProMPPeer, peers_available
from baselines.position_bench.config import CRITERION_TEXT, METHODS, PEER_METHODS
from motion_envs._typing import FloatArray
from motion_envs.datasets.lasa import LASA_CITATION
from motion_envs.datasets.position_csv import PositionDataset
from motion_envs.datasets.resampling import resample_positions
from motion_envs.datasets.splits import position_folds
from motion_envs.models.position_criteria import CRITERIA
from motion_envs.models.position_nominal import (
    PositionNominal,
    position_conditions,
    varying_columns,
)
from motion_envs.models.sine_regression import SineSeriesRegression


class _Timer:
    def __init__(self) -> None:
        self.fit: defaultdict[str, float] = defaultdict(float)
        self.predict: defaultdict[str, float] = defaultdict(float)
        self.n_fit: Counter[str] = Counter()
        self.n_predict: Counter[str] = Counter()

    def add(self, method: str, fit_s: float, predict_s: float) -> None:
        self.fit[method] += fit_s
        self.predict[method] += predict_s
        self.n_fit[method] += 1
        self.n_predict[method] += 1


def predict_folds(
    y_all: FloatArray,
    durations: FloatArray,
    folds: list[tuple[str, NDArray[np.int64], NDArray[np.int64]]],
    kinds: list[str],
    n_sines: int | None,
    methods: list[str],
    timer: _Timer,
    n_weights: int = 10,
) -> tuple[dict[str, FloatArray], list[int]]:
    """Each method's predictions of the scored demonstrations of ``folds``, in fold order.

    Every fold fits each method on its training demonstrations and predicts its scored
    ones from their own start, end and duration. Returns ``method -> (m, K, D)`` and the
    ``N`` the sine series chose in each fold.
    """
    scored_all = np.concatenate([scored for _, _, scored in folds])
    preds = {m: np.empty((scored_all.size, *y_all.shape[1:])) for m in methods}
    chosen = []
    n_sines_arg: int | str = "auto" if n_sines is None else n_sines
    row = 0
    for _, train, scored in folds:
        rows = slice(row, row + scored.size)
        row += scored.size
        yt = y_all[train]
        for method, kind in (("line", "line"), ("null", "null"), ("lippi", "sine")):
            if method not in methods:
                continue
            t0 = time.perf_counter()
            nominal = PositionNominal(kind, n_sines=n_sines_arg, conditions=kinds)
            nominal.fit(yt, durations[train])
            t1 = time.perf_counter()
            preds[method][rows] = nominal.predict(y_all[scored], durations[scored])
            if method == "lippi":
                cv = nominal.selection_seconds_
                timer.add("lippi", t1 - t0 - cv, (time.perf_counter() - t1) / scored.size)
                timer.fit["lippi_cv"] += cv
                chosen.append(nominal.n_sines_)
        for name, cls in (("dmp", DMPPeer), ("promp", ProMPPeer)):
            if name not in methods:
                continue
            t0 = time.perf_counter()
            peer = cls(n_weights_per_dim=n_weights).fit(yt)
            t1 = time.perf_counter()
            for k, i in enumerate(scored):
                preds[name][rows.start + k] = peer.predict(y_all[i, 0], y_all[i, -1])
            timer.add(name, t1 - t0, (time.perf_counter() - t1) / scored.size)
    return preds, chosen


def _score(y: FloatArray, preds: dict[str, FloatArray]) -> dict[str, dict[str, float]]:
    out = {}
    for m, p in preds.items():
        out[m] = {c: float(np.median(f(y, p))) for c, f in CRITERIA.items()}
    return out


def _validation_rows(
    y: FloatArray, durations: FloatArray, kinds: list[str], n_sines: int
) -> list[dict[str, Any]]:
    q = position_conditions(y, durations, kinds)
    q = q[:, varying_columns(q)]
    if y.shape[0] <= q.shape[1] + 2:
        return []
    model = SineSeriesRegression(n_sines=n_sines).fit(q, list(y), times="normalised")
    return model.validate().summary()


#: Fewest demonstrations of a shape that leave-one-out scores (``position_folds``).
MIN_DEMOS_LOO = 3
#: Fewest training demonstrations from which ``--n-sines auto`` chooses N (leave-one-out
#: cross-validation inside each fold, :mod:`motion_envs.models.sine_regression`) and the
#: learned rows their hyper-parameters (nested cross-validation).
MIN_TRAIN_FOR_AUTO = 3


def _check_enough_demonstrations(
    dataset: Any, folds: Any, split: str, n_sines: int | None, learned: Sequence[str]
) -> None:
    """Refuse, before any fitting, a shape whose folds leave too few demonstrations to
    choose ``N`` (``--n-sines auto``) or the learned rows' hyper-parameters by
    cross-validation on the training demonstrations; the message names the shape, its
    demonstrations and the true rule."""
    what = [w for w, on in (("--n-sines auto", n_sines is None), ("--learned", learned)) if on]
    if not what:
        return
    for task in dataset.task_names():
        train_sizes = [f[1].size for f in folds if f[0] == task]
        if train_sizes and min(train_sizes) < MIN_TRAIN_FOR_AUTO:
            n = int((dataset.tasks == task).sum())
            needed = n + MIN_TRAIN_FOR_AUTO - min(train_sizes)
            how = "leave-one-out" if split == "loo" else f"the {split!r} split"
            raise ValueError(
                f"shape {task!r} has {n} demonstrations; {how} with {' and '.join(what)} "
                f"needs at least {needed} ({MIN_TRAIN_FOR_AUTO} left in every fold for the "
                "cross-validation on training demonstrations); give --n-sines N and "
                "--learned off, or drop the shape with --shapes"
            )


def run_benchmark(
    dataset: PositionDataset,
    n_points: int = 200,
    kinds: list[str] | None = None,
    n_sines: int | None = None,
    use_peers: bool = True,
    n_weights: int = 10,
    progress: bool = True,
    split: str = "loo",
    test_fraction: float = 0.25,
    split_seed: int = 0,
    learned: str = "full",
) -> dict[str, Any]:
    """Run the benchmark on one split (default leave one out); returns ``results.json``.

    ``learned`` is the budget of the ``ridge`` and ``mlp`` columns (:data:`LEARNED_MODES`).

    ``split="loo"`` predicts every demonstration from the others of its shape;
    ``"test"``/``"train"`` fit on each shape's training demonstrations of
    :func:`~motion_envs.datasets.splits.split_by_replicate` (``test_fraction``,
    ``split_seed``) and score the split's (the folds of
    :func:`motion_envs.datasets.splits.position_folds`, shared with PositionReach-v0).
    """
    from tqdm import tqdm

    kinds = ["start", "end"] if kinds is None else kinds
    position_conditions(np.zeros((1, 2, 1)), np.ones(1), kinds)  # validates the names
    if learned not in LEARNED_MODES:
        raise ValueError(f"learned must be one of {list(LEARNED_MODES)}; got {learned!r}")
    from baselines.learned import sklearn_missing_reason, torch_missing_reason

    have_peers = use_peers and peers_available()
    methods = [m for m in METHODS if have_peers or m not in PEER_METHODS]
    learned_skipped: dict[str, str] = {}
    missing_sklearn, missing_torch = sklearn_missing_reason(), torch_missing_reason()
    if learned == "off":
        learned_skipped = {"ridge": "--learned off", "mlp": "--learned off"}
    elif missing_sklearn:
        learned_skipped = {"ridge": missing_sklearn, "mlp": missing_sklearn}
    elif missing_torch:
        learned_skipped = {"mlp": missing_torch}
    methods = [m for m in methods if m not in learned_skipped]
    learned_methods = [m for m in ("ridge", "mlp") if m in methods]
    learned_chosen: dict[str, Any] = {}
    learned_seconds = 0.0
    y_all, dur_all = resample_positions(dataset, n_points)
    timer = _Timer()
    per_shape: dict[str, Any] = {}
    predictions: dict[str, dict[str, FloatArray]] = {}
    truths: dict[str, FloatArray] = {}
    folds = position_folds(dataset, split, test_fraction, split_seed)
    _check_enough_demonstrations(dataset, folds, split, n_sines, learned_methods)
    skipped = []
    for task in tqdm(dataset.task_names(), desc="shapes", file=sys.stderr, disable=not progress):
        task_folds = [f for f in folds if f[0] == task]
        if not task_folds:
            skipped.append(task)
            continue
        scored = np.concatenate([f[2] for f in task_folds])
        preds, chosen = predict_folds(
            y_all, dur_all, task_folds, kinds, n_sines, methods, timer, n_weights
        )
        if learned_methods:
            from baselines.learned import mlp_config
            from baselines.learned.position import learned_position_predictions

            t_l = time.perf_counter()
            learned_preds, learned_chosen[task] = learned_position_predictions(
                y_all, dur_all, task_folds, kinds, learned_methods, mlp_config(learned)
            )
            learned_seconds += time.perf_counter() - t_l
            preds.update(learned_preds)
        y = y_all[scored]
        members = dataset.tasks == task
        n_val = Counter(chosen).most_common(1)[0][0]
        per_shape[task] = {
            "n_demos": int(members.sum()),
            "n_scored": int(scored.size),
            "n_sines": chosen,
            "criteria": _score(y, preds),
            "validation": _validation_rows(y_all[members], dur_all[members], kinds, n_val),
        }
        predictions[task] = preds
        truths[task] = y
    if not per_shape:
        counts = ", ".join(f"{t!r}: {int((dataset.tasks == t).sum())}" for t in skipped)
        raise ValueError(
            f"no shape/task can be scored on split {split!r}: each needs at least "
            f"{MIN_DEMOS_LOO} demonstrations (demonstrations per shape: {counts})"
        )
    summary = {
        m: {
            c: float(np.median([per_shape[s]["criteria"][m][c] for s in per_shape]))
            for c in CRITERIA
        }
        for m in methods
    }
    timing = {
        m: {
            "fit_s_per_call": timer.fit[m] / timer.n_fit[m],
            "predict_s_per_call": timer.predict[m] / timer.n_predict[m],
        }
        for m in ("lippi", *PEER_METHODS)
        if timer.n_fit[m]
    }
    if "lippi" in timing:
        timing["lippi"]["cv_s_per_call"] = timer.fit["lippi_cv"] / timer.n_fit["lippi"]
        for m in PEER_METHODS:
            if m in timing:
                timing[f"{m}_over_lippi"] = {
                    "fit": timing[m]["fit_s_per_call"] / timing["lippi"]["fit_s_per_call"],
                    "predict": timing[m]["predict_s_per_call"]
                    / timing["lippi"]["predict_s_per_call"],
                }
    return {
        "dataset": dataset.name,
        "unit": dataset.unit,
        "n_points": n_points,
        "split": {"split": split, "test_fraction": test_fraction, "split_seed": split_seed},
        "conditions": kinds,
        "n_sines": "auto (leave-one-out CV, 0..15)" if n_sines is None else n_sines,
        "methods": methods,
        "peers_available": have_peers,
        "criteria": CRITERION_TEXT,
        "summary_median_across_shapes": summary,
        "per_shape": per_shape,
        "skipped": skipped,
        "timing": timing,
        "learned": {
            "skipped": learned_skipped,
            "chosen": learned_chosen,
            "seconds_ridge_and_mlp": learned_seconds,
        },
        "citation": LASA_CITATION if dataset.name == "lasa" else None,
        "_predictions": predictions,
        "_truth": truths,
    }
