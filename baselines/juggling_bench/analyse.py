"""``motion-bench juggling --analyse FILE``: ball flights and pattern timing of a recording.

:func:`load_ball_markers` reads the ball markers (a juggling CSV's ``ball_x, ball_z``; a
C3D, BVH or Qualisys TSV through the import's readers, with the import's options after
``?``: ``ball=NAME[,NAME...]`` or ``balls=unlabelled``, ``up``, ``unit``, ``lateral``);
:func:`run_analysis` (a pure function of :class:`AnalyseConfig`) detects the flights and
the pattern with :func:`motion_envs.models.juggling.detect_flights` and
:func:`~motion_envs.models.juggling.pattern_summary`; :func:`report_analysis` is the
printed text; :func:`write_analysis` writes ``results.json``, ``flights.csv`` and
``flights.png``.
"""

from __future__ import annotations

import dataclasses
import json
import math
import os
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd

from baselines.juggling_bench.text import clean_json
from motion_envs._io import atomic_write_text, save_figure
from motion_envs._typing import FloatArray
from motion_envs.datasets.juggling import read_juggling_csv
from motion_envs.datasets.mocap import YUP_TO_ZUP, is_mocap_source, parse_source, read_recording
from motion_envs.models.juggling import (
    Flight,
    FlightAnalysis,
    FlightOptions,
    ThrowEvent,
    detect_flights,
    pattern_summary,
)

__all__ = [
    "AnalyseConfig",
    "BallMarkers",
    "load_ball_markers",
    "recording_warnings",
    "report_analysis",
    "run_analysis",
    "write_analysis",
]

#: Gravity the fitted one is compared with (m/s^2).
STANDARD_GRAVITY = 9.81


@dataclass(frozen=True)
class BallMarkers:
    """Ball marker trajectories as read: per recording, times ``(F,)`` and positions
    ``(F, U, D)`` (vertical last, NaN missing; D = 2 for a juggling CSV: lateral,
    vertical), the index of the lateral coordinate when the file or ``lateral=`` says
    it (None: the across-body axis is found from the data), and what was read."""

    source: str
    recordings: tuple[tuple[str, FloatArray, FloatArray], ...]
    lateral: int | None
    description: str


@dataclass(frozen=True)
class AnalyseConfig:
    """``source``: the file (``FILE?option=value&...`` for a motion capture file);
    ``balls``: the number of balls of the pattern (None: Shannon's theorem's count,
    rounded); ``options``: the flight detection's."""

    source: str
    balls: int | None = None
    options: FlightOptions = field(default_factory=FlightOptions)


def load_ball_markers(source: str | os.PathLike[str]) -> BallMarkers:
    """The ball markers of ``source`` (module docstring).

    Raises ``FileNotFoundError`` for a missing file and ``ValueError`` naming the file
    for a file that cannot be read or names no ball.
    """
    text = os.fspath(source)
    if is_mocap_source(text):
        path, opts = parse_source(text)
        if opts.ball is None and opts.balls != "unlabelled":
            raise ValueError(
                f"{path}: give the ball markers (?ball=NAME[,NAME...]) or ?balls=unlabelled"
            )
        rec = read_recording(path, opts.unit)
        if rec.fmt == "bvh" and rec.scale is None:
            raise ValueError(f"{path}: BVH lengths carry no unit; add unit=m|cm|mm|in after ?")
        if opts.balls == "unlabelled":
            cols = [j for j, name in enumerate(rec.labels) if not name]
            if not cols:
                raise ValueError(f"{path}: balls=unlabelled, but the file has no unlabelled marker")
            what = f"{len(cols)} unlabelled trajectories"
        else:
            kind = "joint" if rec.fmt == "bvh" else "marker"
            names = [n.strip() for n in str(opts.ball).split(",") if n.strip()]
            cols = [rec.index(n, kind) for n in names]
            what = f"{kind}(s) {', '.join(names)}"
        pts = rec.points[:, cols]
        if opts.up == "y":
            pts = pts @ YUP_TO_ZUP.T
        query = text.partition("?")[2]
        given = any(item.partition("=")[0] == "lateral" for item in query.split("&"))
        lateral = (0 if opts.lateral == "x" else 1) if given else None
        desc = f"{path.name}: {rec.n_frames} frames at {rec.rate:g} Hz, {what}"
        return BallMarkers(str(path), ((path.stem, rec.t, pts),), lateral, desc)
    demos = read_juggling_csv(text)
    recs = []
    for r in demos.recordings:
        if r.ball is None:
            raise ValueError(f"{text}: no ball columns (ball_x, ball_z) to analyse")
        recs.append((r.name, r.t, r.ball[:, None, :]))
    n = sum(r[1].size for r in recs)
    desc = f"{Path(text).name}: {len(recs)} recording(s), {n} samples, ball_x and ball_z"
    return BallMarkers(text, tuple(recs), 0, desc)


