"""The intervals and verdicts of ``motion-bench orientation``, ``position`` and ``agent``.

Every ratio a benchmark prints is a :class:`baselines.stats.Comparison`: the ratio of two
methods' criteria (lower is better), its 95 % bootstrap interval over the groups that
matter (people for the orientation data and the reaching agents, shapes for LASA), the
win count per group and the verdict in words (docs/protocol.md). The benchmark modules
call this one and add its output under new keys of ``results.json`` (``intervals``,
``verdicts``); their existing values are unchanged. The learned-vs-analytic readings
keep the interval they already print (:func:`baselines.learned.reading.bootstrap_ratio`,
subjects or shapes resampled, seed 0); the new comparisons use
:func:`baselines.stats.compare_errors`.

Also here: the orientation table's predictive floors (``predictive_floor`` in the body
frame, ``predictive_floor_path`` in the path frame: each reach predicted from the other
replicates of its person and task, :mod:`motion_envs.models.criteria`) with every
out-of-sample row's distance to the floor of its frame (:func:`row_frame`), and the
labels and option of the person-calibration rows
(:mod:`motion_envs.models.person_calibration`).
"""

from __future__ import annotations

import argparse
from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np
from numpy.typing import NDArray

from baselines.stats import Comparison, compare_errors, from_readings, intervals_document
from motion_envs.models.person_calibration import PersonCalibration

__all__ = [
    "FLOOR_ROWS",
    "IN_SAMPLE_ROW",
    "agent_comparisons",
    "agent_verdicts",
    "calibration_label",
    "calibration_option",
    "format_agent_verdicts",
    "format_floor",
    "format_verdict_entries",
    "format_verdicts",
    "juggling_verdicts",
    "kept_initial_policy",
    "noise_floor",
    "orientation_verdicts",
    "position_verdicts",
    "row_frame",
    "verdicts_document",
]

#: The paper's in-sample noise measure (Table 1), printed beside the floors.
IN_SAMPLE_ROW = "within_subject"
#: Per frame: the predictive floor, its uncorrected leave-one-out row and the frame's null
#: (the row the gap to the floor is measured from).
FLOOR_ROWS: dict[str, tuple[str, str, str]] = {
    "body": ("predictive_floor", "within_subject_loo", "null_d2_loso"),
    "path": ("predictive_floor_path", "within_subject_path_loo", "null_d2_path_loso"),
}

ORIENTATION_CRITERION = "median over trajectories of the max error over time"
AGENT_CRITERION = "median over episodes of the max error over time"
POSITION_CRITERION = "median across shapes of the median over demos of the max error"


# -- orientation -------------------------------------------------------------------------
def calibration_label(name: str) -> str | None:
    """Printed label of a person-calibration row (None for other rows)."""
    for prefix, text in (
        ("slerp_person_timing_k", "Slerp, person's timing (K={k}), pred. timing, LOSO"),
        ("ridge_person_k", "Ridge + person summary (K={k}), path, LOSO"),
        ("mlp_person_k", "MLP + person summary (K={k}), path, LOSO"),
        ("person_k", "Person calibration (K={k}), d=2, LOSO"),
    ):
        if name.startswith(prefix):
            k, _, rest = name[len(prefix) :].partition("_")
            if rest == "loso_predicted_timing":
                return f"Person calibration (K={k}), pred. timing, LOSO"
            if rest == "path_loso":
                return f"Person calibration (K={k}), d=2, path frame, LOSO"
            return text.format(k=k)
    return None


def calibration_option(text: str) -> tuple[int, ...]:
    """``--calibration``: a comma list of distinct integers K >= 1, or ``off``."""
    if text.strip() == "off":
        return ()
    try:
        ks = tuple(int(v) for v in text.split(","))
    except ValueError:
        ks = ()
    if not ks or any(k < 1 for k in ks) or len(set(ks)) != len(ks):
        raise argparse.ArgumentTypeError(
            f"expected 'off' or a comma list of distinct integers >= 1 (e.g. 1,3,5,10); "
            f"got {text!r}"
        )
    return ks


def _calibration_pairs(ks: Sequence[int]) -> list[tuple[str, str]]:
    """Each calibration row against the null of its own frame and timing."""
    pairs = [(f"person_k{k}_loso", "null_d2_loso") for k in ks]
    pairs += [(f"person_k{k}_path_loso", "null_d2_path_loso") for k in ks]
    pairs += [(f"person_k{k}_loso_predicted_timing", "null_d2_loso_predicted_timing") for k in ks]
    pairs += [
        (f"slerp_person_timing_k{k}_predicted_timing", "slerp_loso_predicted_timing") for k in ks
    ]
    return pairs


