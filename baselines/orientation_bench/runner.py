"""The pure :func:`run` of ``motion-bench orientation``: Table 1, the nominal's criterion
and the learned leave-one-subject-out rows.

(Named ``runner`` so that the package attribute ``run`` stays the function.)"""

from __future__ import annotations

import math
import time
from typing import Any

import numpy as np

from baselines import options
from baselines.learned import LEARNED_MODES
from baselines.learned.person_rows import LearnedPersonRows
from baselines.learned.rows import LearnedRows
from baselines.orientation_bench.config import OrientationConfig, OrientationResults
from motion_envs.datasets import OrientationDataset, load_orientation_dataset
from motion_envs.datasets.orientation import check_up
from motion_envs.datasets.splits import split_by_subject
from motion_envs.models.criteria import table1
from motion_envs.models.orientation_nominal import orientation_criterion
from motion_envs.models.person_calibration import PersonCalibration


def _split(
    config: OrientationConfig, dataset: OrientationDataset
) -> tuple[OrientationDataset, OrientationDataset]:
    return split_by_subject(dataset, test_fraction=config.test_fraction, seed=config.split_seed)


def _nominal_criterion(config: OrientationConfig, dataset: OrientationDataset) -> dict[str, Any]:
    """Offline criterion of ``config.nominal`` fitted on the train split, scored on ``split``.

    The same :mod:`motion_envs.models.orientation_nominal` code builds the environments'
    nominal, so the zero-action policy of ``MotionEnvs/OrientationReach-v0`` reproduces
    this value.
    """
    assert config.nominal is not None
    train, test = _split(config, dataset)
    scored = {"train": train, "test": test, "all": dataset}[config.split]
    res = orientation_criterion(train, scored, nominal=config.nominal, degree=config.degree)
    return {
        "nominal": config.nominal,
        "degree": config.degree,
        "scored_on": config.split,
        "criterion": res["criterion"],
        "n_train": res["n_train"],
        "n_scored": res["n_test"],
        "n_unseen": res["n_unseen"],
    }


def _learned_rows(
    config: OrientationConfig, dataset: OrientationDataset
) -> tuple[LearnedRows | None, str | None]:
    """The rows of :mod:`baselines.learned.rows` at ``config.learned``'s budget, or None
    and the reason they are skipped (too few subjects, scikit-learn missing)."""
    if config.learned == "off":
        return None, None
    n_subjects = np.unique(dataset.subjects).size
    if n_subjects < 3:
        return None, f"{n_subjects} subjects, at least 3 needed"
    from baselines.learned import mlp_config, sklearn_missing_reason, torch_missing_reason
    from baselines.learned.rows import learned_orientation_rows

    missing_sklearn = sklearn_missing_reason()
    if missing_sklearn:
        return None, missing_sklearn
    use_torch = torch_missing_reason() is None
    budget = mlp_config(config.learned) if use_torch else None
    return learned_orientation_rows(dataset, mlp_config=budget, use_torch=use_torch), None


def _pairs(dataset: OrientationDataset) -> dict[tuple[str, str], list[int]]:
    """The trajectories of each (subject, task) with at least 2 of them."""
    groups: dict[tuple[str, str], list[int]] = {}
    for i, key in enumerate(zip(dataset.subjects.tolist(), dataset.tasks.tolist(), strict=True)):
        groups.setdefault((str(key[0]), str(key[1])), []).append(i)
    return {k: v for k, v in groups.items() if len(v) >= 2}


def check_kept(
    config: OrientationConfig, every: OrientationDataset, kept: OrientationDataset
) -> None:
    """Raise a :class:`~baselines.options.ConfigError` saying what to change when the
    trajectories ``kept`` after ``--min-deg`` cannot make Table 1: fewer than 2, or no
    (subject, task) pair with 2 replicates (the within-subject row). The message says
    how many were dropped and why, and the largest ``--min-deg`` that would do."""
    angles = np.degrees(every.rotation_angles())
    dropped = len(every) - len(kept)
    why = (
        f"{dropped} of {len(every)} trajectories rotate less than {config.min_deg:g} degrees "
        f"from start to end and were dropped (--min-deg {config.min_deg:g}; the slerp is "
        "ill-posed for tiny rotations)"
    )
    pairs = _pairs(every)
    # the largest threshold that keeps a pair: the second largest angle of a pair's group
    keeps_pair = max((np.sort(angles[idx])[-2] for idx in pairs.values()), default=None)
    if len(kept) < 2 or not _pairs(kept):
        need = (
            f"{len(kept)} left, Table 1 needs at least 2"
            if len(kept) < 2
            else "no (subject, task) pair left has 2 replicates, which Table 1's "
            "within-subject row needs"
        )
        if keeps_pair is None:
            raise options.ConfigError(
                "data",
                f"{config.data}: no (subject, task) pair has 2 replicates, which Table 1's "
                "within-subject row needs: give a subject's repeats of a task the same "
                "subject and task labels (--subject/--task of the import, or the "
                "subject,task columns of a segments table)",
            )
        low = math.floor(keeps_pair * 10) / 10
        raise options.ConfigError(
            "min_deg",
            f"{why}; {need}: lower --min-deg to {low:g} or below (keeps "
            f"{int(np.sum(angles >= low))} trajectories)",
        )