def run_analysis(config: AnalyseConfig) -> dict[str, Any]:
    """Flights and pattern of ``config.source``: the results document (no files, no
    printing). Keys starting with ``_`` hold the arrays of the plot."""
    markers = load_ball_markers(config.source)
    analyses: list[FlightAnalysis] = []
    for name, t, pts in markers.recordings:
        analyses.append(detect_flights(t, pts, config.options, recording=name))
    flights = tuple(f for a in analyses for f in a.flights)
    counts: dict[str, int] = {}
    for a in analyses:
        for k, v in a.counts.items():
            counts[k] = counts.get(k, 0) + v
    gravity = [f.gravity for f in flights]
    median = float(np.median(gravity)) if gravity else math.nan
    pattern = pattern_summary(flights, markers.lateral, config.balls)
    noise = float(np.median([a.noise for a in analyses]))
    return {
        "source": markers.source,
        "read": markers.description,
        "noise_m": noise,
        "n_flights": len(flights),
        "gravity_median": median,
        "gravity_iqr": [float(q) for q in np.quantile(gravity, [0.25, 0.75])]
        if gravity
        else [math.nan, math.nan],
        "gravity_error": median / STANDARD_GRAVITY - 1.0,
        "counts": counts,
        "pattern": pattern.as_dict(),
        "warnings": [*recording_warnings(flights, noise, median), *pattern.warnings],
        "throws": [dataclasses.asdict(e) for e in pattern.events],
        "flights": [_row(f, pattern.axis) for f in flights],
        "options": {k: getattr(config.options, k) for k in config.options.__dataclass_fields__},
        "_markers": markers,
        "_flights": flights,
        "_pattern": pattern,
    }


#: A warning when the median fitted gravity is further than this from 9.81 m/s^2.
GRAVITY_WARNING = 0.03
#: ... when the flights' median residual rms exceeds this many times the noise.
RESIDUAL_WARNING = 3.0
#: ... when the interquartile range of the flights' fitted gravity is wider than this
#: fraction of 9.81 m/s^2.
SPREAD_WARNING = 0.1
#: ... when fewer than this share of the flights have their release seen.
SEEN_WARNING = 0.25


def recording_warnings(flights: tuple[Flight, ...], noise: float, gravity: float) -> list[str]:
    """What in the flights says the recording does not fit the analysis' assumptions:
    gravity off 9.81 by more than :data:`GRAVITY_WARNING` (units, up axis, drag, a
    camera calibration), flights off their parabolas by more than
    :data:`RESIDUAL_WARNING` times the noise or their fitted gravity spread over an
    interquartile range wider than :data:`SPREAD_WARNING` of 9.81 (a marker off the
    ball's centre on a spinning ball: the flights are cut into pieces, each fitted
    with a different gravity),
    releases seen on fewer than :data:`SEEN_WARNING` of the flights (balls hidden in
    the hands: the pattern rests on few events)."""
    out: list[str] = []
    if not flights:
        return out
    if abs(gravity / STANDARD_GRAVITY - 1.0) > GRAVITY_WARNING:
        out.append(
            f"median gravity {gravity:.2f} m/s^2 is more than {GRAVITY_WARNING:.0%} from "
            f"{STANDARD_GRAVITY}: check the unit, the up axis and the camera calibration"
        )
    rms = float(np.median([f.residual_rms for f in flights]))
    if rms > RESIDUAL_WARNING * noise:
        out.append(
            f"the flights sit {rms * 1e3:.1f} mm (rms) off their parabolas, "
            f"{rms / noise:.1f} x the noise: markers off the balls' centres or spinning "
            "balls; flights may be cut and events missed"
        )
    q1, q3 = (float(q) for q in np.quantile([f.gravity for f in flights], [0.25, 0.75]))
    if q3 - q1 > SPREAD_WARNING * STANDARD_GRAVITY:
        out.append(
            f"the flights' fitted gravity spreads from {q1:.2f} to {q3:.2f} m/s^2 (IQR): "
            "markers off the balls' centres (spinning balls) cut the flights into pieces"
        )
    seen = sum(f.start_seen for f in flights) / len(flights)
    if seen < SEEN_WARNING:
        out.append(
            f"releases seen on only {seen:.0%} of the flights (the ball not seen in the "
            "hand before them): the pattern rests on few events"
        )
    return out


def _row(f: Flight, axis: tuple[float, ...]) -> dict[str, Any]:
    """The flight's table row, release and catch along the across-body ``axis``."""
    row: dict[str, Any] = dict(f.row(0))
    ends = f.position(np.array([f.start, f.end]))[:, :-1] @ np.array(axis)
    row["release_lateral"], row["catch_lateral"] = float(ends[0]), float(ends[1])
    return row


