"""``motion-bench position``: the sine-series model on LASA (or the users' CSV) vs peers.

Leave one demonstration out per shape (task): every method is fitted on the other
demonstrations of the shape and predicts the held-out one from its start point, end
point and duration. All trajectories are resampled (linear interpolation) to
``--n-points`` samples of normalised time ``tau = t / T`` and every method works and is
scored on that grid, so the time normalisation is the same for all.

Methods:

* ``line``: the straight line from start to end;
* ``null``: the line plus the mean residual ``D(tau)`` of the training demonstrations;
* ``lippi``: :class:`~motion_envs.models.sine_regression.SineSeriesRegression` with
  conditions ``--conditions`` (start and end by default; columns constant over the
  training demonstrations, such as LASA's end point at the origin, are dropped) and ``N``
  chosen by leave-one-out cross-validation on the training demonstrations
  (``--n-sines auto``);
* ``dmp``, ``promp``: :mod:`baselines.peers` (``movement_primitives``), same start/goal;
* ``ridge``, ``mlp``: learned residuals (:mod:`baselines.learned.position`, docs/learned.md):
  ridge and a torch MLP of Lippi's residual on the conditions, hyper-parameters chosen
  on the training demonstrations only (``mlp`` is skipped without torch; both with
  ``--learned off``).

Criteria per held-out demonstration: max error (the papers' criterion), RMSE, DTW and
swept error area (:mod:`motion_envs.models.position_criteria`). Per shape we take the
median over its demonstrations; the printed table is the median across shapes. The
reading compares the learned columns with the analytic ones (ratios, a bootstrap over
shapes, per-shape counts; ``learned_ratio.png``).

:func:`run` computes (a pure function of a :class:`PositionConfig`), :func:`report` is
the printed text, :func:`write` writes ``results.json``, ``results.csv`` and
``shapes.png``; :func:`register` adds the sub-command to ``motion-bench``.
"""

from __future__ import annotations

import argparse
import csv
import io
import json
import math
import sys
import time
from collections import Counter, defaultdict
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from baselines import options
from baselines.learned import LEARNED_MODES
from baselines.peers import DMPPeer, ProMPPeer, peers_available, peers_missing_reason
from motion_envs._io import atomic_write_text, save_figure
from motion_envs.datasets import POSITION_DATASETS, load_position_dataset
from motion_envs.datasets.lasa import LASA_CITATION
from motion_envs.datasets.position_csv import PositionDataset
from motion_envs.datasets.resampling import resample_positions
from motion_envs.datasets.splits import POSITION_SPLITS, position_folds
from motion_envs.models.position_criteria import CRITERIA
from motion_envs.models.position_nominal import (
    CONDITION_KINDS,
    PositionNominal,
    position_conditions,
    varying_columns,
)
from motion_envs.models.sine_regression import SineSeriesRegression

__all__ = [
    "METHODS",
    "PositionConfig",
    "format_table",
    "plot_grid",
    "register",
    "report",
    "run",
    "run_benchmark",
    "write",
]

FloatArray = NDArray[np.float64]

METHODS: tuple[str, ...] = ("line", "null", "lippi", "dmp", "promp", "ridge", "mlp")
PEER_METHODS = ("dmp", "promp")

CRITERION_TEXT = {
    "max_error": "median over demos of max_t |error|",
    "rmse": "median over demos of RMSE",
    "dtw": "median over demos of DTW (sum of Euclidean costs)",
    "swept_area": "median over demos of swept error area",
}


