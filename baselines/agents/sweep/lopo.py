"""Agents judged by people: the summary of a leave-one-person-out sweep.

A LOPO sweep (``configs/sweeps/orientation_lopo.yaml``) trains one agent per fold and
seed: the environment's ``fold = i`` holds the ``i``-th person out as its test split.
With ``inner_folds: K`` (the shipped file) each trial is nested
(:mod:`baselines.agents.sweep.nested`): the checkpoint is chosen by ``K`` inner folds
over the fold's training people, then one agent is refitted on all of them with the
nominal fitted on them for training and for scoring. Without it, checkpoints are chosen
on validation people carved from the training people (``val_fraction``). Each trial's
``test_ratio`` is the agent's criterion over the nominal's on one held-out person.

:func:`lopo_summary` gives, per person (fold), the ratio of every seed and their median;
across people the interquartile mean of the ``(seeds, people)`` ratios with its 95 %
interval over people (:func:`baselines.stats.group_bootstrap`: a person's seeds move
together) and the stratified one over seeds within each person
(:func:`baselines.stats.iqm_intervals`), the number of people on which the agent is below
the nominal, and the verdict in words (:func:`baselines.stats.verdict`: lower is better).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np
from numpy.typing import NDArray

__all__ = ["fold_of", "format_lopo", "lopo_summary"]


def fold_of(configuration: Mapping[str, Any]) -> int | None:
    """The ``fold`` environment argument of a sweep configuration (None: not LOPO)."""
    fold = (configuration.get("overrides", {}).get("env_kwargs") or {}).get("fold")
    return None if fold is None else int(fold)


def _inner_score(trial: Mapping[str, Any]) -> float:
    """What chooses among a fold's configurations: the inner folds' mean ratio at the kept
    step (nested trials), else the validation criterion over the nominal's."""
    if trial.get("inner_val_ratio") is not None:
        return float(trial["inner_val_ratio"])
    nominal = trial.get("val_nominal_criterion")
    if trial.get("best_val_criterion") is None or not nominal:
        return float("inf")
    return float(trial["best_val_criterion"]) / float(nominal)


def _iqm_block(per_person: Mapping[int, Mapping[int, float]], seeds: list[int]) -> dict[str, Any]:
    """IQM over the ``(seeds, people)`` ratios with two 95 % intervals, medians per
    person, the people below 1 and the verdict.

    ``iqm_ratio_ci95`` resamples *people* (all seeds of a person together: the question
    is how the agent does on new people; the verdict uses it; ``detectable_ratios``: the
    ratios it detects 80 % of the time at this many people, :func:`detectable_ratios`,
    and ``decidable``: whether the IQM reaches it); ``iqm_ratio_ci95_seeds``
    is the stratified one (seeds resampled within each person, the people fixed: the seed noise
    only, a point with one seed)."""
    from baselines.stats import (
        detectable_ratios,
        group_bootstrap_replicates,
        iqm,
        iqm_intervals,
        verdict,
    )

    people = sorted(per_person)
    matrix = np.array([[per_person[p][s] for p in people] for s in seeds])  # (seeds, people)
    agg = iqm_intervals({"ratio": matrix})["ratio"]
    flat = matrix.ravel()  # cell (seed, person) -> seed * n_people + person

    def of_rows(rows: NDArray[np.int64]) -> float:
        return iqm(flat[rows])

    person_of_cell = np.tile(np.asarray(people), len(seeds))
    point, lo, hi, reps = group_bootstrap_replicates(of_rows, person_of_cell)
    below, above = detectable_ratios(point, lo, hi, reps)
    claimed = agg["iqm"]
    decidable = bool(claimed <= below) if claimed <= 1.0 else bool(claimed >= above)
    medians = np.median(matrix, axis=0)
    return {
        "ratio_per_person": {str(p): dict(per_person[p]) for p in people},
        "ratio_per_person_median": {str(p): float(m) for p, m in zip(people, medians, strict=True)},
        "iqm_ratio": agg["iqm"],
        "iqm_ratio_ci95": [lo, hi],
        "iqm_ratio_ci95_seeds": list(agg["ci95"]),
        "people_below_one": int(np.sum(medians < 1.0)),
        "verdict": verdict(lo, hi, n_groups=len(people)),
        "detectable_ratios": [below, above],
        "decidable": decidable if np.isfinite(below) else None,
    }