def _num(value: Any, fmt: str) -> str:
    if value is None or (isinstance(value, float) and not math.isfinite(value)):
        return "n/a"
    return format(value, fmt)


def report_analysis(doc: dict[str, Any]) -> str:
    """The printed summary."""
    p = doc["pattern"]
    c = doc["counts"]
    iqr = doc["gravity_iqr"]
    lines = [
        f"ball flights of {doc['read']}",
        f"noise {doc['noise_m'] * 1e3:.2f} mm; {c['fragments']} fragments "
        f"({c['fragments shorter than a window']} shorter than a window), "
        f"{c['pieces']} ballistic pieces ({c['pieces joined']} joined), "
        f"rejected: {c['fragments pulled down']} fragments pulled down faster than gravity "
        f"(not balls), {c['pieces not ballistic']} pieces not ballistic, "
        f"{c['flights too short']} flights too short, "
        f"{c['flights not ballistic']} flights not ballistic",
        f"{doc['n_flights']} flights; gravity median {_num(doc['gravity_median'], '.3f')} "
        f"m/s^2 (IQR {_num(iqr[0], '.3f')} to {_num(iqr[1], '.3f')}; "
        f"{_num(100 * doc['gravity_error'], '+.2f')} % from {STANDARD_GRAVITY})",
        f"pattern: {p['throws']} throws, {p['catches']} catches seen (the ball seen in a "
        f"hand before / after the flight); {p['hands']} hand(s) apart along "
        f"({', '.join(f'{a:+.2f}' for a in p['axis'])}) of the horizontal axes"
        + ("" if p["regular"] else "; not on a regular beat"),
        f"throw period {_num(p['throw_period'], '.3f')} s, hand period "
        f"{_num(p['hand_period'], '.3f')} s, alternation {_num(p['alternation'], '.2f')}; "
        f"apex {_num(p['apex_above_release'], '.3f')} m above the release (median)",
        f"flight F {_num(p['flight'], '.3f')} s (median; mean over the siteswap "
        f"{_num(p['flight_mean'], '.3f')}), dwell D {_num(p['dwell'], '.3f')} s, "
        f"vacant V {_num(p['vacant'], '.3f')} s, dwell ratio {_num(p['dwell_ratio'], '.3f')}",
        f"siteswap {p['siteswap'] or 'n/a'} (throw values agree "
        f"{_num(100 * p['siteswap_agreement'], '.0f')} %); balls: siteswap "
        f"{p['balls_siteswap'] if p['balls_siteswap'] is not None else 'n/a'}, Shannon "
        f"(F + D) / (V + D) = N / H {_num(p['balls_theorem'], '.2f')}, concurrent "
        f"{_num(p['balls_concurrent'], '.1f')}; pattern: "
        f"{p['balls'] if p['balls'] is not None else 'n/a'} (flight time for that N "
        f"{_num(p['flight_theorem'], '.3f')} s vs measured {_num(p['flight_mean'], '.3f')} s)",
        *(f"warning: {w}" for w in doc["warnings"]),
    ]
    if doc["n_flights"] == 0:
        low, high = doc["options"]["gravity_range"]
        lines.append(
            f"no flight found: a flight is ballistic for at least "
            f"{doc['options']['min_duration']:g} s with a downward acceleration of {low:g} "
            f"to {high:g} m/s^2 (are the lengths in metres, the up axis right?)"
        )
    return "\n".join(lines)