def run(config: OrientationConfig) -> OrientationResults:
    """Table 1, the learned rows (and the nominal's criterion) for ``config``; no
    printing, no files.

    Raises ``ValueError`` for unusable data and :class:`~baselines.options.ConfigError`
    (naming the field) for a ``plot_task`` the data does not have or an ``up`` or
    ``learned`` that is not valid, before computing.
    """
    if config.learned not in LEARNED_MODES:
        raise options.ConfigError(
            "learned", f"expected one of {list(LEARNED_MODES)}; got {config.learned!r}"
        )
    if any(k < 1 for k in config.calibration):
        raise options.ConfigError("calibration", f"K must be >= 1; got {list(config.calibration)}")
    if config.up is not None:
        try:
            check_up(config.up)
        except ValueError as exc:
            raise options.ConfigError("up", str(exc)) from None
    t0 = time.perf_counter()
    every = load_orientation_dataset(config.data, min_deg=0.0, up=config.up)
    dataset = every.drop_small_rotations(config.min_deg)
    check_kept(config, every, dataset)
    full = dataset
    if config.split != "all":
        dataset = _split(config, full)[config.split == "test"]
    if config.plot_task is not None and config.plot_task not in set(dataset.tasks.tolist()):
        raise options.ConfigError(
            "plot_task",
            f"task {config.plot_task!r} is not in the data; choose one of "
            f"{sorted(set(dataset.tasks.tolist()))}",
        )
    table = table1(dataset.ragged, dataset.subjects, dataset.tasks, up=dataset.up)
    learned, note = _learned_rows(config, dataset)
    comparisons: list[dict[str, Any]] = []
    if learned is not None:
        from baselines.learned.rows import compare

        table.criteria.update(learned.criteria)
        comparisons = compare(learned, dataset.subjects)
    calibration, calibration_note = _calibration_rows(config, dataset)
    learned_calibration = None
    if calibration is not None:
        table.criteria.update(calibration.criteria)
        if learned is not None:
            learned_calibration = _learned_calibration_rows(config, dataset)
            table.criteria.update(
                {k: v for k, v in learned_calibration.criteria.items() if np.isfinite(v)}
            )
    from baselines.verdicts import orientation_verdicts

    subjects = np.asarray(dataset.subjects).astype(str)
    verdicts = orientation_verdicts(
        comparisons, calibration, config.calibration, subjects, learned, learned_calibration
    )
    elapsed = time.perf_counter() - t0
    nominal = _nominal_criterion(config, full) if config.nominal is not None else None
    return OrientationResults(
        config, dataset, table, nominal, elapsed, learned, comparisons, note,
        calibration, calibration_note, verdicts, learned_calibration,
    )  # fmt: skip


def _calibration_rows(
    config: OrientationConfig, dataset: OrientationDataset
) -> tuple[PersonCalibration | None, str | None]:
    """The person-calibration rows for ``config.calibration`` (None and why not)."""
    if not config.calibration:
        return None, None
    n_subjects = np.unique(dataset.subjects).size
    if n_subjects < 3:
        return None, f"{n_subjects} subjects, at least 3 needed"
    from motion_envs.models.person_calibration import person_calibration_rows

    rows = person_calibration_rows(
        dataset.ragged, dataset.subjects, config.calibration, up=dataset.up
    )
    return rows, None


def _learned_calibration_rows(
    config: OrientationConfig, dataset: OrientationDataset
) -> LearnedPersonRows:
    """The learned rows given the calibration summary (:mod:`baselines.learned.person_rows`)
    at ``config.learned``'s budget; called when both the learned and the calibration rows
    were computed (at least 3 subjects, scikit-learn installed)."""
    from baselines.learned import mlp_config, torch_missing_reason
    from baselines.learned.person_rows import learned_person_rows

    use_torch = torch_missing_reason() is None
    budget = mlp_config(config.learned) if use_torch else None
    return learned_person_rows(dataset, config.calibration, mlp_config=budget, use_torch=use_torch)