def orientation_verdicts(
    readings: Sequence[Mapping[str, Any]],
    calibration: PersonCalibration | None,
    ks: Sequence[int],
    subjects: NDArray[Any],
    learned: Any | None = None,
    learned_calibration: Any | None = None,
) -> list[Comparison]:
    """Comparisons of the orientation benchmark, each within one frame: the
    learned-vs-analytic readings (learned rows against the best analytic row of their
    frame), each person-calibration row against the null of its frame and timing
    (``null_d2_loso``, ``null_d2_path_loso``, ``null_d2_loso_predicted_timing``; the
    calibration's timing against ``slerp_loso_predicted_timing``) and each learned row
    given the calibration summary (``learned_calibration``,
    :class:`~baselines.learned.person_rows.LearnedPersonRows`, path frame) against
    ``person_k{K}_path_loso`` and against the same learned row without the summary
    (``learned``'s ``ridge_loso``, ``mlp_loso``); people resampled."""
    out = from_readings(readings, "people", ORIENTATION_CRITERION, "rad")
    if calibration is not None:
        err = dict(calibration.errors)
        pairs = _calibration_pairs(ks)
        if learned_calibration is not None:
            err.update(learned_calibration.errors)
            if learned is not None:
                err.update(learned.errors)
            for m in ("ridge", "mlp"):
                for k in ks:
                    a = f"{m}_person_k{k}_loso"
                    pairs += [(a, b) for b in (f"person_k{k}_path_loso", f"{m}_loso")]
        for a, b in pairs:
            if a not in err or b not in err:
                continue
            ok = np.isfinite(err[a]) & np.isfinite(err[b])
            out.append(compare_errors(err[a][ok], err[b][ok], subjects[ok], a, b))
    return out


def row_frame(name: str) -> str:
    """The frame a row's residual is modelled in: ``"path"`` (path-frame rows, the
    learned rows), ``"none"`` (the slerp rows, residual predicted as 0: the same in every
    frame) or ``"body"`` (the paper's frame)."""
    if name.startswith("slerp"):
        return "none"
    if "_path" in name or name.startswith(("ridge", "mlp")):
        return "path"
    return "body"


def _out_of_sample(name: str) -> bool:
    return ("_loso" in name or "_loro" in name or name.endswith("_predicted_timing")) and not (
        name.startswith(("within_subject", "predictive_floor"))
    )


def noise_floor(criteria: Mapping[str, float]) -> dict[str, Any] | None:
    """The predictive floors per frame and every out-of-sample row's distance to the floor
    of its frame (:func:`row_frame`); None without the body-frame floor.

    ``floors[frame]``: the floor row and value, its uncorrected leave-one-out row and
    value, and the frame's null (``null_d2_loso``, ``null_d2_path_loso``) with its value.
    ``rows[name]``: ``frame``, ``floor_row`` and ``floor`` (the value it is held to; a
    frame-free slerp row to the lower floor; predicted-timing rows to the observed-timing
    floor), ``distance = value - floor`` (rad) and ``ratio = value / floor``.
    ``in_sample``: the paper's ``within_subject`` (each reach inside its own mean;
    below the floors, not one for predictors)."""
    floors: dict[str, dict[str, Any]] = {}
    for frame, (row, loo, ref) in FLOOR_ROWS.items():
        value = criteria.get(row)
        if value is None or not np.isfinite(value):
            continue
        ref_value = criteria.get(ref)
        if ref_value is not None and not np.isfinite(ref_value):
            ref_value = None
        floors[frame] = {
            "row": row,
            "value": value,
            "leave_one_out_row": loo,
            "leave_one_out": criteria.get(loo),
            "reference": ref,
            "reference_value": ref_value
            if ref_value is not None and np.isfinite(ref_value)
            else None,
        }
    if "body" not in floors:
        return None
    rows: dict[str, dict[str, Any]] = {}
    for name, value in criteria.items():
        if not _out_of_sample(name) or not np.isfinite(value):
            continue
        frame = row_frame(name)
        if frame == "none":
            held = min(floors.values(), key=lambda f: f["value"])
        else:
            held = floors.get(frame, floors["body"])
        rows[name] = {
            "frame": frame,
            "floor_row": held["row"],
            "floor": held["value"],
            "distance": value - held["value"],
            "ratio": value / held["value"],
        }
    in_sample = criteria.get(IN_SAMPLE_ROW)
    return {"in_sample": {"row": IN_SAMPLE_ROW, "value": in_sample}, "floors": floors, "rows": rows}


