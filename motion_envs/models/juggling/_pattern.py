"""The juggling pattern of recorded ball flights: hands, beat, throw values, siteswap,
dwell, and the number of balls three ways.

Input: the flights of :func:`~motion_envs.models.juggling.detect_flights` (vertical
last). Only events that were seen count: a **throw** is the first sample of a flight
whose ball was seen in a hand just before it (``start_seen``), a **catch** the last
sample of one seen in a hand after it (``end_seen``); an end at a tracking loss or a
marker swap is no event.

Assumptions (a recording that breaks one gets a warning, not a silent number): vanilla
asynchronous juggling (the hands throw in turn, one ball per throw, a hand holds at
most one ball: no multiplex, no synchronous throws), catches and throws at about one
height band (the hands below the balls' apexes), two hands at most, apart across the
body; a pattern is a run of throws on a regular beat.

Steps (:func:`pattern_summary`):

1. **Across-body axis.** The principal axis of the horizontal positions of all throws
   and catches (the hands are apart across the body; the throws' forward spread is
   smaller). A 2-D input (lateral, vertical) has its lateral axis; ``lateral=`` forces
   a horizontal coordinate.
2. **Hands.** The throws' positions on that axis split in two by the optimal two-means;
   two hands when the centres are more than :data:`HANDS_SEPARATION` pooled standard
   deviations apart and each holds at least :data:`HANDS_MIN_SHARE` of the throws, else
   one. An event belongs to the hand on its side of the midline between the centres.
3. **Beat.** ``b`` = the median interval between successive throws of a recording; a
   run of throws ends at an interval over :data:`PAUSE_BEATS` beats. Within a run each
   throw gets a beat index (the previous one plus the interval in beats, rounded). The
   throws are on a regular beat when at least :data:`REGULAR_SHARE` of the intervals are
   within :data:`BEAT_TOLERANCE` beats of a whole number of beats, and there are at
   least :data:`MIN_PATTERN_THROWS` throws; else (single throws, an irregular
   recording) the throw period, dwell ratio, throw values and siteswap are not given.
4. **Dwell.** A ball caught by a hand is thrown by that hand's next throw (one ball per
   hand): dwell ``D`` = from the catch to that throw, when it comes within
   :data:`DWELL_LIMIT` hand periods (a missed throw would double it); hand period =
   the median interval between throws of one hand two beats apart (two hands) or the
   beat (one hand); vacant ``V`` = hand period - D; dwell ratio = D / hand period.
5. **Throw values.** The ball thrown on beat ``k`` is thrown again on beat ``k'`` by
   the hand that caught it: its value is ``k' - k`` (a siteswap's throw value). When
   that next throw was not seen, the value is ``round((F + D) / b)`` from the flight
   time ``F`` (``F_h = h b - D``, :func:`~motion_envs.datasets.juggling.siteswap_flights`),
   and when the catch was not seen either, ``F`` is where the flight's parabola comes
   down to the median catch height above the release.
6. **Siteswap.** For periods ``p`` = 1 .. :data:`MAX_PERIOD` (multiples of the
   shortest period at which some beat never has a seen throw), the throws of a run are
   grouped by beat modulo ``p`` and each group's most common value taken; the siteswap is
   the shortest period whose values agree with as many throws as any period's, give or
   take :data:`SITESWAP_SLACK` of them (or one), and with at least
   :data:`SITESWAP_AGREEMENT` of the throws (one beat never seen takes the value that
   completes the permutation of landing beats; more: no siteswap), written from its
   largest rotation (``441``, ``531``) and checked by the permutation test
   (:func:`~motion_envs.datasets.juggling.siteswap_balls`).
7. **Balls**, three ways: the siteswap's average throw; Shannon's theorem
   ``(F + D) / (V + D) = N / H`` with ``F`` the mean flight over the siteswap's throws
   (the median flight of each value; the median of all flights without a siteswap); and
   the concurrent count: at each moment of the pattern, the balls in the air (the
   flights, each extended to the median release and catch heights where its ends were
   not seen) plus the hands holding one (from a catch to that hand's next throw), the
   median over time. ``balls`` is the given number, else the siteswap's, else the
   theorem's rounded, else the concurrent count rounded; a warning says when they
   disagree by half a ball or more. The flight time the theorem gives for ``balls``,
   ``N (V + D) / H - D``, is reported beside the measured mean flight.
"""