def plot_flights(doc: dict[str, Any], path: Path, span: float = 4.0) -> Path:
    """Heights over time (``span`` s of the first recording from its first throw: every
    marker sample, the fitted parabolas over each flight), the histogram of fitted g,
    and below the ladder diagram of the same span (:func:`plot_ladder`)."""
    from matplotlib.figure import Figure

    markers: BallMarkers = doc["_markers"]
    name, t, pts = markers.recordings[0]
    fig = Figure(figsize=(11, 6.6))
    grid = fig.add_gridspec(2, 2, width_ratios=[2.6, 1], height_ratios=[1.6, 1])
    ax, hx = fig.add_subplot(grid[0, 0]), fig.add_subplot(grid[0, 1])
    mine = [e for e in doc["_pattern"].events if e.recording == name]
    t0 = max(float(t[0]), mine[0].time - 0.2) if mine else float(t[0])
    sel = t <= t0 + span
    z = pts[sel, :, -1]
    tt = np.broadcast_to(t[sel, None], z.shape)
    ax.plot(tt.ravel(), z.ravel(), ".", ms=1.2, color="0.6", label="marker samples")
    first = True
    for f in doc["_flights"]:
        if f.recording != name or f.start > t0 + span:
            continue
        ts = np.linspace(f.start, f.end, 60)
        ax.plot(
            ts, f.position(ts)[:, -1], color="C3", lw=1.2, label="fitted flight" if first else None
        )
        ax.plot(
            [f.start, f.end], f.position(np.array([f.start, f.end]))[:, -1], "|", color="k", ms=6
        )
        first = False
    ax.set_xlim(t0, t0 + span)
    ax.set_xlabel("time (s)")
    ax.set_ylabel("height (m)")
    ax.set_title(f"{name}: ball heights, fitted parabolas (| release and catch)", fontsize=9)
    ax.grid(alpha=0.3)
    ax.legend(loc="upper right", fontsize=8, markerscale=4)
    g = np.array([r["gravity"] for r in doc["flights"]])
    if g.size:
        hx.hist(g, bins=min(30, max(5, g.size // 4)), color="C0", alpha=0.8)
        hx.axvline(
            doc["gravity_median"], color="C3", lw=1.5, label=f"median {doc['gravity_median']:.3f}"
        )
    hx.axvline(STANDARD_GRAVITY, color="k", ls="--", lw=1, label=f"{STANDARD_GRAVITY}")
    hx.set_xlabel("fitted g (m/s$^2$)")
    hx.set_ylabel("flights")
    hx.set_title(f"{doc['n_flights']} flights", fontsize=9)
    hx.legend(fontsize=8)
    hand_period = doc["_pattern"].hand_period
    plot_ladder(fig.add_subplot(grid[1, :]), mine, t0, t0 + span, hand_period)
    fig.tight_layout()
    return save_figure(fig, path, dpi=150)


def plot_ladder(
    ax: Any, events: list[ThrowEvent], start: float, end: float, hand_period: float = math.nan
) -> None:
    """The ladder diagram of the seen throws between ``start`` and ``end`` (s): a rail
    per hand, each throw a line from its hand at the release to the catching hand at
    the catch (dashed up to the parabola's end when the catch was not seen), labelled
    with its value; a thick segment on the rail from a catch to that hand's next
    throw (the dwell, when that throw comes within 1.1 ``hand_period``)."""
    longest = 1.1 * hand_period if math.isfinite(hand_period) else 1.0
    hands = sorted({e.hand for e in events} | {e.catch_hand for e in events if e.catch_hand >= 0})
    for h in hands:
        ax.axhline(h, color="0.8", lw=1)
    shown = [e for e in events if e.time <= end and (e.time >= start or e.catch_time >= start)]
    for e in shown:
        colour = f"C{e.value % 10}" if e.value > 0 else "0.4"
        if e.catch_hand >= 0:
            ax.plot([e.time, e.catch_time], [e.hand, e.catch_hand], color=colour, lw=1.4)
            mid = (0.5 * (e.time + e.catch_time), 0.5 * (e.hand + e.catch_hand))
            later = [o.time for o in events if o.hand == e.catch_hand and o.time > e.catch_time]
            if later and later[0] - e.catch_time <= longest:
                ax.plot([e.catch_time, later[0]], [e.catch_hand] * 2, color=colour, lw=4, alpha=0.5)
        else:
            mid = (e.time + 0.1, e.hand + (0.25 if e.hand == 0 else -0.25))
            ax.plot([e.time, mid[0]], [e.hand, mid[1]], color=colour, lw=1.2, ls="--")
        if e.value > 0:
            ax.annotate(str(e.value), mid, fontsize=7, ha="center", va="center", color=colour)
    ax.set_xlim(start, end)
    ax.set_ylim(-0.3, max(hands, default=0) + 0.3)
    ax.set_yticks(hands, [f"hand {h}" for h in hands])
    ax.set_xlabel("time (s)")
    ax.set_title(
        "ladder diagram: seen throws (release to catch, value), dwell on the hand's rail",
        fontsize=9,
    )


def write_analysis(doc: dict[str, Any], out: str | os.PathLike[str]) -> list[Path]:
    """``results.json``, ``flights.csv`` and ``flights.png`` in ``out`` (atomically)."""
    folder = Path(out)
    folder.mkdir(parents=True, exist_ok=True)
    paths = [
        atomic_write_text(
            folder / "results.json", json.dumps(clean_json(doc), indent=2, allow_nan=False) + "\n"
        )
    ]
    table = pd.DataFrame(doc["flights"]) if doc["flights"] else pd.DataFrame(columns=["start"])
    paths.append(atomic_write_text(folder / "flights.csv", table.to_csv(index=False)))
    paths.append(plot_flights(doc, folder / "flights.png"))
    return paths
