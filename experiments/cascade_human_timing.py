"""The simulated jugglers' timing, measured from their trajectories, against published
human values; and the same measurement on a human recording.

**Simulated** (default). For each pattern (``--patterns``; default every registered one:
``3`` and ``3-human`` by the fitted cascade juggler, ``5``, ``4``, ``441``, ``531``,
``423``, ``51`` by the siteswap juggler) and each of ``--episodes`` TRAINING seeds
(``episode_seeds("train", n)``), one zero-action episode of ``MotionEnvs/Cascade-v0`` on
``--level`` (default ``easy``: 5 % release-speed and 4 deg release-angle scatter) with
at most ``--max-catches`` catches is played (``CascadeEnv.play``) and the true hand and
ball positions of every 5 ms period are kept. The timing is then measured from those
positions alone by :func:`motion_envs.models.juggling.timing.measure_timing` (releases
and catches detected from the ball-hand distance and the ballistic fit, throw values
from the release times; the first ``--skip-start`` s, the start from rest, and in an
episode ending in a drop the last :data:`DROP_TAIL` s, not counted), and checked against
the world's own events (the periods where a ball's holder changes): ``event_error_ms``,
the largest difference between a detected release or catch and the world's. Per pattern,
over the seeds: the mean and a 95 % t-interval of the beat, the throws per second (all,
per hand), the dwell, the dwell ratio, each throw value's flight and height, the hands'
span; against the juggler's own constants (its beat and dwell ratio; for the siteswap
juggler each value's planned flight ``h b - D_h``). Then the comparison with the
published human values (:data:`PUBLISHED`, each with its source and where it was read).

**A recording** (``--recording FILE --hands R,L --balls B1,B2,B3``): a C3D, Qualisys TSV
or CSV (``t, <marker>_x, <marker>_z``) read by
:func:`~motion_envs.models.juggling.timing.read_pattern_markers` and measured the same
way; printed beside the published values. No human juggling recording is on this
machine: the comparison with recordings is for whoever has one.

Prints a table and one JSON object; ``--out`` writes it (atomically), ``--plot`` a
figure (``--from-json`` re-reads a written JSON instead of running). ``python
experiments/cascade_human_timing.py --episodes 8``: about 1.5 min CPU.
"""

from __future__ import annotations

import argparse
import json
import math
import sys
from dataclasses import asdict, dataclass, field, replace
from typing import Any

import numpy as np
from scipy import stats

from motion_envs._io import atomic_write_text
from motion_envs.datasets.juggling import SIMULATED_LABEL, episode_seeds
from motion_envs.models.juggling.timing import (
    PatternTiming,
    PatternTrajectories,
    TimingOptions,
    measure_timing,
    read_pattern_markers,
)

#: s before a drop whose catches are not counted (the failing throws).
DROP_TAIL = 1.0
#: The patterns measured by default (every one Cascade-v0 registers today).
PATTERNS = ("3", "3-human", "5", "4", "441", "531", "423", "51")
#: Measured human values found in retrieved texts (docs/juggling_human_timing.md): each
#: with what was measured, the value, the source and the address it was read at.
PUBLISHED: tuple[dict[str, Any], ...] = (
    {
        "quantity": "dwell_ratio",
        "pattern": "3, 5 (cascades)",
        "value": 2.0 / 3.0,
        "text": "'My tests show r is usually about 2/3'",
        "source": "J. Kalvan, 'How Many Objects Can Be Juggled', 1997",
        "url": "http://fermatslibrary.com/s/how-many-objects-can-be-juggled",
    },
    {
        "quantity": "dwell_ratio",
        "pattern": "3, 5, 7, 9 (cascades)",
        "value": 2.0 / 3.0,
        "text": "'Various tests with highly skilled jugglers show that the preferred dwell "
        "ratio for a cascade with 3, 5, 7, or 9 balls is near r = 2/3' (Kalvan, quoted)",
        "source": "J. Kalvan, quoted on solipsys.co.uk 'Dwell Time'",
        "url": "https://www.solipsys.co.uk/new/DwellTime.html?TheBox",
    },
    {
        "quantity": "catches_per_second",
        "pattern": "speed juggling (a record, not a preferred tempo)",
        "value": 500.0 / 60.0,
        "text": "'Speed jugglers can achieve nearly 500 catches in a minute, a rate that "
        "allows just 120 ms per catch'",
        "source": "Physics Today, 'Juggling dynamics', DOI 10.1063/PT.3.4417",
        "url": "https://physicstoday.aip.org/quick-study/juggling-dynamics",
    },
)


@dataclass(frozen=True)
class TimingConfig:
    """What the simulated measurement runs (module docstring)."""

    patterns: tuple[str, ...] = PATTERNS
    episodes: int = 8
    level: str = "easy"
    max_catches: int = 60
    gravity: float = 9.81
    skip_start: float = 1.0
    contact_radius: float = 0.02
    split: str = "train"
    options: dict[str, Any] = field(default_factory=dict)


