"""``motion-bench juggling``: the analytic juggler of Lippi et al. (section III-A).

Demonstrations are SIMULATED by default (:mod:`motion_envs.datasets.juggling_demos`: a
seeded model of a person; the paper's recordings are not public) or read from the users'
CSV (``--data PATH.csv``, :mod:`motion_envs.datasets.juggling_csv`). They are split by
demonstration (cycle): the juggler is fitted on the training cycles only (``N`` per
phase by cross-validation inside the training cycles) and scored on the held-out ones.

Reported:

* catch rate of ``--cycles`` seeded cycles in the pure-model world, unperturbed and with
  release-velocity noise (``--noise``, relative std) plus hand tracking noise
  (``--tracking``, m), each with and without the eq. 10 correction (the same seeded
  cycles in every condition);
* per phase, on the held-out demonstrations (all resampled to the same normalised-time
  grid): the median over demonstrations of the max over time of the position error
  (the papers' criterion) and of the RMSE, for Lippi's regression, a minimum-jerk movement
  and a DMP (``movement_primitives``) with the same end points and duration, next to the
  within-person variability (a training demonstration of the same person re-targeted to
  the held-out end points, median over the training demonstrations);
* per phase, the paper's validation of the linear hypothesis on the training cycles
  (Lilliefors, F-test, 95 % intervals, jackknife spread over the estimates);
* a Figure-6-style plot and an animation (GIF) of the juggler.

:func:`run` computes (a pure function of a frozen :class:`JugglingConfig`: no argparse,
no printing, no files), :func:`report` is the printed text, :func:`write` writes
``results.json``, ``results.csv``, ``juggling_fig6.png`` and ``juggling.gif`` (every file
through :mod:`motion_envs._io`, atomically); :func:`register` adds the sub-command.
"""

from __future__ import annotations

import argparse
import csv
import io
import json
import math
import sys
import time
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from baselines import options
from motion_envs._io import atomic_write, atomic_write_text, save_figure
from motion_envs.datasets.juggling_demos import (
    SIMULATED_LABEL,
    JugglingDemos,
    departure_from_line,
    generate_demonstrations,
)
from motion_envs.datasets.juggling_task import PHASES, JugglingNoise, JugglingTask
from motion_envs.models.juggling_juggler import AnalyticJuggler, minimum_jerk
from motion_envs.models.juggling_run import (
    cycle_rngs,
    fit_juggler,
    run_cycle,
    run_cycles,
    run_cycles_fast,
)
from motion_envs.models.juggling_world import BallisticWorld

__all__ = ["JugglingConfig", "main", "register", "report", "run", "write"]

FloatArray = NDArray[np.float64]

#: Targets of issue 9, checked in ``results["targets"]``.
TARGET_UNPERTURBED = 0.99
TARGET_NOISE5_CORRECTED = 0.90
TARGET_VARIABILITY_RATIO = 1.5

VIDEO_CAPTION = "analytic juggler in the MuJoCo scene (SIMULATED)"


#: Complete cycles a run needs (:func:`~motion_envs.datasets.juggling_demos.split_cycles`).
MIN_CYCLES = 8


@dataclass(frozen=True)
class JugglingConfig:
    """Everything ``motion-bench juggling`` needs (the CLI maps its flags onto this).

    ``data``: None (or ``"simulated"``) for the SIMULATED demonstrations, else the path of
    a juggling CSV. ``noise``: release-velocity noise levels (relative std), each in
    [0, 1); ``tracking``: hand tracking noise std (m). ``world``: ``"mujoco"`` or
    ``"model"``.
    """

    cycles: int = 1000
    noise: tuple[float, ...] = (0.05, 0.10)
    tracking: float = 0.0005
    seed: int = 0
    data: str | None = None
    demo_cycles: int = 50
    demo_persons: int = 1
    test_fraction: float = 0.25
    n_sines: int | str = "auto"
    n_points: int = 150
    dmp_weights: int = 10
    use_dmp: bool = True
    figure_cycles: int = 3
    world: str = "mujoco"
    mujoco_cycles: int = 100
    mujoco_noise_cycles: int = 25
    progress: bool = True
    task: JugglingTask = field(default_factory=JugglingTask)