from __future__ import annotations

import itertools
import math
from collections import Counter
from dataclasses import dataclass

import numpy as np

from motion_envs._typing import FloatArray
from motion_envs.datasets.juggling import format_siteswap, siteswap_balls
from motion_envs.models.juggling._flights import Flight

__all__ = [
    "BEAT_TOLERANCE",
    "DWELL_LIMIT",
    "HANDS_MIN_SHARE",
    "HANDS_SEPARATION",
    "MAX_PERIOD",
    "MIN_PATTERN_THROWS",
    "PAUSE_BEATS",
    "REGULAR_SHARE",
    "SITESWAP_AGREEMENT",
    "SITESWAP_SLACK",
    "PatternSummary",
    "ThrowEvent",
    "across_axis",
    "pattern_summary",
]

#: Two hands when the two-means centres of the throws are this many pooled std apart.
HANDS_SEPARATION = 4.0
#: ... and each centre holds at least this share of the throws.
HANDS_MIN_SHARE = 0.2
#: An interval over this many beats ends a run of throws (a pause).
PAUSE_BEATS = 6.0
#: An interval is on the beat within this many beats of a whole number.
BEAT_TOLERANCE = 0.25
#: Share of the intervals on the beat for a regular pattern.
REGULAR_SHARE = 0.8
#: Fewest throws for a pattern.
MIN_PATTERN_THROWS = 6
#: A hand's next throw later than this many hand periods after a catch is not the one
#: that throws the caught ball (a throw was missed).
DWELL_LIMIT = 1.1
#: Longest siteswap period looked for.
MAX_PERIOD = 8
#: Share of the valued throws a siteswap's values must agree with.
SITESWAP_AGREEMENT = 0.85
#: A longer period is taken when its values agree with more throws than a shorter
#: one's by more than this share of them (or one throw).
SITESWAP_SLACK = 0.05


@dataclass(frozen=True)
class ThrowEvent:
    """One seen throw: recording, time (s), hand (0: the negative side of the
    across-body axis, 1: the positive), run and beat index within it (-1: not on a
    beat), value (0: unknown) and how it was found (``"next throw"``, ``"flight"``,
    ``"parabola"`` or ``""``), the catch (NaN / -1 when not seen), flight time and
    apex above the release (m)."""

    recording: str
    time: float
    hand: int
    run: int
    beat: int
    value: int
    value_from: str
    catch_time: float
    catch_hand: int
    flight: float
    apex_above: float


@dataclass(frozen=True)
class PatternSummary:
    """The pattern (module docstring); NaN / None where the events do not tell.

    Times in s. ``axis``: the across-body direction (unit, horizontal coordinates);
    ``balls_theorem``: Shannon's ``H (F + D) / (V + D)``; ``balls_concurrent``: the
    median count of balls in the air and in the hands; ``balls_siteswap``: the
    siteswap's average throw; ``balls``: the one used (module docstring, step 7);
    ``flight_theorem``: ``N (V + D) / H - D`` for ``balls``; ``flight``: the median
    flight, ``flight_mean`` the mean over the siteswap's throws; ``siteswap_agreement``:
    the share of valued throws the siteswap's values agree with; ``warnings``: what
    does not fit the assumptions."""

    throws: int
    catches: int
    hands: int
    axis: tuple[float, ...]
    midline: float
    regular: bool
    throw_period: float
    hand_period: float
    flight: float
    flight_mean: float
    dwell: float
    vacant: float
    dwell_ratio: float
    alternation: float
    apex_above_release: float
    siteswap: str | None
    siteswap_agreement: float
    balls: int | None
    balls_theorem: float
    balls_concurrent: float
    balls_siteswap: int | None
    flight_theorem: float
    warnings: tuple[str, ...]
    events: tuple[ThrowEvent, ...]

    def as_dict(self) -> dict[str, object]:
        """Every field but ``events`` (JSON-ready: lists for tuples)."""
        out: dict[str, object] = {}
        for k in self.__dataclass_fields__:
            if k == "events":
                continue
            v = getattr(self, k)
            out[k] = list(v) if isinstance(v, tuple) else v
        return out