def format_floor(floor: Mapping[str, Any] | None) -> str:
    """The printed noise-floor block."""
    if floor is None:
        return ""
    lines = [
        "",
        "predictive floors (each reach predicted from the other replicates of its person and "
        "task, leave one out, scaled by sqrt((n - 1) / n): the error of a predictor that knew "
        "the person's mean for the task; docs/models.md):",
    ]
    for frame, f in floor["floors"].items():
        loo = f["leave_one_out"]
        loo_s = f"; uncorrected leave one out {loo:.3f}" if loo is not None else ""
        lines.append(f"  {frame} frame: {f['row']} = {f['value']:.3f} rad{loo_s}")
    ins = floor["in_sample"]
    if ins["value"] is not None:
        lines.append(
            f"  the paper's {ins['row']} = {ins['value']:.3f} rad is in sample (each reach "
            "inside the mean it is scored against): not a floor for predictors"
        )
    lines.append(
        "each out-of-sample row against the floor of its frame (distance = row - floor, rad; "
        "ratio = row / floor; slerp rows, the same in every frame, against the lower floor; "
        "predicted-timing rows held to the observed-timing floor):"
    )
    lines.append(f"  {'row':<44} {'frame':<5} {'value':>6} {'floor':>6} {'dist.':>7} {'ratio':>6}")
    for name, r in floor["rows"].items():
        value = r["floor"] + r["distance"]
        lines.append(
            f"  {name:<44} {r['frame']:<5} {value:6.3f} {r['floor']:6.3f} "
            f"{r['distance']:+7.3f} {r['ratio']:6.3f}"
        )
    return "\n".join(lines)


def format_verdicts(comparisons: Sequence[Comparison], title: str) -> str:
    """A block of verdict lines under ``title``."""
    if not comparisons:
        return ""
    width = max(len(c.name) for c in comparisons)
    c0 = comparisons[0]
    head = (
        f"\n{title}: ratio of criteria ({c0.criterion}, {c0.unit}; lower is better), "
        f"95 % bootstrap interval over {c0.group}, seed 0; power: the ratios the interval "
        f"detects 80 % of the time at this many {c0.group} (the same resampling):"
    )
    return "\n".join([head, *(c.line(width) for c in comparisons)])


def format_verdict_entries(entries: Sequence[Mapping[str, Any]], title: str) -> str:
    """:func:`format_verdicts` of the ``verdicts`` entries of a ``results.json``."""
    return format_verdicts([_entry_comparison(v) for v in entries], title)


def _entry_comparison(v: Mapping[str, Any]) -> Comparison:
    lo, hi = v["ci95"]
    det = v.get("detectable_ratios")
    return Comparison(
        v["a"], v["b"], v["ratio"], (lo, hi), v["wins"], v["n_groups"], v["group"],
        v["criterion"], v["unit"], None if det is None else (float(det[0]), float(det[1])),
    )  # fmt: skip


def verdicts_document(comparisons: Sequence[Comparison]) -> dict[str, Any]:
    """``{"intervals": {...}, "verdicts": [...]}`` for ``results.json``."""
    return {
        "intervals": intervals_document(comparisons),
        "verdicts": [c.to_dict() for c in comparisons],
    }


# -- position ----------------------------------------------------------------------------
def position_verdicts(doc: Mapping[str, Any]) -> list[Comparison]:
    """Comparisons of ``motion-bench position``: the learned readings (interval
    unchanged), then every column against ``lippi`` and against ``null`` (max error,
    median across shapes of the per-shape medians; shapes resampled)."""
    unit = doc.get("unit") or "data units"
    readings = doc["learned"].get("comparisons", [])
    out = from_readings(readings, "shapes", POSITION_CRITERION, unit)
    seen = {c.name for c in out}
    shapes = np.array(list(doc["per_shape"]))
    methods = doc["methods"]

    def values(m: str) -> NDArray[np.float64]:
        return np.array([doc["per_shape"][s]["criteria"][m]["max_error"] for s in shapes])

    for ref in ("lippi", "null"):
        if ref not in methods:
            continue
        for m in methods:
            if m == ref or f"{m} / {ref}" in seen:
                continue
            out.append(
                compare_errors(
                    values(m), values(ref), shapes, m, ref, group="shapes",
                    criterion=POSITION_CRITERION, unit=unit,
                )
            )  # fmt: skip
    return out


# -- agent -------------------------------------------------------------------------------
def agent_comparisons(
    agent: NDArray[np.float64],
    nominal: NDArray[np.float64],
    groups: NDArray[Any],
    group: str,
    unit: str,
    learned: NDArray[np.float64] | None = None,
) -> dict[str, Any]:
    """``criterion_ci``, ``nominal_criterion_ci``, ``ratio_ci``, ``verdict`` (a sentence),
    ``wins`` and the ``intervals``/``verdicts`` entries of ``motion-bench agent``: the
    agent against the zero action (and the learned regressor), same episodes,
    ``group`` (people or shapes) resampled."""
    from baselines.stats import statistic_interval

    comparisons = [compare_errors(agent, nominal, groups, "agent", "nominal", group=group,
                                  criterion=AGENT_CRITERION, unit=unit)]  # fmt: skip
    if learned is not None:
        comparisons.append(
            compare_errors(agent, learned, groups, "agent", "learned", group=group,
                           criterion=AGENT_CRITERION, unit=unit)
        )  # fmt: skip
    main = comparisons[0]
    return {
        "criterion_ci": list(statistic_interval(agent, groups)[1:]),
        "nominal_criterion_ci": list(statistic_interval(nominal, groups)[1:]),
        "ratio_ci": list(main.ci95),
        "verdict": main.sentence(),
        "wins": {"agent_lower": main.wins, "n_groups": main.n_groups, "group": group},
        **verdicts_document(comparisons),
    }