def load_demos(config: JugglingConfig) -> JugglingDemos:
    """The SIMULATED demonstrations, or the users' CSV when ``config.data`` is a path."""
    if config.data is None or config.data == "simulated":
        return generate_demonstrations(
            n_cycles=config.demo_cycles,
            n_persons=config.demo_persons,
            seed=config.seed,
            task=config.task,
        )
    from motion_envs.models.juggling_segmentation import load_juggling_csv

    return load_juggling_csv(config.data, task=config.task)


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
        juggler.correction = corr
        noise = JugglingNoise(level, tracking)
        t0 = time.perf_counter()
        res = run_cycles_fast(juggler, config.cycles, noise, config.seed)
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
            mj = run_cycles(juggler, m, noise, config.seed, world=_scene(juggler.task))
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
    juggler.correction = True
    return rows[0], rows[1:]


def _scene(task: JugglingTask) -> Any:
    from motion_envs.envs.juggling_scene import JugglingScene

    return JugglingScene(task)


def check_config(config: JugglingConfig) -> None:
    """Raise :class:`baselines.options.ConfigError` naming the first field out of range.

    Called by :func:`run` before any computation (the CLI's checkers catch the same values
    earlier, naming the option).
    """
    if config.cycles < 1:
        raise options.ConfigError("cycles", f"must be >= 1; got {config.cycles}")
    if config.world not in ("mujoco", "model"):
        raise options.ConfigError("world", f"must be 'mujoco' or 'model'; got {config.world!r}")
    for level in config.noise:
        if not (math.isfinite(level) and 0 <= level < 1):
            raise options.ConfigError("noise", f"levels must be in [0, 1); got {level}")
    if not (math.isfinite(config.tracking) and config.tracking >= 0):
        raise options.ConfigError("tracking", f"must be finite and >= 0; got {config.tracking}")
    if config.seed < 0:
        raise options.ConfigError("seed", f"must be >= 0; got {config.seed}")
    for name in ("demo_persons", "figure_cycles", "n_points", "dmp_weights"):
        if getattr(config, name) < 1:
            raise options.ConfigError(name, f"must be >= 1; got {getattr(config, name)}")
    for name in ("mujoco_cycles", "mujoco_noise_cycles"):
        if getattr(config, name) < 0:
            raise options.ConfigError(name, f"must be >= 0; got {getattr(config, name)}")
    if config.data in (None, "simulated") and config.demo_cycles * config.demo_persons < MIN_CYCLES:
        raise options.ConfigError(
            "demo_cycles",
            f"{config.demo_cycles} cycle(s) x {config.demo_persons} person(s) of SIMULATED "
            f"demonstrations; at least {MIN_CYCLES} complete cycles are needed",
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
    world = _scene(demos.task) if config.world == "mujoco" else BallisticWorld(demos.task)
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


# -- printing, files, plots ---------------------------------------------------------------
def _clean(value: Any) -> Any:
    if isinstance(value, float):
        return value if math.isfinite(value) else None
    if isinstance(value, dict):
        return {str(k): _clean(v) for k, v in value.items() if not str(k).startswith("_")}
    if isinstance(value, (list, tuple)):
        return [_clean(v) for v in value]
    if isinstance(value, (np.floating, np.integer, np.bool_)):
        return _clean(value.item())
    return value


def report(doc: dict[str, Any]) -> str:
    """The printed catch-rate, per-phase and validation tables."""
    lines = [
        f"juggling benchmark: data {doc['data']}",
        f"world: {doc['world']}; split by demonstration: {doc['split']['n_train_cycles']} "
        f"train / {doc['split']['n_test_cycles']} test cycles; gravity "
        f"{doc['task']['gravity']} m/s^2",
        "",
        f"catch rate, unperturbed: {doc['catch_rate']:.3f}",
        f"{'release noise':>14}{'tracking (m)':>14}{'eq. 10':>8}{'catch rate':>12}",
    ]
    for r in doc["catch_rates"]:
        lines.append(
            f"{r['noise']:>14.2f}{r['tracking']:>14.4f}{'on' if r['correction'] else 'off':>8}"
            f"{r['catch_rate']:>12.3f}"
        )
    mj = [r for r in [doc.get("catch_rate_detail", {}), *doc["catch_rates"]] if "mujoco" in r]
    if mj:
        same = all(r["mujoco"]["agrees_with_pure_model"] for r in mj)
        n_mj = sum(r["mujoco"]["cycles"] for r in mj)
        lines.append(
            f"MuJoCo scene: {n_mj} of these cycles stepped in JugglingScene "
            f"({'identical outcomes' if same else 'OUTCOMES DIFFER'} from the pure model); "
            + ", ".join(f"{r['mujoco']['catch_rate']:.3f}" for r in mj)
        )
    methods = list(next(iter(doc["per_phase"].values()))["methods"])
    lines += [
        "",
        "per phase, held-out demonstrations (m): median over demos of max_t |error| (and of RMSE)",
        f"{'phase':<9}{'N':>3}" + "".join(f"{m:>22}" for m in [*methods, "within-person"]),
    ]
    for phase, v in doc["per_phase"].items():
        cells = [v["methods"][m] for m in methods] + [v["within_person"]]
        lines.append(
            f"{phase:<9}{v['n_sines']:>3}"
            + "".join(f"{c['max_error']:>12.4f} ({c['rmse']:.4f})" for c in cells)
        )
    lines += [
        "",
        "validation of the linear hypothesis (training cycles), non-exact sine coefficients:",
        "  normal: share with Lilliefors p > 0.05; F-test: share with p < 0.05; "
        "CI/|F|, jack/|F|: medians over coefficients",
        f"{'phase':<9}{'coord':>6}{'n':>4}{'normal':>8}{'F-test':>8}{'CI/|F|':>9}{'jack/|F|':>10}",
    ]
    for phase, rows in doc["validation"].items():
        for row in rows:
            if "error" in row:
                lines.append(f"{phase:<9}  {row['error']}")
                continue
            lines.append(
                f"{phase:<9}{'xz'[row['coordinate']]:>6}{row['n_coefficients']:>4}"
                f"{row['normal_frac']:8.2f}{row['ftest_frac']:8.2f}"
                f"{row['ci_rel']:9.2f}{row['jack_rel']:10.2f}"
            )
    t = doc["targets"]
    lines += ["", "targets (issue 9):"]
    lines.append(f"  unperturbed catch rate >= 0.99: {_met(t['unperturbed_catch_rate>=0.99'])}")
    lines.append(f"  5 % noise with eq. 10 >= 0.90: {_met(t['noise5_corrected_catch_rate>=0.90'])}")
    for key, text in (
        ("lippi_within_1.5x_within_person", "Lippi within 1.5x within-person variability"),
        ("lippi_ahead_of_minimum_jerk", "Lippi ahead of minimum jerk (max error)"),
    ):
        lines.append(f"  {text}: " + ", ".join(f"{p} {_met(m)}" for p, m in t[key].items()))
    if doc["simulated"]:
        lines.append(f"\nDATA ARE {SIMULATED_LABEL}")
    return "\n".join(lines)


def _met(flag: bool | None) -> str:
    return "n/a" if flag is None else ("met" if flag else "MISSED")


def results_csv(doc: dict[str, Any]) -> str:
    """``results.csv``: one row per catch-rate run and per (phase, method)."""
    buf = io.StringIO()
    w = csv.writer(buf)
    w.writerow(
        ["kind", "phase", "method", "noise", "correction", "catch_rate", "max_error", "rmse"]
    )
    w.writerow(
        ["catch_rate", "", "analytic_juggler", 0.0, True, f"{doc['catch_rate']:.6g}", "", ""]
    )
    for r in doc["catch_rates"]:
        w.writerow(
            [
                "catch_rate",
                "",
                "analytic_juggler",
                r["noise"],
                r["correction"],
                f"{r['catch_rate']:.6g}",
                "",
                "",
            ]
        )
    for phase, v in doc["per_phase"].items():
        for m, c in [*v["methods"].items(), ("within_person", v["within_person"])]:
            w.writerow(
                ["phase_error", phase, m, "", "", "", f"{c['max_error']:.6g}", f"{c['rmse']:.6g}"]
            )
    return buf.getvalue()


PHASE_COLORS = {"toss": "C3", "go_down": "C0", "catch": "C2", "return": "C1"}


def plot_figure6(doc: dict[str, Any], path: Path) -> Path:
    """Demonstrations (left) and generated cycles (right), phases coloured, ball flights."""
    from matplotlib.figure import Figure
    from matplotlib.lines import Line2D

    demos: JugglingDemos = doc["_demos"]
    fig = Figure(figsize=(11, 4.8))
    axes = fig.subplots(1, 2, sharex=True, sharey=True)
    ax = axes[0]
    shown = 0
    for seg in demos.segments():
        if (seg.recording, seg.cycle) not in doc["_test"] or seg.cycle > 200:
            continue
        ax.plot(*seg.positions.T, color=PHASE_COLORS[seg.phase], lw=0.8, alpha=0.8)
        shown += 1
    rec = demos.recordings[0]
    if rec.ball is not None and rec.phase is not None:
        flying = np.isin(rec.phase, ["go_down", "catch"])
        ax.plot(*np.where(flying[:, None], rec.ball, np.nan).T, color="0.5", lw=0.5, ls=":")
    ax.set_title(f"held-out demonstrations ({'SIMULATED' if demos.simulated else 'recorded'})")
    ax = axes[1]
    for tr in doc["_traces"]:
        for phase in PHASES:
            sel = tr.phase == phase
            ax.plot(*np.where(sel[:, None], tr.hand, np.nan).T, color=PHASE_COLORS[phase], lw=1)
        fly = np.isin(tr.phase, ["go_down", "catch"])
        ax.plot(*np.where(fly[:, None], tr.ball, np.nan).T, color="0.4", lw=0.8, ls="--")
    ax.set_title("analytic juggler (pure model), ball flights dashed")
    for a in axes:
        a.set_xlabel("x (m)")
        a.set_aspect("equal", adjustable="box")
        a.grid(alpha=0.3)
    axes[0].set_ylabel("z (m)")
    handles = [Line2D([], [], color=c, label=p) for p, c in PHASE_COLORS.items()]
    fig.legend(handles=handles, loc="lower center", ncol=4, fontsize=8)
    label = "SIMULATED demonstrations" if demos.simulated else demos.name
    fig.suptitle(f"Juggling, Lippi et al. Fig. 6 style — {label}", fontsize=10)
    fig.tight_layout(rect=(0, 0.06, 1, 1))
    return save_figure(fig, path, dpi=100)


def _save_gif(images: list[Any], path: Path, fps: int) -> Path:
    """PIL images as a looping GIF at ``fps``, written atomically (:mod:`motion_envs._io`)."""
    return atomic_write(
        path,
        lambda fh: images[0].save(
            fh,
            format="GIF",
            save_all=True,
            append_images=images[1:],
            duration=int(1000 / fps),
            loop=0,
        ),
        binary=True,
    )


def write_animation(doc: dict[str, Any], path: Path, fps: int = 25) -> Path:
    """A GIF of the first generated cycles (hand, catch circle, ball), labelled SIMULATED.

    Drawn on a matplotlib ``Figure`` with its own Agg canvas (no pyplot), one RGBA frame
    every ``1 / fps`` s of the trace.
    """
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure
    from matplotlib.patches import Circle
    from PIL import Image

    tr = doc["_traces"][0]
    stride = max(1, round(1 / (fps * doc["task"]["dt"])))
    idx = np.arange(0, len(tr.times), stride)
    fig = Figure(figsize=(4, 4))
    canvas: Any = FigureCanvasAgg(fig)  # matplotlib's canvas methods are untyped
    ax = fig.subplots()
    lo = np.minimum(tr.hand.min(0), tr.ball.min(0)) - 0.1
    hi = np.maximum(tr.hand.max(0), tr.ball.max(0)) + 0.1
    ax.set_xlim(lo[0], hi[0])
    ax.set_ylim(lo[1], hi[1])
    ax.set_aspect("equal")
    hand = Circle(tuple(tr.hand[0]), doc["task"]["catch_radius"], color="C1", alpha=0.4)
    ball = Circle(tuple(tr.ball[0]), doc["task"]["ball_radius"], color="C3")
    ax.add_patch(hand)
    ax.add_patch(ball)
    (path_line,) = ax.plot([], [], color="0.5", lw=0.8)
    title = ax.set_title("")
    ax.text(0.02, 0.02, "SIMULATED, pure model", transform=ax.transAxes, fontsize=7)
    images = []
    for i in idx:
        hand.center = tuple(tr.hand[i])
        ball.center = tuple(tr.ball[i])
        path_line.set_data(tr.hand[: i + 1, 0], tr.hand[: i + 1, 1])
        title.set_text(f"analytic juggler: {tr.phase[i]}  t = {tr.times[i]:.2f} s")
        canvas.draw()
        rgba = np.asarray(canvas.buffer_rgba()).copy()
        # opaque frames as RGB: they quantise to the GIF palette better (as PillowWriter)
        images.append(Image.fromarray(rgba[..., :3] if rgba[..., 3].min() == 255 else rgba))
    return _save_gif(images, path, fps)


class _Filming:
    """A JugglingScene that renders every ``stride``-th step (camera ``side``)."""

    def __init__(self, scene: Any, stride: int, width: int = 480, height: int = 360) -> None:
        from motion_envs.envs.rendering import new_mujoco_renderer

        self.scene, self.stride, self.task = scene, stride, scene.task
        scene.model.vis.global_.offwidth = max(scene.model.vis.global_.offwidth, width)
        scene.model.vis.global_.offheight = max(scene.model.vis.global_.offheight, height)
        self.renderer = new_mujoco_renderer(scene.model, height, width)
        self.frames: list[NDArray[np.uint8]] = []
        self._k = 0

    def _shoot(self) -> None:
        self.scene.sync()
        self.renderer.update_scene(self.scene.data, camera="side")
        self.frames.append(self.renderer.render().copy())

    def reset(self, hand_pos: Any, **kwargs: Any) -> Any:
        state = self.scene.reset(hand_pos, **kwargs)
        self._k = 0
        self._shoot()
        return state

    def step(self, hand_target: Any, release_armed: bool) -> Any:
        state = self.scene.step(hand_target, release_armed)
        self._k += 1
        if self._k % self.stride == 0:
            self._shoot()
        return state


def write_mujoco_video(doc: dict[str, Any], path: Path, cycles: int = 1, fps: int = 20) -> Path:
    """A GIF of the analytic juggler in the MuJoCo scene (``rgb_array`` frames, camera side).

    Replays the figure's first ``cycles`` cycles (same seeds) with a renderer attached.
    """
    from PIL import Image, ImageDraw

    juggler: AnalyticJuggler = doc["_juggler"]
    task = juggler.task
    film = _Filming(_scene(task), max(1, round(1 / (fps * task.dt))))
    for rngs in cycle_rngs(doc["config"]["seed"] + 1, cycles):
        run_cycle(juggler, film, JugglingNoise(), rngs, through_return=True)
    film.renderer.close()
    images = []
    for frame in film.frames:
        img = Image.fromarray(frame)
        ImageDraw.Draw(img).text(
            (8, 8), "analytic juggler in the MuJoCo scene (SIMULATED)", fill="black"
        )
        images.append(img.convert("P", palette=Image.Palette.ADAPTIVE))
    return _save_gif(images, path, fps)


def write(doc: dict[str, Any], out: str | Path, video: bool = True) -> list[Path]:
    """results.json, results.csv, juggling_fig6.png and (``video``) juggling.gif in ``out``.

    Every file is written atomically through :mod:`motion_envs._io`.
    """
    out = Path(out)
    paths = [
        atomic_write_text(out / "results.json", json.dumps(_clean(doc), indent=2) + "\n"),
        atomic_write_text(out / "results.csv", results_csv(doc)),
        plot_figure6(doc, out / "juggling_fig6.png"),
    ]
    if video:
        target = out / "juggling.gif"
        if doc["config"]["world"] == "mujoco":
            try:
                paths.append(write_mujoco_video(doc, target))
                return paths
            except Exception as exc:  # no OpenGL context: draw the same cycles with matplotlib
                print(
                    f"motion-bench juggling: MuJoCo rendering unavailable ({exc}); "
                    "the GIF is drawn with matplotlib",
                    file=sys.stderr,
                )
        paths.append(write_animation(doc, target))
    return paths


def main(args: argparse.Namespace) -> int:
    """``motion-bench juggling`` with parsed arguments: run, print, write."""
    config = JugglingConfig(
        cycles=args.cycles,
        noise=args.noise,
        tracking=args.tracking,
        seed=args.seed,
        data=args.data,
        progress=not args.no_progress,
        use_dmp=not args.no_dmp,
        world=args.world,
        demo_cycles=args.demo_cycles,
        demo_persons=args.demo_persons,
        mujoco_cycles=args.mujoco_cycles,
        mujoco_noise_cycles=args.mujoco_cycles // 4,
        task=args.gravity,
    )
    t0 = time.perf_counter()
    doc = run(config)
    doc["timing"]["total_s"] = time.perf_counter() - t0
    print(report(doc))
    if args.out:
        paths = write(doc, args.out, video=not args.no_video)
        print("wrote " + ", ".join(str(p) for p in paths))
    print(f"total {doc['timing']['total_s']:.1f} s")
    return 0


def noise_levels(text: str) -> tuple[float, ...]:
    """``--noise``: a comma list of finite numbers in [0, 1) (relative std)."""
    what = f"a comma list of numbers in [0, 1) (e.g. 0.05,0.1); got {text!r}"
    try:
        levels = tuple(float(v) for v in text.split(",") if v.strip())
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected {what}") from None
    if not levels or not all(math.isfinite(v) and 0 <= v < 1 for v in levels):
        raise argparse.ArgumentTypeError(f"expected {what}")
    return levels


def gravity_task(text: str) -> JugglingTask:
    """``--gravity``: a finite number > 0 (m/s^2), as the task it defines."""
    value = options.non_negative_float(text)
    if value <= 0:
        raise argparse.ArgumentTypeError(f"expected a finite number > 0; got {text!r}")
    try:
        return JugglingTask(gravity=value)
    except ValueError as exc:
        raise argparse.ArgumentTypeError(str(exc)) from None


def juggling_data(text: str) -> str:
    """``--data``: ``simulated`` or an existing, readable juggling CSV with ``t,x,z``.

    Only the header line is read here (the rows are checked when the run loads them).
    """
    if text == "simulated":
        return text
    if (recording := options.mocap_data(text, "juggling")) is not None:  # FILE.c3d?opt=...
        return recording
    path = options.input_file(text)
    try:
        with path.open(encoding="utf-8", newline="") as fh:
            header = next(csv.reader([fh.readline()]), [])
    except UnicodeDecodeError:
        raise argparse.ArgumentTypeError(f"{text} is not a UTF-8 text CSV") from None
    missing = [c for c in ("t", "x", "z") if c not in [h.strip() for h in header]]
    if missing:
        raise argparse.ArgumentTypeError(
            f"{text}: line 1: missing column(s) {missing}; expected header "
            "t,x,z[,ball_x,ball_z][,phase][,recording]"
        )
    return str(path)


DESCRIPTION = """\
The analytic juggler of Lippi, Avizzano & Ruffaldi (section III-A). Demonstrations are
SIMULATED by default (a seeded model of a person; the paper's recordings are not public)
or read from a juggling CSV (--data). They are split by demonstration (cycle): the
juggler is fitted on the training cycles only (N per phase by cross-validation inside
them) and scored on the held-out ones.

Reported: the catch rate of --cycles seeded cycles, unperturbed and with release noise
(--noise) plus tracking noise (--tracking), each with and without the eq. 10
correction; per phase, on the held-out demonstrations, the median over demonstrations of
the max over time of the position error (and of the RMSE) for Lippi's regression,
minimum jerk and a DMP, next to the within-person variability; the paper's validation of
the linear hypothesis; a Figure-6-style plot and a GIF of the juggler (with --out)."""


def register(subparsers: argparse._SubParsersAction[options.Parser]) -> None:
    """Add the ``juggling`` sub-command."""
    p = options.add_subcommand(
        subparsers,
        "juggling",
        help="the analytic juggler (Lippi et al. III-A): catch rates, per-phase errors vs "
        "minimum jerk and DMP, validation statistics (SIMULATED demonstrations by default)",
        description=DESCRIPTION,
    )
    p.add_argument(
        "--cycles", type=options.positive_int, default=1000, help="seeded juggling cycles per run"
    )
    p.add_argument(
        "--noise",
        type=noise_levels,
        default="0.05,0.10",
        help="release-velocity noise levels (relative std), comma-separated",
    )
    p.add_argument(
        "--tracking", type=options.non_negative_float, default=0.0005, help="tracking noise std (m)"
    )
    p.add_argument(
        "--seed",
        type=options.non_negative_int,
        default=0,
        help="seed of data, split and cycles (default: 0)",
    )
    p.add_argument(
        "--data",
        type=juggling_data,
        default=None,
        help="a juggling CSV, or 'simulated' (default: SIMULATED demonstrations)",
    )
    p.add_argument(
        "--demo-cycles",
        type=options.positive_int,
        default=50,
        help="SIMULATED cycles per person (examples)",
    )
    p.add_argument("--demo-persons", type=options.positive_int, default=1, help="SIMULATED persons")
    p.add_argument(
        "--gravity",
        type=gravity_task,
        default="1.0",
        help="m/s^2 (9.81: real gravity)",
    )
    p.add_argument(
        "--out",
        type=options.output_folder,
        default=None,
        help="folder for results.json/.csv, plot, GIF (nothing written without it)",
    )
    p.add_argument(
        "--world",
        choices=("mujoco", "model"),
        default="mujoco",
        help="mujoco: the figure, the video and the first --mujoco-cycles cycles of each run "
        "in the MuJoCo scene (checked equal to the pure model, which runs all cycles); "
        "model: pure model only (fast)",
    )
    p.add_argument(
        "--mujoco-cycles",
        type=options.non_negative_int,
        default=100,
        help="unperturbed cycles stepped in MuJoCo (a quarter of it per perturbed run)",
    )
    p.add_argument("--no-dmp", action="store_true", help="skip the DMP competitor")
    p.add_argument("--no-video", action="store_true", help="skip the GIF")
    p.add_argument("--no-progress", action="store_true", help="no progress bars")
    p.set_defaults(func=main)