def _median(values: list[float]) -> float:
    return float(np.median(values)) if values else math.nan


def _two_means(x: FloatArray) -> tuple[float, float, float, float]:
    """Centres (low, high), pooled std and the low share of the optimal 1-D two-means
    split."""
    xs = np.sort(x)
    n = xs.size
    k = np.arange(1, n)
    left = np.cumsum(xs)[:-1]
    right = xs.sum() - left
    # within-cluster sum of squares = total sum of squares - between-cluster terms
    cost = float((xs**2).sum()) - left**2 / k - right**2 / (n - k)
    i = int(np.argmin(cost))
    pooled = math.sqrt(max(float(cost[i]), 0.0) / max(n - 2, 1))
    return float(left[i] / k[i]), float(right[i] / (n - k[i])), pooled, float(k[i] / n)


def across_axis(horizontal: FloatArray) -> FloatArray:
    """The unit principal axis of ``(n, 2)`` horizontal positions (its larger component
    positive); ``(1, 0)`` for fewer than 3 positions. For ``(n, 1)`` positions:
    ``(1,)``."""
    h = np.asarray(horizontal, dtype=np.float64)
    if h.shape[1] == 1:
        return np.ones(1)
    if h.shape[0] < 3:
        return np.array([1.0, 0.0])
    _, vecs = np.linalg.eigh(np.cov(h.T))
    u: FloatArray = vecs[:, -1]
    if u[int(np.argmax(np.abs(u)))] < 0:
        u = -u
    return u


def _release_height(f: Flight) -> float:
    return float(f.position(f.start)[-1])


def _time_at_height(f: Flight, height: float, rising: bool = False) -> float:
    """The time where the flight's parabola comes down to ``height`` (its descending
    branch), or goes up through it (``rising``); NaN when it never reaches it."""
    c0, c1, c2 = (float(c) for c in f.coef[:, -1])
    disc = c1 * c1 - 4.0 * c2 * (c0 - height)
    if c2 >= 0 or disc < 0:
        return math.nan
    roots = sorted((-c1 + s * math.sqrt(disc)) / (2.0 * c2) + f.t_ref for s in (1.0, -1.0))
    return roots[0] if rising else roots[1]


@dataclass
class _Throw:
    flight: Flight
    hand: int
    run: int = -1
    beat: int = -1
    value: int = 0
    value_from: str = ""
    catch_hand: int = -1
    dwell: float = math.nan


def _beat(intervals: list[float]) -> float:
    """The beat: starting from the 10th, 25th and 50th percentiles of the intervals
    (missed throws make some intervals two or more beats), each refined by least
    squares on the whole numbers of beats it gives the intervals up to
    :data:`PAUSE_BEATS`; the one that puts most intervals within
    :data:`BEAT_TOLERANCE` of a whole number of beats (the longest of equals)."""
    x = np.array(intervals)
    if x.size == 0:
        return math.nan
    best, best_share = math.nan, -1.0
    for q in (50, 25, 10):
        b = float(np.percentile(x, q))
        if b <= 0:
            continue
        for _ in range(5):
            use = x[x / b <= PAUSE_BEATS]
            n = np.maximum(1, np.round(use / b))
            b = float((use * n).sum() / (n * n).sum())
        use = x[x / b <= PAUSE_BEATS]
        share = float(np.mean(np.abs(use / b - np.round(use / b)) <= BEAT_TOLERANCE))
        if share > best_share + 0.02:
            best, best_share = b, share
    return best