def lopo_summary(
    trials: Sequence[Mapping[str, Any]], configurations: Sequence[Mapping[str, Any]]
) -> dict[str, Any] | None:
    """Per-person ratios, their IQM with its interval and the verdict (module docstring);
    None when no configuration has a ``fold`` or a ratio is missing.

    Where a fold has several configurations (searched hyper-parameters), the one with
    the lowest median over seeds of the inner score (:func:`_inner_score`: never the
    held-out person) is the fold's, and only its test ratios are reported. The agent over
    the learned ridge regressor fitted on the same training people (``agent_over_ridge``)
    is summarised the same way when every trial has it."""
    folds = {i: fold_of(c) for i, c in enumerate(configurations)}
    by_fold: dict[int, dict[int, list[Mapping[str, Any]]]] = {}
    for t in trials:
        fold = folds.get(int(t["config_index"]))
        if fold is None or t.get("test_ratio") is None:
            continue
        by_fold.setdefault(fold, {}).setdefault(int(t["config_index"]), []).append(t)
    if not by_fold:
        return None
    chosen = {
        fold: min(cands, key=lambda c: (np.median([_inner_score(t) for t in cands[c]]), c))
        for fold, cands in by_fold.items()
    }
    kept = {fold: by_fold[fold][c] for fold, c in chosen.items()}
    per_person = {f: {int(t["seed"]): float(t["test_ratio"]) for t in ts} for f, ts in kept.items()}
    people = sorted(per_person)
    seeds = sorted(set.intersection(*(set(v) for v in per_person.values())))
    if not seeds:
        return None
    per_person = {p: {s: per_person[p][s] for s in seeds} for p in people}
    block = _iqm_block(per_person, seeds)
    nested = all(t.get("inner_val_ratio") is not None for ts in kept.values() for t in ts)
    out: dict[str, Any] = {
        "folds": people,
        "seeds": seeds,
        "chosen_config_per_person": {str(p): chosen[p] for p in people},
        "selection": "inner folds over the training people"
        if nested
        else "validation people carved from the training people",
        **{k: v for k, v in block.items() if k != "people_below_one"},
        "people_below_nominal": block["people_below_one"],
        "n_people": len(people),
    }
    learned = {
        p: {int(t["seed"]): t.get("test_learned_ratio") for t in kept[p] if t["seed"] in seeds}
        for p in people
    }
    if all(r is not None for v in learned.values() for r in v.values()):
        over = _iqm_block(
            {p: {s: float(r) for s, r in v.items() if r is not None} for p, v in learned.items()},
            seeds,
        )
        first = {p: kept[p][0] for p in people}  # the ridge and nominal: the same for all seeds
        ridge = {
            str(p): float(t["test_learned_criterion"]) / float(t["test_nominal_criterion"])
            for p, t in first.items()
        }
        out["agent_over_ridge"] = {**over, "ridge_over_nominal_per_person": ridge}
    return out


def _power(block: Mapping[str, Any]) -> str:
    """The power clause of a summary line (blocks written before it was added: none)."""
    det = block.get("detectable_ratios")
    if det is None or block.get("decidable") is None:
        return ""
    below, above = det
    tail = ""
    if not block["decidable"] and block["verdict"] == "no difference":
        tail = "; cannot decide at this size"
    elif not block["decidable"] and block["verdict"] in ("better", "worse"):
        tail = "; an effect below the one this size detects 80 % of the time"
    return f"; 80 % power at this many people for ratios <= {below:.3f} or >= {above:.3f}{tail}"


def format_lopo(lopo: Mapping[str, Any]) -> str:
    """The LOPO summary in words (unit, direction, interval, verdict)."""
    lo, hi = lopo["iqm_ratio_ci95"]
    per = ", ".join(f"fold {p}: {r:.3f}" for p, r in lopo["ratio_per_person_median"].items())
    lines = [
        f"agent / nominal per held-out person (median over {len(lopo['seeds'])} seeds; "
        f"checkpoints chosen by {lopo['selection']}): {per}",
        f"IQM of agent / nominal over people and seeds = {lopo['iqm_ratio']:.3f} "
        f"(95% CI {lo:.3f}-{hi:.3f} people resampled, lower is better); lower on "
        f"{lopo['people_below_nominal']}/{lopo['n_people']} people; {lopo['verdict']} at 95 %"
        + _power(lopo),
    ]
    over = lopo.get("agent_over_ridge")
    if over:
        lo, hi = over["iqm_ratio_ci95"]
        per = ", ".join(f"fold {p}: {r:.3f}" for p, r in over["ratio_per_person_median"].items())
        lines += [
            f"agent / ridge regressor (fitted on the same training people) per person: {per}",
            f"IQM of agent / ridge = {over['iqm_ratio']:.3f} (95% CI {lo:.3f}-{hi:.3f} people "
            f"resampled, lower is better); lower on {over['people_below_one']}/"
            f"{lopo['n_people']} people; {over['verdict']} at 95 %" + _power(over),
        ]
    return "\n".join(lines)
