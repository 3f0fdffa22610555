"""Train/test splits of datasets by subject (held-out people, not held-out samples).

A split by subject judges a model on people it has never seen: every trajectory of a
test subject is in the test set and none in the training set. The subjects are sorted,
shuffled with ``numpy.random.default_rng(seed)`` and the first
``max(1, round(test_fraction * n_subjects))`` of the permutation are the test subjects
(at least one subject always stays in training). The same ``(dataset, test_fraction,
seed)`` always gives the same split, on every platform.
"""

from __future__ import annotations

from typing import Any, Protocol, TypeVar

import numpy as np
from numpy.typing import NDArray

__all__ = [
    "DEFAULT_SPLIT_SEED",
    "DEFAULT_TEST_FRACTION",
    "POSITION_SPLITS",
    "held_out_subjects",
    "position_folds",
    "split_by_replicate",
    "split_by_subject",
]

#: Seed of the default split used by the environments and ``motion-bench``.
DEFAULT_SPLIT_SEED = 0
#: Default share of the subjects held out for testing.
DEFAULT_TEST_FRACTION = 0.25
#: Splits of a position dataset (see :func:`position_folds`).
POSITION_SPLITS: tuple[str, ...] = ("train", "test", "loo")


class _SubjectDataset(Protocol):
    @property
    def subjects(self) -> NDArray[np.str_]: ...

    def __len__(self) -> int: ...

    def subset(self, mask: Any) -> Any: ...


D = TypeVar("D", bound=_SubjectDataset)


def _check(test_fraction: float, seed: int) -> None:
    if not isinstance(test_fraction, (float, int)) or isinstance(test_fraction, bool):
        raise ValueError(f"test_fraction must be a number in (0, 1); got {test_fraction!r}")
    if not 0.0 < float(test_fraction) < 1.0:
        raise ValueError(f"test_fraction must be in (0, 1); got {test_fraction!r}")
    if isinstance(seed, bool) or not isinstance(seed, (int, np.integer)) or seed < 0:
        raise ValueError(f"seed must be an integer >= 0; got {seed!r}")


def held_out_subjects(
    subjects: NDArray[np.str_] | list[str],
    test_fraction: float = DEFAULT_TEST_FRACTION,
    seed: int = DEFAULT_SPLIT_SEED,
) -> NDArray[np.str_]:
    """The sorted subject labels held out for testing (see the module docstring)."""
    _check(test_fraction, seed)
    unique = np.unique(np.asarray(subjects).astype(str))
    if unique.size < 2:
        raise ValueError(
            f"a split by subject needs at least 2 subjects; the dataset has {unique.size} "
            "(split one person's trials with split_by_replicate; the orientation "
            "environments: split_by='replicate')"
        )
    n_test = min(max(1, round(float(test_fraction) * unique.size)), unique.size - 1)
    order = np.random.default_rng(int(seed)).permutation(unique.size)
    return np.sort(unique[order[:n_test]])


def split_by_subject(
    dataset: D, test_fraction: float = DEFAULT_TEST_FRACTION, seed: int = DEFAULT_SPLIT_SEED
) -> tuple[D, D]:
    """Split a dataset into ``(train, test)`` by subject.

    Parameters
    ----------
    dataset:
        Any dataset with a ``subjects`` array (one label per trajectory) and a
        ``subset(mask)`` method, e.g. :class:`~motion_envs.datasets.OrientationDataset`.
    test_fraction:
        Share of the *subjects* (not trajectories) held out, in ``(0, 1)``; rounded to
        a whole number of subjects, at least 1 and at most ``n_subjects - 1``.
    seed:
        Seed of the subject permutation (``numpy.random.default_rng(seed)``).

    Returns
    -------
    train, test:
        Two datasets of the same type; trajectory order is kept.
    """
    held_out = held_out_subjects(dataset.subjects, test_fraction, seed)
    is_test = np.isin(np.asarray(dataset.subjects).astype(str), held_out)
    return dataset.subset(~is_test), dataset.subset(is_test)


def split_by_replicate(
    dataset: Any,
    test_fraction: float = DEFAULT_TEST_FRACTION,
    seed: int = DEFAULT_SPLIT_SEED,
    mask: bool = False,
) -> Any:
    """Split each task's demonstrations into train and test (for one-subject data, e.g. LASA).

    Tasks are visited in sorted order with one ``numpy.random.default_rng(seed)``; each
    task's trajectories are permuted and the first
    ``min(max(1, round(test_fraction * n)), n - 2)`` held out, so at least two stay in
    training (a task with fewer than 3 trajectories stays wholly in training).

    Returns ``(train, test)`` datasets, or with ``mask=True`` the ``(L,)`` boolean mask
    of the test trajectories.
    """
    _check(test_fraction, 0)
    if isinstance(seed, bool) or not isinstance(seed, (int, np.integer)) or seed < 0:
        raise ValueError(f"seed must be an integer >= 0; got {seed!r}")
    tasks = np.asarray(dataset.tasks).astype(str)
    rng = np.random.default_rng(int(seed))
    is_test = np.zeros(tasks.size, dtype=bool)
    for task in np.unique(tasks):
        members = np.flatnonzero(tasks == task)
        n_test = min(max(1, round(float(test_fraction) * members.size)), members.size - 2)
        perm = rng.permutation(members.size)
        if n_test > 0:
            is_test[members[perm[:n_test]]] = True
    if mask:
        return is_test
    return dataset.subset(~is_test), dataset.subset(is_test)


def position_folds(
    dataset: Any,
    split: str = "loo",
    test_fraction: float = 0.25,
    seed: int = 0,
) -> list[tuple[str, NDArray[np.int64], NDArray[np.int64]]]:
    """The ``(task, train indices, scored indices)`` folds of a split of a position
    dataset (anything with ``.tasks``), tasks in order of first appearance.

    * ``"loo"``: one fold per demonstration, trained on the other demonstrations of its
      task (tasks with fewer than 3 demonstrations are skipped);
    * ``"train"`` / ``"test"``: one fold per task, trained on the task's training
      demonstrations of :func:`~motion_envs.datasets.splits.split_by_replicate`
      (``test_fraction``, ``seed``) and scoring the split's own (tasks with none skipped).
    """
    if split not in POSITION_SPLITS:
        raise ValueError(f"split must be one of {list(POSITION_SPLITS)}; got {split!r}")
    tasks = np.asarray(dataset.tasks).astype(str)
    folds: list[tuple[str, NDArray[np.int64], NDArray[np.int64]]] = []
    if split != "loo":
        is_test = split_by_replicate(dataset, test_fraction=test_fraction, seed=seed, mask=True)
    for task in dict.fromkeys(tasks.tolist()):
        members = np.flatnonzero(tasks == task)
        if split == "loo":
            if members.size < 3:
                continue
            folds.extend((task, members[members != i], np.array([i])) for i in members)
        else:
            in_task = tasks == task
            scored = np.flatnonzero(in_task & (is_test if split == "test" else ~is_test))
            if scored.size:
                folds.append((task, np.flatnonzero(in_task & ~is_test), scored))
    return folds