def _runs(times: list[float], beat: float) -> tuple[list[int], list[int], list[float]]:
    """Run and beat index of each of the sorted ``times``, and each interval's distance
    to a whole number of beats."""
    runs, beats, off = [0], [0], []
    for a, b in itertools.pairwise(times):
        n = (b - a) / beat
        if n > PAUSE_BEATS:
            runs.append(runs[-1] + 1)
            beats.append(0)
            continue
        k = max(1, round(n))
        off.append(abs(n - k))
        runs.append(runs[-1])
        beats.append(beats[-1] + k)
    return runs, beats, off


def _empty_beats(throws: list[_Throw]) -> int:
    """The shortest period ``q`` (2 .. :data:`MAX_PERIOD`) at which a beat of the
    longest run never has a seen throw though it spans at least 3 periods, the other
    beats have 2 or more each, and missed throws spread evenly would leave a beat empty
    with probability under 1 %: a value never seen (an empty hand, or a throw
    the capture always misses, such as the short 1 of 441); the siteswap's period is a
    multiple of it. 1 when there is none."""
    runs: dict[tuple[str, int], list[int]] = {}
    for th in throws:
        if th.beat >= 0:
            runs.setdefault((th.flight.recording, th.run), []).append(th.beat)
    if not runs:
        return 1
    beats = np.array(max(runs.values(), key=len))
    beats = beats - beats.min()
    span = int(beats.max()) + 1
    seen = beats.size / span
    for q in range(2, MAX_PERIOD + 1):
        if span < 3 * q:
            break
        count = np.bincount(beats % q, minlength=q)
        # a beat left empty by chance: q (1 - seen)^(span / q) under even misses
        chance = q * (1.0 - seen) ** (span / q) if seen < 1 else 0.0
        if count.min() == 0 and count[count > 0].min() >= 2 and chance < 0.01:
            return q
    return 1


def _siteswap(throws: list[_Throw], warnings: list[str]) -> tuple[tuple[int, ...] | None, float]:
    """The siteswap of the valued on-beat throws (step 6) and its agreement."""
    by_run: dict[tuple[str, int], dict[int, int]] = {}
    for th in throws:
        if th.value > 0 and th.beat >= 0:
            by_run.setdefault((th.flight.recording, th.run), {})[th.beat] = th.value
    total = sum(len(v) for v in by_run.values())
    if total < MIN_PATTERN_THROWS:
        return None, math.nan
    step = _empty_beats(throws)
    fits: list[tuple[int, int, dict[tuple[str, int], list[int]]]] = []
    for p in range(step, MAX_PERIOD + 1, step):
        agree = 0
        modes: dict[tuple[str, int], list[int]] = {}
        for key, seq in by_run.items():
            first = min(seq)
            groups: dict[int, list[int]] = {}
            for k, v in seq.items():
                groups.setdefault((k - first) % p, []).append(v)
            mode = [
                Counter(groups[r]).most_common(1)[0][0] if r in groups else -1 for r in range(p)
            ]
            agree += sum(v == mode[(k - first) % p] for k, v in seq.items())
            modes[key] = mode
        fits.append((p, agree, modes))
    most = max(a for _, a, _ in fits)
    slack = max(1.0, SITESWAP_SLACK * total)
    p, agree, modes = next(f for f in fits if most - f[1] <= slack)
    share = agree / total
    key = max(by_run, key=lambda r: len(by_run[r]))
    seq = by_run[key]
    if (max(seq) - min(seq) + 1) < 2 * p:
        warnings.append(f"the longest run covers fewer than two periods of {p} beats")
        return None, share
    mode = modes[key]
    unseen = [r for r in range(p) if mode[r] < 0]
    if len(unseen) == 1:  # the one value whose landing completes the permutation
        r = unseen[0]
        landed = {(i + h) % p for i, h in enumerate(mode) if h >= 0}
        free = [b for b in range(p) if b not in landed]
        mode[r] = (free[0] - r) % p if len(free) == 1 else -1
        if mode[r] >= 0:
            warnings.append(
                f"no value seen on beat {r + 1} of {p}: {mode[r]} completes the permutation"
            )
    if any(h < 0 for h in mode):
        warnings.append(f"throws of period {p} not seen on every beat: no siteswap")
        return None, share
    rotations = [tuple(mode[i:] + mode[:i]) for i in range(p)]
    pattern = max(rotations)
    if share < SITESWAP_AGREEMENT:
        warnings.append(
            f"no siteswap of period <= {MAX_PERIOD} fits {SITESWAP_AGREEMENT:.0%} of the "
            f"throw values (best {format_siteswap(pattern)}: {share:.0%})"
        )
        return None, share
    try:
        siteswap_balls(pattern)
    except ValueError as exc:
        warnings.append(f"the throw values repeat as {format_siteswap(pattern)}: {exc}")
        return None, share
    return pattern, share


