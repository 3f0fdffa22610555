"""Agents judged by people: the summary of a leave-one-person-out sweep.

A LOPO sweep (``configs/sweeps/orientation_lopo.yaml``) trains one agent per fold and
seed: the environment's ``fold = i`` holds the ``i``-th person out as its test split
(nominal fitted on the other people, for training and for scoring) and carves
validation people from the training people (``val_fraction``: never a single person),
on which checkpoints are chosen. Each trial's ``test_ratio`` is then the agent's
criterion over the nominal's on one held-out person.

:func:`lopo_summary` gives, per person (fold), the ratio of every seed and their median;
across people the interquartile mean of the ``(seeds, people)`` ratios with its 95 %
interval (:func:`baselines.stats.iqm_intervals`, rliable; runs resampled within each
person), the number of people on which the agent is below the nominal, and the verdict
in words (:func:`baselines.stats.verdict`: lower is better).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np

__all__ = ["fold_of", "format_lopo", "lopo_summary"]


def fold_of(configuration: Mapping[str, Any]) -> int | None:
    """The ``fold`` environment argument of a sweep configuration (None: not LOPO)."""
    fold = (configuration.get("overrides", {}).get("env_kwargs") or {}).get("fold")
    return None if fold is None else int(fold)


def lopo_summary(
    trials: Sequence[Mapping[str, Any]], configurations: Sequence[Mapping[str, Any]]
) -> dict[str, Any] | None:
    """Per-person ratios, their IQM with its interval and the verdict (module docstring);
    None when no configuration has a ``fold`` or a ratio is missing."""
    from baselines.stats import iqm_intervals, verdict

    folds = {i: fold_of(c) for i, c in enumerate(configurations)}
    per_person: dict[int, dict[int, float]] = {}
    for t in trials:
        fold = folds.get(int(t["config_index"]))
        if fold is None or t.get("test_ratio") is None:
            continue
        per_person.setdefault(fold, {})[int(t["seed"])] = float(t["test_ratio"])
    if not per_person:
        return None
    people = sorted(per_person)
    seeds = sorted(set.intersection(*(set(v) for v in per_person.values())))
    if not seeds:
        return None
    matrix = np.array([[per_person[p][s] for p in people] for s in seeds])  # (seeds, people)
    agg = iqm_intervals({"ratio": matrix})["ratio"]
    lo, hi = agg["ci95"]
    medians = np.median(matrix, axis=0)
    return {
        "folds": people,
        "seeds": seeds,
        "ratio_per_person": {str(p): per_person[p] for p in people},
        "ratio_per_person_median": {str(p): float(m) for p, m in zip(people, medians, strict=True)},
        "iqm_ratio": agg["iqm"],
        "iqm_ratio_ci95": [lo, hi],
        "people_below_nominal": int(np.sum(medians < 1.0)),
        "n_people": len(people),
        "verdict": verdict(lo, hi),
    }


def format_lopo(lopo: Mapping[str, Any]) -> str:
    """The LOPO summary in words (unit, direction, interval, verdict)."""
    lo, hi = lopo["iqm_ratio_ci95"]
    per = ", ".join(f"fold {p}: {r:.3f}" for p, r in lopo["ratio_per_person_median"].items())
    return (
        f"agent / nominal per held-out person (median over {len(lopo['seeds'])} seeds): {per}\n"
        f"IQM of agent / nominal over people and seeds = {lopo['iqm_ratio']:.3f} "
        f"(95% CI {lo:.3f}-{hi:.3f}, lower is better); lower on "
        f"{lopo['people_below_nominal']}/{lopo['n_people']} people; {lopo['verdict']} at 95 %"
    )
