"""The configuration and results of ``motion-bench orientation``: :class:`OrientationConfig`
and :class:`OrientationResults`."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

from baselines.learned.person_rows import LearnedPersonRows
from baselines.learned.rows import LearnedRows
from baselines.stats import Comparison
from motion_envs.datasets import OrientationDataset
from motion_envs.datasets.vr_kitchen import DEFAULT_MIN_DEG
from motion_envs.models.criteria import Table1Result
from motion_envs.models.person_calibration import PersonCalibration

SPLITS: tuple[str, ...] = ("all", "train", "test")


@dataclass(frozen=True)
class OrientationConfig:
    """What ``motion-bench orientation`` computes (the defaults are the CLI's).

    Attributes
    ----------
    data:
        ``"vr-kitchen"``, ``"cohort"``, ``"cohort:CONFIG"`` or a path to an orientation CSV.
    min_deg:
        Trajectories rotating less than this (degrees, start to end) are dropped.
    split, split_seed, test_fraction:
        Table 1 on ``"all"`` trajectories or one side of the split by subject.
    nominal, degree:
        Also score this nominal model (fitted on the train split) on ``split``.
    plot_task:
        Task whose residuals :func:`write` draws (None: the most frequent).
    learned:
        Budget of the path-frame, predicted-timing and learned rows, one of
        :data:`LEARNED_MODES`.
    up:
        The data's vertical axis for the path frame (None: the dataset's own, ``+y`` for
        vr-kitchen, ``+z`` for a CSV and the cohort).
    calibration:
        The K of the person-calibration rows
        (:mod:`motion_envs.models.person_calibration`); empty: none.
    """

    data: str = "vr-kitchen"
    min_deg: float = DEFAULT_MIN_DEG
    split: str = "all"
    split_seed: int = 0
    test_fraction: float = 0.25
    nominal: str | None = None
    degree: int = 2
    plot_task: str | None = None
    learned: str = "full"
    up: tuple[float, float, float] | None = None
    calibration: tuple[int, ...] = ()


@dataclass(frozen=True)
class OrientationResults:
    """What :func:`run` returns: the scored dataset, Table 1 (with the learned rows
    appended to ``table.criteria``), the nominal's criterion and the learned rows.

    ``learned`` is None when the rows were not computed, ``learned_note`` then says why
    (None for ``--learned off``); ``comparisons`` are
    :func:`baselines.learned.rows.compare`'s readings; ``calibration`` the person-
    calibration rows (None when not asked for, ``calibration_note`` then says why when
    asked); ``verdicts`` every printed ratio with its interval (:mod:`baselines.verdicts`);
    ``learned_calibration`` the learned rows given the calibration summary
    (:mod:`baselines.learned.person_rows`; None unless both the learned and the
    calibration rows are computed).
    """

    config: OrientationConfig
    dataset: OrientationDataset
    table: Table1Result
    nominal: dict[str, Any] | None
    seconds: float
    learned: LearnedRows | None = None
    comparisons: list[dict[str, Any]] = field(default_factory=list)
    learned_note: str | None = None
    calibration: PersonCalibration | None = None
    calibration_note: str | None = None
    verdicts: list[Comparison] = field(default_factory=list)
    learned_calibration: LearnedPersonRows | None = None