def pattern_summary(
    flights: tuple[Flight, ...] | list[Flight],
    lateral: int | None = None,
    balls: int | None = None,
) -> PatternSummary:
    """The pattern of the flights (module docstring); ``lateral`` forces the horizontal
    coordinate across the body (None: from the data), ``balls`` the number of balls
    (None: measured). Raises ``ValueError`` for ``balls < 1`` or a ``lateral`` that is
    not a horizontal coordinate."""
    if balls is not None and balls < 1:
        raise ValueError(f"balls: expected an integer >= 1; got {balls!r}")
    flights = sorted(flights, key=lambda f: (f.recording, f.start))
    dims = flights[0].coef.shape[1] if flights else 2
    if lateral is not None and not 0 <= lateral < dims - 1:
        raise ValueError(f"lateral: expected a horizontal coordinate 0..{dims - 2}; got {lateral}")
    warnings: list[str] = []
    seen = [f for f in flights if f.start_seen]
    caught = [f for f in flights if f.end_seen]
    horizontal = [f.position(f.start)[:-1] for f in seen] + [f.position(f.end)[:-1] for f in caught]
    if dims == 2:
        axis = np.ones(1)
    elif lateral is not None:
        axis = np.eye(dims - 1)[lateral]
    else:
        axis = across_axis(np.array(horizontal).reshape(-1, dims - 1))

    def across(f: Flight, t: float) -> float:
        return float(f.position(t)[:-1] @ axis)

    hands, midline = 1, math.nan
    if len(seen) >= 4:
        low, high, pooled, share = _two_means(np.array([across(f, f.start) for f in seen]))
        if high - low > HANDS_SEPARATION * pooled and min(share, 1 - share) >= HANDS_MIN_SHARE:
            hands, midline = 2, 0.5 * (low + high)

    def hand(x: float) -> int:
        return 0 if hands == 1 or x < midline else 1

    throws = [_Throw(f, hand(across(f, f.start))) for f in seen]
    for th in throws:
        if th.flight.end_seen:
            th.catch_hand = hand(across(th.flight, th.flight.end))
    intervals = [
        b.flight.start - a.flight.start
        for a, b in itertools.pairwise(throws)
        if a.flight.recording == b.flight.recording
    ]
    beat = _beat(intervals)
    off: list[float] = []
    by_rec: dict[str, list[_Throw]] = {}
    for th in throws:
        by_rec.setdefault(th.flight.recording, []).append(th)
    if math.isfinite(beat) and beat > 0:
        for mine in by_rec.values():
            runs, beats, o = _runs([th.flight.start for th in mine], beat)
            off.extend(o)
            for th, r, k in zip(mine, runs, beats, strict=True):
                th.run, th.beat = r, k
    regular = (
        len(throws) >= MIN_PATTERN_THROWS
        and bool(off)
        and float(np.mean(np.array(off) <= BEAT_TOLERANCE)) >= REGULAR_SHARE
    )
    if not regular:
        if throws:
            warnings.append(
                f"the {len(throws)} seen throws are not on a regular beat (single throws, "
                "or too few): no throw period, dwell ratio, throw values or siteswap"
            )
        for th in throws:
            th.beat = -1
    # hand period and alternation from throws on adjacent beats
    same: list[float] = []
    alternate: list[bool] = []
    for mine in by_rec.values():
        for a, b in itertools.pairwise(mine):
            if a.run != b.run or a.beat < 0:
                continue
            if b.beat - a.beat == 1:
                alternate.append(a.hand != b.hand)
        for h in range(hands):
            own = [th for th in mine if th.hand == h and th.beat >= 0]
            step = 2 if hands == 2 else 1
            same.extend(
                b.flight.start - a.flight.start
                for a, b in itertools.pairwise(own)
                if a.run == b.run and b.beat - a.beat == step
            )
    alternation = float(np.mean(alternate)) if alternate else math.nan
    hand_period = _median(same) if regular else math.nan
    if regular and hands == 2 and alternation < 0.8:
        warnings.append(
            f"the hands alternate on only {alternation:.0%} of adjacent beats: not an "
            "asynchronous pattern (synchronous and multiplex patterns are not analysed)"
        )
    # dwell: a catch to the catching hand's next throw (step 4)
    limit = DWELL_LIMIT * (hand_period if math.isfinite(hand_period) else math.inf)
    nxt: dict[int, _Throw] = {}
    for i, th in enumerate(throws):
        if th.catch_hand < 0:
            continue
        c = th.flight.end
        later = [
            o for o in by_rec[th.flight.recording] if o.hand == th.catch_hand and o.flight.start > c
        ]
        if later and later[0].flight.start - c <= limit:
            if not regular or later[0].run == th.run:
                nxt[i] = later[0]
                th.dwell = later[0].flight.start - c
    dwell = _median([th.dwell for th in throws if math.isfinite(th.dwell)])
    if regular and not math.isfinite(dwell):
        warnings.append(
            "no seen catch is followed by its hand's next throw: no dwell, throw values or siteswap"
        )
    vacant = hand_period - dwell
    ratio = dwell / hand_period
    # throw values (step 5)
    complete = [f.duration for f in flights if f.start_seen and f.end_seen]
    catch_rise = _median(
        [float(f.position(f.end)[-1]) - _release_height(f) for f in seen if f.end_seen]
    )
    if regular:
        for i, th in enumerate(throws):
            f = th.flight
            if i in nxt and nxt[i].beat >= 0:
                th.value, th.value_from = nxt[i].beat - th.beat, "next throw"
                continue
            if not math.isfinite(dwell):
                continue
            if f.end_seen:
                flight, how = f.duration, "flight"
            else:
                flight = _time_at_height(f, _release_height(f) + catch_rise) - f.start
                how = "parabola"
            if math.isfinite(flight):
                value = round((flight + dwell) / beat)
                if value >= 1:
                    th.value, th.value_from = value, how
    pattern, agreement = _siteswap(throws, warnings) if regular else (None, math.nan)
    # flights by value and the theorem (step 7)
    by_value: dict[int, list[float]] = {}
    for th in throws:
        if th.flight.end_seen and th.value > 0:
            by_value.setdefault(th.value, []).append(th.flight.duration)
    if pattern is not None and math.isfinite(dwell):
        flight_mean = float(
            np.mean([_median(by_value[h]) if h in by_value else h * beat - dwell for h in pattern])
        )
    else:
        flight_mean = _median(complete)
    theorem = hands * (flight_mean + dwell) / (vacant + dwell)
    concurrent = _concurrent(flights, throws, nxt, dwell, catch_rise)
    b_site = siteswap_balls(pattern) if pattern is not None else None
    n = balls
    if n is None:
        for candidate in (b_site, theorem, concurrent):
            if candidate is not None and math.isfinite(candidate):
                n = max(1, round(candidate))
                break
        if n is not None and b_site is None and not math.isfinite(theorem):
            warnings.append(
                f"{n} balls from the concurrent count alone (fewer when flights or catches "
                "are missed)"
            )
    if n is not None:
        named = {
            "the siteswap": b_site,
            "Shannon's theorem": theorem,
            "the concurrent count": concurrent,
        }
        if balls is not None:
            named["--n-balls"] = balls
        off_by = {
            k: v
            for k, v in named.items()
            if v is not None and math.isfinite(v) and abs(v - n) >= 0.5
        }
        if off_by:
            said = ", ".join(
                f"{k} {v:.2f}" for k, v in named.items() if v is not None and math.isfinite(v)
            )
            warnings.append(f"the ball counts disagree ({said}); used {n}")
    flight_theorem = n * (vacant + dwell) / hands - dwell if n is not None else math.nan
    apex = [f.apex_height - _release_height(f) for f in seen if f.apex_time > f.start]
    events = tuple(
        ThrowEvent(
            recording=th.flight.recording,
            time=th.flight.start,
            hand=th.hand,
            run=th.run,
            beat=th.beat,
            value=th.value,
            value_from=th.value_from,
            catch_time=th.flight.end if th.flight.end_seen else math.nan,
            catch_hand=th.catch_hand,
            flight=th.flight.duration if th.flight.end_seen else math.nan,
            apex_above=th.flight.apex_height - _release_height(th.flight),
        )
        for th in throws
    )
    return PatternSummary(
        throws=len(throws),
        catches=len(caught),
        hands=hands,
        axis=tuple(float(a) for a in axis),
        midline=midline,
        regular=regular,
        throw_period=beat if regular else math.nan,
        hand_period=hand_period,
        flight=_median(complete),
        flight_mean=flight_mean,
        dwell=dwell,
        vacant=vacant,
        dwell_ratio=ratio,
        alternation=alternation,
        apex_above_release=_median(apex),
        siteswap=format_siteswap(pattern) if pattern is not None else None,
        siteswap_agreement=agreement,
        balls=n,
        balls_theorem=theorem,
        balls_concurrent=concurrent,
        balls_siteswap=b_site,
        flight_theorem=flight_theorem,
        warnings=tuple(warnings),
        events=events,
    )


