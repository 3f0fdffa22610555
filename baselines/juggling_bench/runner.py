"""The pure :func:`run` of ``motion-bench juggling``: load the demonstrations, fit on the
training cycles, score on the held-out ones, run the catch-rate cycles.

(Named ``runner`` so that the package attribute ``run`` stays the function.)
"""

from __future__ import annotations

import time
from dataclasses import asdict
from typing import Any

from baselines.juggling_bench.config import (
    TARGET_NOISE5_CORRECTED,
    TARGET_UNPERTURBED,
    TARGET_VARIABILITY_RATIO,
    JugglingConfig,
    check_config,
)
from baselines.juggling_bench.scoring import catch_rates, juggling_scene, phase_errors, validation
from motion_envs.datasets.juggling import JugglingDemos, JugglingNoise
from motion_envs.models.juggling import (
    BallisticWorld,
    cycle_rngs,
    fit_juggler,
    load_demonstrations,
    run_cycle,
)


def load_demos(config: JugglingConfig) -> JugglingDemos:
    """The SIMULATED demonstrations, or the users' CSV when ``config.data`` is a path."""
    return load_demonstrations(
        config.data, config.task, config.seed, config.demo_cycles, config.demo_persons
    )


def run(config: JugglingConfig) -> dict[str, Any]:
    """Fit on the training cycles, score on the held-out ones, run the catch-rate cycles.

    Returns the results document (``results.json`` minus keys starting with ``_``, which
    hold arrays for the plots).
    """
    check_config(config)
    timing: dict[str, float] = {}
    t0 = time.perf_counter()
    demos = load_demos(config)
    timing["demonstrations_s"] = time.perf_counter() - t0
    t0 = time.perf_counter()
    juggler, train, test = fit_juggler(
        demos, config.seed, config.test_fraction, n_sines=config.n_sines
    )
    timing["fit_s"] = time.perf_counter() - t0
    t0 = time.perf_counter()
    per_phase = phase_errors(
        juggler, demos, train, test, config.n_points, config.use_dmp, config.dmp_weights
    )
    timing["phase_errors_s"] = time.perf_counter() - t0
    t0 = time.perf_counter()
    checks = validation(juggler)
    timing["validation_s"] = time.perf_counter() - t0
    t0 = time.perf_counter()
    detail, rates = catch_rates(juggler, config)
    rate = detail["catch_rate"]
    timing["catch_rates_s"] = time.perf_counter() - t0
    world = juggling_scene(demos.task) if config.world == "mujoco" else BallisticWorld(demos.task)
    traces = [
        run_cycle(juggler, world, JugglingNoise(), r, True, True)
        for r in cycle_rngs(config.seed + 1, config.figure_cycles)
    ]
    five = next((r for r in rates if abs(r["noise"] - 0.05) < 1e-12 and r["correction"]), None)
    targets = {
        "unperturbed_catch_rate>=0.99": rate >= TARGET_UNPERTURBED,
        "noise5_corrected_catch_rate>=0.90": None
        if five is None
        else five["catch_rate"] >= TARGET_NOISE5_CORRECTED,
        "lippi_within_1.5x_within_person": {
            p: bool(v["lippi_over_within"] <= TARGET_VARIABILITY_RATIO)
            for p, v in per_phase.items()
        },
        "lippi_ahead_of_minimum_jerk": {
            p: bool(v["methods"]["lippi"]["max_error"] < v["methods"]["minimum_jerk"]["max_error"])
            for p, v in per_phase.items()
        },
    }
    return {
        "benchmark": "juggling (Lippi, Avizzano & Ruffaldi 2011, section III-A)",
        "data": demos.label(),
        "simulated": demos.simulated,
        "world": "MuJoCo scene (JugglingScene) and the equal vectorised pure model"
        if config.world == "mujoco"
        else "pure model (BallisticWorld)",
        "task": asdict(demos.task),
        "config": {k: v for k, v in asdict(config).items() if k not in ("task", "progress")},
        "split": {
            "by": "demonstration (cycle)",
            "n_train_cycles": len(train),
            "n_test_cycles": len(test),
            "seed": config.seed,
        },
        "catch_rate": rate,
        "catch_rate_detail": detail,
        "catch_rates": rates,
        "per_phase": per_phase,
        "per_phase_notes": {
            "grid": f"every example resampled to {config.n_points} points of tau = t / T",
            "toss": "examples run from the toss start to the hand's turning point (the "
            "release lies inside; the eq. 9 plan ends there)",
            "criteria": "median over held-out demonstrations of max_t |error| and of RMSE (m)",
            "within_person": "median over the person's training demonstrations re-targeted "
            "to the held-out end points",
        },
        "validation": checks,
        "targets": targets,
        "timing": timing,
        "_demos": demos,
        "_test": test,
        "_traces": traces,
        "_juggler": juggler,
    }