def simulate(
    pattern: str, seed: int, level: str, max_catches: int, gravity: float = 9.81
) -> tuple[PatternTrajectories, dict[str, Any], list[tuple[float, int, str]]]:
    """One zero-action episode: its SIMULATED trajectories, the juggler's constants and
    the world's events ``(time, ball, "release" | "catch")`` (a holder change between
    two periods, timed halfway)."""
    from motion_envs.envs.juggling import CascadeEnv

    env = CascadeEnv(level=level, pattern=pattern, max_catches=max_catches, gravity=gravity)
    t: list[float] = []
    hands: list[np.ndarray[Any, Any]] = []
    balls: list[np.ndarray[Any, Any]] = []
    holders: list[tuple[int, ...]] = []

    def keep(state: Any) -> None:
        t.append(state.time)
        hands.append(state.hand_pos.copy())
        balls.append(state.ball_pos.copy())
        holders.append(state.holder)

    catches, tosses, dropped, _ = env.play(int(seed), keep)
    events = []
    for k in range(1, len(t)):
        for i, (a, b) in enumerate(zip(holders[k - 1], holders[k], strict=True)):
            if a != b:
                when = 0.5 * (t[k - 1] + t[k])
                events.append((when, i, "release" if b < 0 else "catch"))
    c = env.controller
    nominal: dict[str, Any] = {
        "beat": float(c.beat),
        "dwell_ratio": float(c.dwell_ratio),
        "dwell": float(c.dwell_ratio * 2.0 * c.beat),
        "catches": catches,
        "tosses": tosses,
        "dropped": dropped,
    }
    plan = getattr(c, "plan", None)
    if plan is not None:  # the siteswap juggler: each value's planned flight and hold
        tm = plan.timing
        nominal["flight_by_value"] = {
            str(h): tm.flight(h) for h in sorted(set(tm.throws)) if h != 2
        }
        nominal["dwell_by_value"] = {str(h): tm.hold(h) for h in sorted(set(tm.throws)) if h != 2}
    traj = PatternTrajectories(
        t=np.array(t),
        hands=np.array(hands),
        balls=np.array(balls),
        source=f"{SIMULATED_LABEL} Cascade-v0 pattern={pattern} level={level} seed={seed}",
        simulated=True,
    )
    return traj, nominal, events


def event_error(timing: PatternTiming, events: list[tuple[float, int, str]]) -> float:
    """s: the largest distance from a detected release (catch) to the world's nearest
    release (catch) of the same ball."""
    worst = 0.0
    for f in timing.flights:
        for when, kind in ((f.release, "release"), (f.catch, "catch")):
            near = [abs(e[0] - when) for e in events if e[1] == f.ball and e[2] == kind]
            worst = max(worst, min(near) if near else math.inf)
    return worst


def _interval(x: list[float]) -> dict[str, float]:
    """Mean, sd, 95 % t-interval of the mean, min and max of the finite ``x`` (the mean
    alone, and no interval, for one value)."""
    a = np.array([v for v in x if math.isfinite(v)])
    if a.size == 0:
        return {"n": 0}
    mean = float(a.mean())
    if a.size == 1:
        return {"n": 1, "mean": mean, "min": mean, "max": mean}
    sd = float(a.std(ddof=1))
    half = float(stats.t.ppf(0.975, a.size - 1) * sd / math.sqrt(a.size))
    return {
        "n": int(a.size),
        "mean": mean,
        "sd": sd,
        "ci_low": mean - half,
        "ci_high": mean + half,
        "min": float(a.min()),
        "max": float(a.max()),
    }