def _concurrent(
    flights: list[Flight],
    throws: list[_Throw],
    nxt: dict[int, _Throw],
    dwell: float,
    catch_rise: float,
) -> float:
    """Median over the pattern's time of the balls in the air plus the hands holding
    one (step 7); NaN without throws."""
    release = _median([_release_height(f) for f in flights if f.start_seen])
    spans: dict[str, list[tuple[float, float]]] = {}
    for f in flights:
        s, e = f.start, f.end
        if math.isfinite(release):
            if not f.start_seen:  # back along the parabola to the release height
                rise = _time_at_height(f, release, rising=True)
                if math.isfinite(rise):
                    s = min(s, rise)
            if not f.end_seen and math.isfinite(catch_rise):
                fall = _time_at_height(f, release + catch_rise)
                if math.isfinite(fall):
                    e = max(e, fall)
        spans.setdefault(f.recording, []).append((s, e))
    held = set()
    d = dwell if math.isfinite(dwell) else 0.0
    for i, th in enumerate(throws):
        if th.catch_hand < 0:
            continue
        if i in nxt:
            held.add(id(nxt[i]))
            end = nxt[i].flight.start
        else:
            end = th.flight.end + d
        spans[th.flight.recording].append((th.flight.end, end))
    for th in throws:  # a throw whose catch was not seen was held for a dwell
        if id(th) not in held:
            spans[th.flight.recording].append((th.flight.start - d, th.flight.start))
    counts: list[FloatArray] = []
    for rec, sp in spans.items():
        own = [th.flight.start for th in throws if th.flight.recording == rec]
        if len(own) < 2:
            continue
        grid = np.linspace(min(own), max(own), 2000)
        arr = np.array(sp)
        counts.append(
            ((arr[:, 0][None, :] <= grid[:, None]) & (grid[:, None] <= arr[:, 1][None, :]))
            .sum(axis=1)
            .astype(np.float64)
        )
    if not counts:
        return math.nan
    return float(np.median(np.concatenate(counts)))
