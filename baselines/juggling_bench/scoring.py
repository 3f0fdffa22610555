"""The scores of ``motion-bench juggling``: per-phase errors of every method on the
held-out demonstrations, the paper's validation of the linear hypothesis, and the catch
rates of seeded cycles (pure model, and the MuJoCo scene where asked)."""

from __future__ import annotations

import sys
import time
from typing import Any

import numpy as np

from baselines.juggling_bench.config import JugglingConfig
from motion_envs._typing import FloatArray
from motion_envs.datasets.juggling import (
    PHASES,
    JugglingDemos,
    JugglingNoise,
    JugglingTask,
    departure_from_line,
)
from motion_envs.geometry.minimum_jerk import minimum_jerk
from motion_envs.models.juggling import AnalyticJuggler, run_cycles, run_cycles_fast


def _criteria(truth: FloatArray, pred: FloatArray) -> tuple[FloatArray, FloatArray]:
    """Per demonstration: max over time of |error| and RMSE; arrays ``(m, K, 2)``."""
    err = np.linalg.norm(truth - pred, axis=-1)
    return err.max(axis=-1), np.sqrt(np.mean(err**2, axis=-1))


def _retarget(y: FloatArray, start: FloatArray, end: FloatArray) -> FloatArray:
    """Keep ``y``'s residual from its line, replace the line by ``start -> end``."""
    tau = np.linspace(0.0, 1.0, y.shape[0])[:, None]
    out: FloatArray = departure_from_line(y) + (start + tau * (end - start))
    return out


def phase_errors(
    juggler: AnalyticJuggler,
    demos: JugglingDemos,
    train: set[tuple[int, int]],
    test: set[tuple[int, int]],
    n_points: int,
    use_dmp: bool,
    dmp_weights: int,
) -> dict[str, Any]:
    """Per phase: criteria of every method on the held-out demonstrations (medians)."""
    from baselines.peers import DMPPeer, peers_available

    have_dmp = use_dmp and peers_available()
    out: dict[str, Any] = {}
    segs = demos.segments(toss_to_top=True)
    persons = [r.person for r in demos.recordings]
    tau = np.linspace(0.0, 1.0, n_points)
    for phase in PHASES:
        tr = [s for s in segs if s.phase == phase and (s.recording, s.cycle) in train]
        te = [s for s in segs if s.phase == phase and (s.recording, s.cycle) in test]
        y_tr = np.stack([s.resampled(n_points) for s in tr])
        y_te = np.stack([s.resampled(n_points) for s in te])
        starts, ends = y_te[:, 0], y_te[:, -1]
        model = juggler.phases_[phase].model
        q = np.column_stack([starts, ends])
        p = model.predict_coefficients(q, starts, ends)
        from motion_envs.geometry import sine_series as ss

        preds = {"lippi": ss.evaluate(p, tau), "minimum_jerk": minimum_jerk(starts, ends, tau)}
        if have_dmp:
            dmp = DMPPeer(n_weights_per_dim=dmp_weights).fit(y_tr)
            preds["dmp"] = np.stack([dmp.predict(a, b) for a, b in zip(starts, ends, strict=True)])
        # within-person variability: other demonstrations of the same person, re-targeted
        wp_max, wp_rmse = [], []
        for i, s in enumerate(te):
            same = [k for k, r in enumerate(tr) if persons[r.recording] == persons[s.recording]]
            if not same:
                continue
            ret = np.stack([_retarget(y_tr[k], starts[i], ends[i]) for k in same])
            m, r = _criteria(y_te[i][None], ret)
            wp_max.append(np.median(m))
            wp_rmse.append(np.median(r))
        methods = {}
        for name, pred in preds.items():
            m, r = _criteria(y_te, pred)
            methods[name] = {"max_error": float(np.median(m)), "rmse": float(np.median(r))}
        within = {
            "max_error": float(np.median(wp_max)) if wp_max else float("nan"),
            "rmse": float(np.median(wp_rmse)) if wp_rmse else float("nan"),
        }
        out[phase] = {
            "n_train": len(tr),
            "n_test": len(te),
            "n_sines": int(model.n_sines),
            "duration_range_s": list(juggler.phases_[phase].duration_range),
            "samples_range": [
                int(min(len(s.times) for s in tr + te)),
                int(max(len(s.times) for s in tr + te)),
            ],
            "methods": methods,
            "within_person": within,
            "lippi_over_within": methods["lippi"]["max_error"] / within["max_error"]
            if wp_max
            else float("nan"),
            "_truth": y_te,
            "_pred": preds,
        }
    return out


def validation(juggler: AnalyticJuggler) -> dict[str, list[dict[str, float | int]]]:
    """The paper's checks of the linear hypothesis, per phase, on the training cycles."""
    out = {}
    for phase, fit in juggler.phases_.items():
        try:
            out[phase] = fit.model.validate().summary()
        except ValueError as exc:  # too few examples for the tests
            out[phase] = [{"error": str(exc)}]  # type: ignore[dict-item]
    return out


def catch_rates(
    juggler: AnalyticJuggler, config: JugglingConfig
) -> tuple[dict[str, Any], list[dict[str, Any]]]:
    """Unperturbed catch rate and the perturbed runs (same seeded cycles in each)."""
    from tqdm import tqdm

    runs = [(0.0, 0.0, True)] + [
        (level, config.tracking, corr) for level in config.noise for corr in (False, True)
    ]
    rows = []
    for level, tracking, corr in tqdm(
        runs, desc="catch-rate runs", file=sys.stderr, disable=not config.progress
    ):
        variant = juggler.variant(correction=corr)  # the fitted model is shared, not changed
        noise = JugglingNoise(level, tracking)
        t0 = time.perf_counter()
        res = run_cycles_fast(variant, config.cycles, noise, config.seed)
        row = {
            "noise": level,
            "tracking": tracking,
            "correction": corr,
            "catch_rate": float(np.mean([r.caught for r in res])),
            "dropped": int(sum(r.dropped for r in res)),
            "no_release": int(sum(not r.released for r in res)),
            "mean_corrections": float(np.mean([r.corrections for r in res])),
            "seconds": time.perf_counter() - t0,
        }
        if config.world == "mujoco":
            m = min(
                config.cycles, config.mujoco_cycles if level == 0 else config.mujoco_noise_cycles
            )
            t0 = time.perf_counter()
            mj = run_cycles(variant, m, noise, config.seed, world=juggling_scene(juggler.task))
            row["mujoco"] = {
                "cycles": m,
                "catch_rate": float(np.mean([r.caught for r in mj])) if m else None,
                "agrees_with_pure_model": all(
                    (a.caught, a.dropped, a.steps, a.corrections)
                    == (b.caught, b.dropped, b.steps, b.corrections)
                    for a, b in zip(mj, res, strict=False)
                ),
                "seconds": time.perf_counter() - t0,
            }
        rows.append(row)
    return rows[0], rows[1:]


def juggling_scene(task: JugglingTask) -> Any:
    from motion_envs.envs.juggling import JugglingScene

    return JugglingScene(task)