def measure_pattern(pattern: str, config: TimingConfig) -> dict[str, Any]:
    """One pattern's figures over the seeds (module docstring)."""
    base = TimingOptions(
        gravity=config.gravity,
        contact_radius=config.contact_radius,
        skip_start=config.skip_start,
        **config.options,
    )
    per_seed: list[dict[str, Any]] = []
    nominal: dict[str, Any] = {}
    for seed in episode_seeds(config.split, config.episodes):
        traj, nominal, events = simulate(
            pattern, int(seed), config.level, config.max_catches, config.gravity
        )
        opts = base
        if nominal["dropped"]:  # the throws of the last second before a drop are not counted
            opts = replace(opts, skip_end=DROP_TAIL)
        try:
            timing = measure_timing(traj, opts)
        except ValueError as exc:  # a seed dropping in its first beats has no timing
            per_seed.append({"seed": int(seed), "error": str(exc), "catches": nominal["catches"]})
            continue
        row = timing.summary()
        row.update(
            seed=int(seed),
            catches=nominal["catches"],
            dropped=nominal["dropped"],
            event_error_ms=1e3 * event_error(timing, events),
        )
        per_seed.append(row)
    ok = [r for r in per_seed if "error" not in r]
    scalars = ("beat", "throws_per_second", "dwell", "dwell_ratio", "event_error_ms")
    agg: dict[str, Any] = {k: _interval([r[k] for r in ok]) for k in scalars}
    agg["throws_per_second_per_hand"] = _interval(
        [v for r in ok for v in r["throws_per_second_per_hand"]]
    )
    agg["hand_span"] = _interval([v for r in ok for v in r["hand_span"]])
    agg["release_offset"] = _interval([r["release_offset"] for r in ok])
    agg["catch_offset"] = _interval([r["catch_offset"] for r in ok])
    values = sorted({int(v) for r in ok for v in r["flight_by_value"]})
    for key in ("flight_by_value", "dwell_by_value", "height_by_value"):
        agg[key] = {str(v): _interval([r[key].get(str(v), math.nan) for r in ok]) for v in values}
    return {
        "pattern": pattern,
        "simulated": True,
        "nominal": {k: v for k, v in nominal.items() if k not in ("catches", "tosses", "dropped")},
        "measured": agg,
        "seeds": per_seed,
    }


def run(config: TimingConfig) -> dict[str, Any]:
    """Every pattern's figures and the published values (module docstring)."""
    from tqdm import tqdm

    rows = [measure_pattern(p, config) for p in tqdm(config.patterns, desc="patterns")]
    return {
        "label": SIMULATED_LABEL,
        "config": asdict(config),
        "rows": rows,
        "published": list(PUBLISHED),
        "human_recordings": "none on this machine; run --recording on one",
    }


def _finite(x: Any) -> Any:
    """``x`` with every non-finite float as None (strict JSON)."""
    if isinstance(x, dict):
        return {k: _finite(v) for k, v in x.items()}
    if isinstance(x, (list, tuple)):
        return [_finite(v) for v in x]
    if isinstance(x, (float, np.floating)):
        return float(x) if math.isfinite(x) else None
    return x


def _fmt(d: dict[str, Any], scale: float = 1.0, digits: int = 3) -> str:
    if not d.get("n"):
        return "-"
    if d["n"] == 1:
        return f"{scale * d['mean']:.{digits}f} (one seed)"
    return (
        f"{scale * d['mean']:.{digits}f} [{scale * d['ci_low']:.{digits}f}, "
        f"{scale * d['ci_high']:.{digits}f}]"
    )


def report(results: dict[str, Any]) -> str:
    """The printed table."""
    lines = [
        f"{SIMULATED_LABEL} jugglers on Cascade-v0 ({results['config']['level']}, "
        f"{results['config']['episodes']} {results['config']['split']} seeds): mean "
        "[95 % interval] over seeds, measured from the trajectories; (nominal)",
        "pattern  | beat s                 | throws/s              | dwell ratio           "
        "| flight s by value                            | max event error ms",
    ]
    for row in results["rows"]:
        m, nom = row["measured"], row["nominal"]
        flights = "; ".join(
            f"{v}: {_fmt(d)}" for v, d in m["flight_by_value"].items() if d.get("n")
        )
        lines.append(
            f"{row['pattern']:<8} | {_fmt(m['beat'])} ({nom['beat']:.3f}) | "
            f"{_fmt(m['throws_per_second'], digits=2)} | {_fmt(m['dwell_ratio'])} "
            f"({nom['dwell_ratio']:.3f}) | {flights} | "
            f"{m['event_error_ms'].get('max', math.nan):.1f}"
        )
    lines.append("published human values:")
    for p in results["published"]:
        lines.append(
            f"  {p['quantity']} {p['value']:.3f} ({p['pattern']}): {p['source']}, {p['url']}"
        )
    lines.append(f"human recordings: {results['human_recordings']}")
    return "\n".join(lines)


def measure_recording(args: argparse.Namespace) -> dict[str, Any]:
    """``--recording``: the recording's timing beside the published values."""
    traj = read_pattern_markers(
        args.recording,
        args.hands.split(","),
        args.balls.split(","),
        unit=args.unit,
        up=args.up,
        lateral=args.lateral,
    )
    opts = TimingOptions(gravity=args.gravity, contact_radius=args.contact_radius)
    return {"recording": measure_timing(traj, opts).summary(), "published": list(PUBLISHED)}