@dataclass(frozen=True)
class PositionConfig:
    """What ``motion-bench position`` computes (the defaults are the CLI's).

    ``data`` is ``"lasa"`` or a position CSV path, ``shapes`` the tasks kept (None: all);
    the other fields are :func:`run_benchmark`'s arguments (``n_sines=None``: chosen by
    cross-validation; ``use_peers``: the DMP and ProMP columns when installed;
    ``learned``: the budget of the ridge and mlp columns, one of :data:`LEARNED_MODES`).
    """

    data: str = "lasa"
    shapes: tuple[str, ...] | None = None
    n_points: int = 200
    conditions: tuple[str, ...] = ("start", "end")
    n_sines: int | None = None
    n_weights: int = 10
    split: str = "loo"
    test_fraction: float = 0.25
    split_seed: int = 0
    use_peers: bool = True
    progress: bool = True
    learned: str = "full"


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
    model = SineSeriesRegression(n_sines=n_sines).fit(list(y), q)
    return model.validate().summary()


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
    :func:`motion_envs.models.nominal.position_folds`, shared with PositionReach-v0).
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
        raise ValueError(
            f"no shape/task can be scored on split {split!r} "
            "(leave-one-out needs 3 or more trajectories per task)"
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


def _split_text(split: dict[str, Any]) -> str:
    if split["split"] == "loo":
        return "leave one demonstration out"
    return (
        f"{split['split']} split (test fraction {split['test_fraction']:g} per shape, "
        f"seed {split['split_seed']})"
    )


def format_table(doc: dict[str, Any]) -> str:
    """The printed table: median across shapes of each per-shape criterion."""
    methods = doc["methods"]
    unit = f" ({doc['unit']})" if doc["unit"] else ""
    lines = [
        f"position benchmark on {doc['dataset']!r}: {len(doc['per_shape'])} shapes, "
        f"{_split_text(doc['split'])}, {doc['n_points']}-point normalised-time grid{unit}",
        "per shape: median over held-out demos; below: median across shapes",
        "",
        f"{'criterion':<56}" + "".join(f"{m:>10}" for m in methods),
        "-" * (56 + 10 * len(methods)),
    ]
    for c, text in doc["criteria"].items():
        vals = "".join(f"{doc['summary_median_across_shapes'][m][c]:10.3f}" for m in methods)
        lines.append(f"{c + ': ' + text:<56}{vals}")
    if not doc["peers_available"]:
        lines.append("dmp, promp: skipped (movement_primitives not installed or not requested)")
    return "\n".join(lines)


def format_validation(doc: dict[str, Any]) -> str:
    """Per shape (phase) and coordinate: the paper's checks of the linear hypothesis."""
    lines = [
        "validation of the linear hypothesis (Lippi et al.), all demos of each shape, "
        "non-exact sine coefficients:",
        "  normal: share with Lilliefors p > 0.05; F-test: share with p < 0.05; "
        "CI/|F|: median 95% CI half-width over |F|; jack/|F|: median jackknife sd over |F|",
        f"{'shape':<18}{'coord':>6}{'n':>4}{'normal':>8}{'F-test':>8}{'CI/|F|':>9}{'jack/|F|':>10}",
    ]
    for shape, res in doc["per_shape"].items():
        if not res["validation"]:
            lines.append(f"{shape:<18}  (too few demonstrations for the tests)")
        for row in res["validation"]:
            lines.append(
                f"{shape:<18}{row['coordinate']:>6}{row['n_coefficients']:>4}"
                f"{row['normal_frac']:8.2f}{row['ftest_frac']:8.2f}"
                f"{row['ci_rel']:9.2f}{row['jack_rel']:10.2f}"
            )
    return "\n".join(lines)


def _clean(value: Any) -> Any:
    if isinstance(value, float):
        return value if math.isfinite(value) else None
    if isinstance(value, dict):
        return {k: _clean(v) for k, v in value.items() if not str(k).startswith("_")}
    if isinstance(value, list):
        return [_clean(v) for v in value]
    return value


def _csv_text(doc: dict[str, Any]) -> str:
    buf = io.StringIO()
    writer = csv.writer(buf)
    writer.writerow(["shape", "method", *CRITERIA])
    for shape, res in doc["per_shape"].items():
        for m, vals in res["criteria"].items():
            writer.writerow([shape, m, *(f"{vals[c]:.6g}" for c in CRITERIA)])
    return buf.getvalue()


def plot_grid(doc: dict[str, Any], path: Path) -> Path:
    """Held-out demonstrations and each method's predictions (see :mod:`baselines.plots`),
    written atomically to ``path``."""
    from baselines.plots import shapes_figure

    return save_figure(shapes_figure(doc), path, dpi=100)


def run(config: PositionConfig) -> dict[str, Any]:
    """The benchmark of ``config``: the ``results.json`` document (plus the predictions
    under ``_predictions``/``_truth`` for :func:`plot_grid`) with the learned columns'
    comparisons under ``learned.comparisons``; no files, no printing except the progress
    bar on stderr when ``config.progress``."""
    from baselines.learned.position_reading import position_comparisons

    if config.learned not in LEARNED_MODES:
        raise options.ConfigError(
            "learned", f"expected one of {list(LEARNED_MODES)}; got {config.learned!r}"
        )
    dataset = load_position_dataset(config.data, config.shapes)
    doc = run_benchmark(
        dataset,
        n_points=config.n_points,
        kinds=list(config.conditions),
        n_sines=config.n_sines,
        use_peers=config.use_peers,
        n_weights=config.n_weights,
        progress=config.progress,
        split=config.split,
        test_fraction=config.test_fraction,
        split_seed=config.split_seed,
        learned=config.learned,
    )
    doc["learned"]["comparisons"] = position_comparisons(doc)
    return doc


def report(doc: dict[str, Any]) -> str:
    """The text ``motion-bench position`` prints: table, learned reading, validation,
    timing."""
    from baselines.learned.position_reading import format_position_reading

    parts = [format_table(doc)]
    if doc["learned"]["comparisons"] or doc["learned"]["skipped"]:
        parts.append(format_position_reading(doc, doc["learned"]["comparisons"]))
    parts += ["", format_validation(doc)]
    if doc["timing"]:
        parts += [
            "",
            "timing, seconds per call (fit on the training demos / generate one trajectory):",
        ]
        for m, v in doc["timing"].items():
            if "fit_s_per_call" in v:
                parts.append(
                    f"  {m:<6} fit {v['fit_s_per_call']:.3g}  predict {v['predict_s_per_call']:.3g}"
                )
            else:
                parts.append(f"  {m:<13} fit x{v['fit']:.1f}  predict x{v['predict']:.1f}")
    return "\n".join(parts)


def write(doc: dict[str, Any], out: str | Path) -> list[Path]:
    """Write ``results.json``, ``results.csv``, ``shapes.png`` and, with learned columns,
    ``learned_ratio.png`` into ``out`` (atomic)."""
    folder = Path(out)
    written = [
        atomic_write_text(folder / "results.json", json.dumps(_clean(doc), indent=2) + "\n"),
        atomic_write_text(folder / "results.csv", _csv_text(doc)),
    ]
    plot_grid(doc, folder / "shapes.png")
    written.append(folder / "shapes.png")
    comparisons = doc["learned"]["comparisons"]
    if comparisons:
        from baselines.learned_rows import plot_ratios

        written.append(
            plot_ratios(
                comparisons,
                folder / "learned_ratio.png",
                f"per-shape ratio of learned to the best analytic column, {doc['dataset']}",
                group="shape",
            )
        )
    return written


def warn_missing_peers(use_peers: bool) -> None:
    """Say on stderr when the DMP and ProMP columns will be skipped."""
    missing = peers_missing_reason() if use_peers else None
    if missing:
        print(
            f"motion-bench position: movement_primitives cannot be used ({missing}); "
            "the DMP and ProMP columns are skipped",
            file=sys.stderr,
        )


def main(args: argparse.Namespace) -> int:
    """``motion-bench position`` with parsed arguments: run, print, write."""
    warn_missing_peers(not args.no_peers)
    config = PositionConfig(
        data=args.data,
        shapes=tuple(args.shapes) if args.shapes else None,
        n_points=args.n_points,
        conditions=args.conditions,
        n_sines=args.n_sines,
        n_weights=args.n_weights,
        split=args.split,
        test_fraction=args.test_fraction,
        split_seed=args.split_seed,
        use_peers=not args.no_peers,
        progress=not args.no_progress,
        learned=args.learned,
    )
    doc = run(config)
    print(report(doc))
    if args.out:
        written = write(doc, args.out)
        print(f"wrote {', '.join(map(str, written[:-1]))} and {written[-1]}")
    return 0


def position_data(text: str) -> str:
    """``--data``: ``lasa`` or an existing position CSV file."""
    if text in POSITION_DATASETS:
        return text
    if (recording := options.mocap_data(text, "position")) is not None:  # FILE.c3d?opt=...
        return recording
    if not Path(text).exists():
        raise argparse.ArgumentTypeError(
            f"expected one of {list(POSITION_DATASETS)} or a CSV file; {text} does not exist"
        )
    return str(options.input_file(text))


def n_sines_option(text: str) -> int | None:
    """``--n-sines``: ``auto`` (None, chosen by cross-validation) or an integer >= 0."""
    if text == "auto":
        return None
    try:
        return options.non_negative_int(text)
    except argparse.ArgumentTypeError:
        raise argparse.ArgumentTypeError(
            f"expected 'auto' or an integer >= 0; got {text!r}"
        ) from None


def conditions_option(text: str) -> tuple[str, ...]:
    """``--conditions``: a comma list of ``start``, ``end``, ``duration``."""
    kinds = tuple(k.strip() for k in text.split(",") if k.strip())
    bad = [k for k in kinds if k not in CONDITION_KINDS]
    if bad or not kinds:
        raise argparse.ArgumentTypeError(
            f"expected a comma list of {', '.join(CONDITION_KINDS)}; got {text!r}"
        )
    return kinds


def register(subparsers: argparse._SubParsersAction[options.Parser]) -> None:
    """Add the ``position`` sub-command."""
    p = options.add_subcommand(
        subparsers,
        "position",
        help="sine-series model (Lippi et al.) vs line, null, DMP, ProMP on LASA or a CSV",
        description=(
            "Leave one demonstration out per shape (task): every method is fitted on the\n"
            "other demonstrations of the shape and predicts the held-out one from its start,\n"
            "end and duration, on an --n-points grid of normalised time tau = t / T.\n"
            "Methods: line (start to end), null (line + mean residual), lippi (sine-series\n"
            "regression on --conditions, N by leave-one-out cross-validation), dmp and promp\n"
            "(movement_primitives, same start and goal). Criteria: max error (the papers'),\n"
            "RMSE, DTW, swept error area; median over a shape's demonstrations, then across\n"
            "shapes. ridge and mlp: learned residuals (ridge, torch MLP) of the conditions,\n"
            "every hyper-parameter chosen on the training demonstrations only (--learned)."
        ),
    )
    p.add_argument(
        "--data",
        default="lasa",
        type=position_data,
        help="'lasa', a position CSV path, or a recording 'FILE.c3d|.bvh|.tsv?option=value&...' "
        "with motion-bench import's options (docs/recordings.md)",
    )
    p.add_argument(
        "--shapes", nargs="+", default=None, help="shapes (LASA) or tasks (CSV); default: all"
    )
    p.add_argument(
        "--out",
        default=None,
        type=options.output_folder,
        help="folder for results.json/.csv and shapes.png (nothing written without it)",
    )
    p.add_argument(
        "--n-points", type=options.int_at_least(5), default=200, help="normalised-time grid size"
    )
    p.add_argument(
        "--n-sines", type=n_sines_option, default="auto", help="N, or 'auto' for cross-validation"
    )
    p.add_argument(
        "--conditions",
        type=conditions_option,
        default="start,end",
        help="comma list of start, end, duration",
    )
    p.add_argument(
        "--n-weights", type=options.positive_int, default=10, help="DMP/ProMP weights per dimension"
    )
    p.add_argument(
        "--split",
        choices=POSITION_SPLITS,
        default="loo",
        help="loo: leave one demonstration out per shape; test/train: fit on each shape's "
        "training demonstrations (split_by_replicate) and score the test/train ones, as "
        "PositionReach-v0's split",
    )
    p.add_argument(
        "--test-fraction",
        type=options.fraction,
        default=0.25,
        help="held-out share per shape (test/train)",
    )
    p.add_argument(
        "--split-seed", type=options.non_negative_int, default=0, help="seed of the per-shape split"
    )
    p.add_argument("--no-peers", action="store_true", help="skip DMP and ProMP")
    p.add_argument("--no-progress", action="store_true", help="no progress bar")
    p.add_argument(
        "--learned",
        choices=LEARNED_MODES,
        default="full",
        help="budget of the learned ridge and torch-MLP columns (docs/learned.md); quick: one "
        "MLP candidate, 30 epochs, 2 inner folds; off: neither column; the mlp column is "
        "skipped with a message when torch is not installed",
    )
    p.set_defaults(func=main)