def format_agent_verdicts(entries: Mapping[str, Any]) -> str:
    """The printed lines of :func:`agent_verdicts` or :func:`juggling_verdicts` (and the
    initial-policy warning)."""
    lines = []
    if "criterion_ci" in entries:
        lo, hi = entries["criterion_ci"]
        lines.append(f"agent criterion 95% CI {lo:.6g}-{hi:.6g} (lower is better)")
    lines += [_entry_comparison(v).line().strip() for v in entries["verdicts"]]
    if entries.get("kept_initial_policy"):
        lines.append(
            "the kept checkpoint is the INITIAL policy (step 0): validation never improved on "
            "it, so this agent is its untrained starting point"
        )
    return "\n".join(lines)


def kept_initial_policy(manifest: Mapping[str, Any], which: str) -> bool:
    """Whether the evaluated checkpoint is the initial policy: ``--checkpoint best`` and
    validation never improved on the evaluation at step 0 (``best_timesteps == 0``)."""
    return which == "best" and manifest.get("best_timesteps") == 0


def agent_verdicts(
    env_id: str, agent: Any, nominal: Any, learned: Any | None = None
) -> dict[str, Any]:
    """The new entries of a reaching agent's ``results.json``: :func:`agent_comparisons`
    of the :class:`~baselines.agents.evaluate.EpisodeErrors` of the agent, the zero action
    and the learned regressor (people resampled, or shapes without people)."""
    people = "Orientation" in env_id
    return agent_comparisons(
        agent.max_errors,
        nominal.max_errors,
        agent.groups,
        "people" if people else "shapes",
        "rad" if people else "position units",
        None if learned is None else learned.max_errors,
    )


def juggling_verdicts(agent: Any, nominal: Any) -> dict[str, Any]:
    """Juggling-v0 (SIMULATED demonstrations): the drop rate per toss and the deviation of
    the agent over the zero action's, episodes (seeds) resampled; ``intervals``,
    ``verdicts``, ``ratio_ci`` (drop rate) and ``deviation_ratio_ci``."""
    from baselines.stats import Comparison, detectable_ratios, group_bootstrap_replicates

    n = int(agent.seeds.size)

    def segments(eps: Any, rows: NDArray[np.int64]) -> NDArray[np.float64]:
        per = [eps.segment_deviation[eps.segment_episode == i] for i in range(n)]
        return np.concatenate([per[i] for i in rows] or [np.empty(0)])

    def drop_ratio(rows: NDArray[np.int64]) -> float:
        a = 1.0 - agent.catches[rows].sum() / max(int(agent.tosses[rows].sum()), 1)
        b = 1.0 - nominal.catches[rows].sum() / max(int(nominal.tosses[rows].sum()), 1)
        return float(a / b) if b > 0 else float("nan")

    def deviation_ratio(rows: NDArray[np.int64]) -> float:
        a, b = segments(agent, rows), segments(nominal, rows)
        return float(np.median(a) / np.median(b)) if a.size and b.size else float("nan")

    episodes = np.arange(n)
    out: list[Comparison] = []
    for name, stat, per, what, unit in (
        ("drop rate", drop_ratio, (agent.dropped, nominal.dropped), "drops per toss", "1"),
        (
            "deviation", deviation_ratio,
            (agent.episode_deviation(), nominal.episode_deviation()),
            "median deviation from the demonstrations", "m",
        ),
    ):  # fmt: skip
        point, lo, hi, reps = group_bootstrap_replicates(stat, episodes)
        if not np.isfinite(point):
            continue
        a, b = per
        wins = int(np.sum(np.asarray(a) < np.asarray(b)))
        out.append(
            Comparison(
                f"agent {name}", f"nominal {name}", point, (lo, hi), wins, n, "episodes",
                what, unit, detectable_ratios(point, lo, hi, reps),
            )
        )  # fmt: skip
    doc = verdicts_document(out)
    by = {c.a: c for c in out}
    doc["ratio_ci"] = list(by["agent drop rate"].ci95) if "agent drop rate" in by else None
    doc["deviation_ratio_ci"] = (
        list(by["agent deviation"].ci95) if "agent deviation" in by else None
    )
    doc["verdict"] = "; ".join(c.sentence() for c in out) or None
    return doc