def plot(results: dict[str, Any], path: str) -> None:
    """Two panels: each pattern's measured dwell ratio (mean and 95 % interval over seeds)
    against its juggler's planned one and the published human value; each throw value's
    measured flight against the planned ``h b - D_h`` (the siteswap juggler's)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from motion_envs._io import save_figure

    rows = [r for r in results["rows"] if r["measured"]["dwell_ratio"].get("n", 0) >= 2]
    fig, (ax1, ax2) = plt.subplots(1, 2, figsize=(10, 3.8))
    for i, r in enumerate(rows):
        d = r["measured"]["dwell_ratio"]
        err = [[d["mean"] - d["ci_low"]], [d["ci_high"] - d["mean"]]]
        first = i == 0
        ax1.errorbar(i, d["mean"], err, fmt="o", color="C0", capsize=3,
                     label="measured" if first else None)  # fmt: skip
        ax1.plot(i, r["nominal"]["dwell_ratio"], "x", color="C1",
                 label="planned" if first else None)  # fmt: skip
    human = [p["value"] for p in results["published"] if p["quantity"] == "dwell_ratio"]
    if human:
        ax1.axhline(human[0], color="k", lw=0.8, ls="--", label="human, Kalvan: about 2/3")
    ax1.set_xticks(range(len(rows)), [r["pattern"] for r in rows])
    ax1.set_ylabel("dwell ratio D / 2b")
    ax1.set_xlabel("pattern")
    ax1.legend(fontsize=8)
    for r in rows:
        planned = r["nominal"].get("flight_by_value", {})
        for v, d in r["measured"]["flight_by_value"].items():
            if v in planned and d.get("n", 0) >= 2:
                ax2.plot(planned[v], d["mean"], "o")
                ax2.annotate(f"{r['pattern']}:{v}", (planned[v], d["mean"]), fontsize=7)
    lim = [0.0, 1.0]
    ax2.plot(lim, lim, color="k", lw=0.8, ls="--")
    ax2.set_xlabel("planned flight h b - D_h, s")
    ax2.set_ylabel("measured flight, s")
    fig.suptitle(f"{SIMULATED_LABEL}: Cascade-v0's jugglers, measured from their trajectories",
                 fontsize=9)  # fmt: skip
    fig.tight_layout()
    save_figure(fig, path, dpi=120)
    plt.close(fig)


def main(argv: list[str] | None = None) -> None:
    """Parse the arguments, run, print (module docstring)."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--patterns", default=",".join(PATTERNS))
    parser.add_argument("--episodes", type=int, default=8, help="TRAINING seeds per pattern")
    parser.add_argument("--level", default="easy")
    parser.add_argument("--max-catches", type=int, default=60)
    parser.add_argument("--skip-start", type=float, default=1.0)
    parser.add_argument(
        "--contact-radius",
        type=float,
        default=None,
        help="m (default 0.02 simulated, 0.08 recording)",
    )
    parser.add_argument("--gravity", type=float, default=9.81)
    parser.add_argument("--recording", default=None, help="a C3D, TSV or CSV to measure instead")
    parser.add_argument("--hands", default=None, help="right,left hand markers")
    parser.add_argument("--balls", default=None, help="ball markers, comma-separated")
    parser.add_argument("--unit", default=None)
    parser.add_argument("--up", default="z", choices=("z", "y"))
    parser.add_argument("--lateral", default="x", choices=("x", "y"))
    parser.add_argument("--out", default=None, help="write the JSON here")
    parser.add_argument("--plot", default=None, help="write the figure here (simulated runs)")
    parser.add_argument(
        "--from-json", default=None, help="plot and report a JSON written by --out (no run)"
    )
    args = parser.parse_args(argv)
    try:
        if args.recording is not None:
            if not args.hands or not args.balls:
                parser.error("--recording needs --hands R,L and --balls B1,...")
            args.contact_radius = 0.08 if args.contact_radius is None else args.contact_radius
            results = measure_recording(args)
            print(json.dumps(results["recording"], indent=1))
        else:
            if args.episodes < 2 or args.max_catches < 4:
                parser.error("--episodes must be >= 2 and --max-catches >= 4")
            config = TimingConfig(
                patterns=tuple(p for p in args.patterns.split(",") if p),
                episodes=args.episodes,
                level=args.level,
                max_catches=args.max_catches,
                gravity=args.gravity,
                skip_start=args.skip_start,
                contact_radius=0.02 if args.contact_radius is None else args.contact_radius,
            )
            if args.from_json:
                from motion_envs._io import strict_json_loads

                with open(args.from_json, encoding="utf-8") as fh:
                    results = strict_json_loads(fh.read(), args.from_json)
            else:
                results = run(config)
            print(report(results))
            if args.plot:
                plot(results, args.plot)
    except (ValueError, FileNotFoundError) as exc:
        print(f"error: {exc}", file=sys.stderr)
        raise SystemExit(2) from None
    text = json.dumps(_finite(results), default=float)
    print(text)
    if args.out:
        atomic_write_text(args.out, text + "\n")


if __name__ == "__main__":
    main()
