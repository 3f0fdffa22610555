"""Which siteswaps the analytic cascade juggler can play, and why not the others; the
registered patterns.

:func:`check_pattern` takes a siteswap at a cascade juggler's own tempo (its fitted
:class:`~motion_envs.models.juggling.CascadePattern`: the beat ``b`` and the dwell ``D``
of its cascade, Shannon's theorem, at the fit's or a given dwell ratio) and gives each
throw value what it needs (:class:`ThrowNeed`):

* its flight ``F_h = h b - D`` (:func:`~motion_envs.datasets.juggling.siteswap_flights`);
* the vertical release speed that makes the ball fall from the cascade's release height
  ``z_r`` to its catch height ``z_c`` in ``F_h``: ``z_c = z_r + v F - g F^2 / 2``, so
  ``v = (z_c - z_r) / F + g F / 2``, with ``z_c - z_r`` read from the pattern (the
  juggler's nominal toss and flight, which satisfy the same equation);
* the apex above the release, ``v^2 / (2 g)``.

The pattern fits when every reason in :attr:`PatternCheck.reasons` is absent: the ball
count is the fit's (``CascadePattern.balls``); every ball flies (``F_h > 0``: a hand
cannot throw a ball before it has caught it); every release is within the hand's speed
limit (a ball leaves the palm at the palm's speed); and every pattern is a cascade (every
throw the same odd value, the ball count: the juggler's hands each catch the other hand's
ball in turn; self-throws, holds, passes and empty beats are not modelled). At the
three-ball juggler's tempo only ``"3"`` fits: ``"5"`` needs a release above the hand's
limit and ``"441"``'s throw of 1 a dwell shorter than a beat. ``"5"`` is played by the
siteswap juggler at its own tempo, a nominal pattern DESIGNED, not fitted: the release
and catch points of :class:`~motion_envs.models.juggling.SiteswapStyle`, a dwell ratio
of 2/3 (Kalvan's, below), the beat :func:`~motion_envs.models.juggling.choose_beat`
finds (0.22 s at 9.81 m/s^2) and the flight Shannon's theorem gives it (0.81 s). Its
likeness reference is its own SIMULATED demonstrations
(:func:`~motion_envs.models.juggling.siteswap_demonstrations`: that nominal pattern
played by seeded persons); it was not fitted on the five-ball cascade demonstrations
(:data:`~motion_envs.datasets.juggling.CASCADE_STYLES`), from which its hand deviates
by about 48 mm (Cascade-v1's likeness score, the juggler row: 47.9 mm; BENCHMARKS).

:class:`PatternSpec` and :func:`register_pattern`: a pattern Cascade-v0 plays is a spec
(name, siteswap, dwell ratio, the controller's tunables) plus a registration
(:data:`PATTERNS`); :func:`pattern_spec` finds it or refuses with the reason. Two jugglers
play them, chosen by the spec's tunables: with
:class:`~motion_envs.models.juggling.CascadeTunables` the fitted cascade juggler above (the
odd cascades it has demonstrations for; ``"3"`` and ``"3-human"``), with a
:class:`~motion_envs.models.juggling.SiteswapStyle` the siteswap juggler
(:mod:`~motion_envs.models.juggling._cascade_siteswap`: any vanilla siteswap of 2 to 5
balls without empty beats, each throw value on its own flight; ``"5"``, ``"4"``,
``"441"``, ``"531"``, ``"423"``, ``"51"``). :func:`pattern_controller` and
:func:`pattern_likeness` build a spec's controller and its human-likeness reference;
:func:`pattern_tempo` checks it at its juggler's tempo.
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass

from motion_envs.datasets.juggling import (
    CASCADE_STYLES,
    JugglingTask,
    format_siteswap,
    parse_siteswap,
    siteswap_balls,
    siteswap_flights,
    split_cycles,
)
from motion_envs.models.juggling._cascade import CascadePattern, cascade_fit, cascade_likeness
from motion_envs.models.juggling._cascade_control import CascadeController, make_cascade_controller
from motion_envs.models.juggling._cascade_hand import DEFAULT_TUNABLES, CascadeTunables
from motion_envs.models.juggling._cascade_siteswap import (
    HAND_SPEED_LIMIT,
    SiteswapPlan,
    SiteswapStyle,
    choose_beat,
    siteswap_demonstrations,
    siteswap_reasons,
)
from motion_envs.models.juggling._cascade_siteswap_catch import SiteswapCatchController
from motion_envs.models.juggling._cascade_siteswap_control import SiteswapController
from motion_envs.models.juggling._fit import FIT_SEED, FIT_TEST_FRACTION
from motion_envs.models.juggling._levels import CONTROLLERS, HumanLikeness
from motion_envs.models.juggling._v2_catch import CatchPlan

__all__ = [
    "PATTERNS",
    "PatternCheck",
    "PatternSpec",
    "ThrowNeed",
    "check_pattern",
    "pattern_controller",
    "pattern_likeness",
    "pattern_plan",
    "pattern_reasons",
    "pattern_spec",
    "pattern_tempo",
    "register_pattern",
]


@dataclass(frozen=True)
class ThrowNeed:
    """What a throw value needs at the cascade's tempo (module docstring); ``crossing``:
    it lands in the other hand (odd value). For a throw of 0 (an empty beat) every
    figure is 0."""

    value: int
    crossing: bool
    flight: float  # s
    release_speed: float  # m/s, vertical (negative: thrown downwards)
    apex: float  # m above the release


@dataclass(frozen=True)
class PatternCheck:
    """:func:`check_pattern`'s answer: the siteswap, its balls, the tempo it was checked
    at (``beat``, ``dwell``, s), each distinct throw value's :class:`ThrowNeed` (in
    descending order) and the reasons it does not fit (empty: it fits)."""

    siteswap: str
    balls: int
    beat: float
    dwell: float
    throws: tuple[ThrowNeed, ...]
    reasons: tuple[str, ...]

    @property
    def fits(self) -> bool:
        """Whether the cascade juggler can play the pattern."""
        return not self.reasons


def check_pattern(
    siteswap: str,
    pattern: CascadePattern,
    gravity: float,
    speed_limit: float,
    dwell_ratio: float | None = None,
) -> PatternCheck:
    """Check ``siteswap`` at the tempo of ``pattern`` (fitted at ``gravity``, m/s^2; at
    ``dwell_ratio``, None: the fit's) against the hand's ``speed_limit`` (m/s); see the
    module docstring. Raises ``ValueError`` for a siteswap that is not one
    (:func:`parse_siteswap`, :func:`siteswap_balls`) or a non-positive ``gravity`` or
    ``speed_limit``."""
    if not (math.isfinite(gravity) and gravity > 0):
        raise ValueError(f"gravity must be finite and > 0; got {gravity!r}")
    if not (math.isfinite(speed_limit) and speed_limit > 0):
        raise ValueError(f"speed_limit must be finite and > 0; got {speed_limit!r}")
    throws = parse_siteswap(siteswap)
    balls = siteswap_balls(throws)
    r = pattern.dwell_ratio if dwell_ratio is None else float(dwell_ratio)
    period, beat = pattern.timing(r)
    dwell = r * period
    # the catch height below the release, from the juggler's own toss and flight
    f0, v0 = pattern.flight, float(pattern.release_velocity[1])
    drop = v0 * f0 - 0.5 * gravity * f0 * f0  # z_c - z_r
    values = sorted(set(throws), reverse=True)
    needs = []
    for h, f in zip(values, siteswap_flights(values, beat, dwell), strict=True):
        v = drop / f + 0.5 * gravity * f if f > 0 else 0.0
        apex = v * v / (2 * gravity) if v > 0 else 0.0
        needs.append(ThrowNeed(h, h % 2 == 1, f, v, apex))
    reasons = []
    if balls != pattern.balls:
        reasons.append(f"it has {balls} ball{_s(balls)}, the juggler's fit {pattern.balls}")
    for n in needs:
        if n.value > 0 and n.flight <= 0:
            reasons.append(
                f"a throw of {n.value} would fly {n.flight:.3f} s: the dwell ({dwell:.3f} s) "
                f"is not shorter than {n.value} beat{_s(n.value)} ({n.value * beat:.3f} s)"
            )
        elif abs(n.release_speed) > speed_limit:  # a short flight may need a throw down
            reasons.append(
                f"a throw of {n.value} needs a {abs(n.release_speed):.2f} m/s release, above the "
                f"hand's {speed_limit:g} m/s limit"
            )
    if balls % 2 == 0 or values != [balls]:
        reasons.append(
            "it is not a cascade (every throw the same odd value, each hand catching the "
            "other hand's ball): self-throws, passes and empty beats are not modelled"
        )
    return PatternCheck(format_siteswap(throws), balls, beat, dwell, tuple(needs), tuple(reasons))


def _s(n: int) -> str:
    return "" if n == 1 else "s"


@dataclass(frozen=True)
class PatternSpec:
    """A pattern Cascade-v0 plays (:data:`PATTERNS`): its ``name`` (what ``pattern=``
    takes), its vanilla ``siteswap``, its ``dwell_ratio`` ``D / (V + D)`` (None: the
    pattern's training demonstrations' median, the fitted juggler only) with the source of
    that value in ``note``, and the controller's ``tunables`` for it, which also choose the
    juggler (module docstring): :class:`CascadeTunables` the fitted cascade juggler (its
    flight its own toss's, fitted on the pattern's SIMULATED demonstrations, the tempo
    Shannon's theorem's), :class:`SiteswapStyle` the siteswap juggler (each throw value's
    flight from the theorem at the tempo :func:`choose_beat` finds)."""

    name: str
    siteswap: str
    dwell_ratio: float | None = None
    note: str = ""
    tunables: CascadeTunables | SiteswapStyle = DEFAULT_TUNABLES

    @property
    def fitted(self) -> bool:
        """Whether the fitted cascade juggler plays it (else the siteswap juggler)."""
        return isinstance(self.tunables, CascadeTunables)

    @property
    def throws(self) -> tuple[int, ...]:
        """The siteswap's throw values."""
        return parse_siteswap(self.siteswap)

    @property
    def balls(self) -> int:
        """The number of balls (the average throw)."""
        return siteswap_balls(self.throws)


#: The registered patterns by name (:func:`register_pattern`).
PATTERNS: dict[str, PatternSpec] = {}


def cascade_reasons(siteswap: str) -> tuple[str, ...]:
    """Why the fitted cascade juggler cannot play ``siteswap`` whatever its tempo (empty:
    it can): it plays odd cascades (every throw the same odd value, each hand catching the
    other hand's ball) of the ball counts it has demonstrations for
    (:data:`~motion_envs.datasets.juggling.CASCADE_STYLES`). Raises ``ValueError`` for a
    siteswap that is not one."""
    throws = parse_siteswap(siteswap)
    balls = siteswap_balls(throws)
    reasons = []
    if balls % 2 == 0 or set(throws) != {balls}:
        reasons.append(
            "it is not a cascade (every throw the same odd value, each hand catching the "
            "other hand's ball): the fitted juggler has one toss"
        )
    if balls not in CASCADE_STYLES:
        reasons.append(
            f"it has {balls} ball{_s(balls)}; demonstrations exist for "
            f"{', '.join(str(b) for b in sorted(CASCADE_STYLES))}"
        )
    return tuple(reasons)


def pattern_reasons(siteswap: str) -> tuple[str, ...]:
    """Why no juggler can play ``siteswap`` (empty: the siteswap juggler can, at a tempo
    within the hand's limits or not: :func:`~motion_envs.models.juggling.choose_beat`
    says): it plays vanilla siteswaps of 2 to 5 balls without empty beats
    (:func:`~motion_envs.models.juggling.siteswap_reasons`). Raises ``ValueError`` for a
    text that is no valid siteswap (:func:`parse_siteswap`, :func:`siteswap_balls`)."""
    return siteswap_reasons(siteswap)


def register_pattern(spec: PatternSpec) -> PatternSpec:
    """Add ``spec`` to :data:`PATTERNS` (a name is registered once); ``ValueError`` with
    the reasons if its juggler cannot play its siteswap (the fitted one:
    :func:`cascade_reasons`; the siteswap one: :func:`pattern_reasons`, or no tempo within
    the hand's limits at 9.81 m/s^2), or its dwell ratio is not in (0.2, 0.9) (the
    siteswap juggler needs one) or leaves no flight."""
    if not isinstance(spec, PatternSpec):
        raise ValueError(f"register_pattern takes a PatternSpec; got {type(spec).__name__}")
    if spec.name in PATTERNS:
        raise ValueError(f"pattern {spec.name!r} is already registered")
    if not isinstance(spec.tunables, (CascadeTunables, SiteswapStyle)):
        raise ValueError(
            "PatternSpec.tunables must be a CascadeTunables or a SiteswapStyle; "
            f"got {spec.tunables!r}"
        )
    reasons = cascade_reasons(spec.siteswap) if spec.fitted else pattern_reasons(spec.siteswap)
    if reasons:
        raise ValueError(f"pattern {spec.siteswap!r} cannot be played: " + "; ".join(reasons))
    r = spec.dwell_ratio
    if (r is not None or not spec.fitted) and not (isinstance(r, float) and 0.2 < r < 0.9):
        raise ValueError(f"PatternSpec.dwell_ratio must be a float in (0.2, 0.9); got {r!r}")
    if not spec.fitted:
        pattern_plan(spec, 9.81)  # raises with the reason when no tempo fits
    PATTERNS[spec.name] = spec
    return spec


def pattern_spec(name: str) -> PatternSpec:
    """The registered pattern ``name``; ``ValueError`` in one line naming the registered
    ones and, for a siteswap no juggler can play, why."""
    if name in PATTERNS:
        return PATTERNS[name]
    known = ", ".join(repr(p) for p in PATTERNS)
    try:
        reasons = pattern_reasons(name)
    except ValueError as exc:
        raise ValueError(f"pattern must be one of {known}; {exc}") from None
    why = "; ".join(reasons) if reasons else "it is not registered (register_pattern)"
    raise ValueError(f"pattern must be one of {known}; {name!r}: {why}")


@functools.lru_cache(maxsize=32)
def pattern_plan(spec: PatternSpec, gravity: float) -> SiteswapPlan:
    """The siteswap juggler's plan of ``spec`` at ``gravity`` (its tempo:
    :func:`~motion_envs.models.juggling.choose_beat`); ``ValueError`` for a spec the
    fitted juggler plays."""
    if spec.fitted or spec.dwell_ratio is None:
        raise ValueError(f"pattern {spec.name!r} is played by the fitted cascade juggler")
    assert isinstance(spec.tunables, SiteswapStyle)
    return choose_beat(
        spec.siteswap, spec.dwell_ratio, spec.tunables, JugglingTask(gravity=gravity)
    )


def pattern_controller(
    spec: PatternSpec,
    name: str,
    gravity: float,
    latency: float = 0.0,
    dwell_ratio: float | None = None,
    tunables: CascadeTunables | SiteswapStyle | None = None,
    catch: CatchPlan | None = None,
) -> CascadeController | SiteswapController:
    """The reference controller ``name`` (one of ``CONTROLLERS``) playing ``spec`` at
    ``gravity`` with the sensor's ``latency`` (s), at ``dwell_ratio`` (None: the spec's)
    with ``tunables`` (None: the spec's; of the spec's juggler's kind); ``catch``: the
    siteswap juggler's catch plan (:class:`SiteswapCatchController`; None: the juggler's
    own catch; refused for the fitted juggler, whose plan the view carries)."""
    if name not in CONTROLLERS:
        raise ValueError(f"controller must be one of {list(CONTROLLERS)}; got {name!r}")
    t = spec.tunables if tunables is None else tunables
    if not isinstance(t, type(spec.tunables)):
        raise ValueError(
            f"tunables must be a {type(spec.tunables).__name__} for pattern {spec.name!r}; "
            f"got {t!r}"
        )
    r = spec.dwell_ratio if dwell_ratio is None else float(dwell_ratio)
    if isinstance(t, CascadeTunables):
        if catch is not None:
            raise ValueError(f"catch must be None for the fitted juggler (pattern {spec.name!r})")
        return make_cascade_controller(name, cascade_fit(gravity, spec.balls), latency, r, t)
    own = PatternSpec(spec.name, spec.siteswap, r, spec.note, t)
    if catch is not None:
        return SiteswapCatchController(pattern_plan(own, gravity), catch, name, latency)
    return SiteswapController(pattern_plan(own, gravity), name, latency)


@functools.lru_cache(maxsize=16)
def pattern_likeness(spec: PatternSpec, gravity: float) -> HumanLikeness:
    """The human-likeness reference of ``spec`` at ``gravity``: the training cycles of its
    SIMULATED demonstrations (the fitted juggler's: the cascade's,
    :func:`~motion_envs.models.juggling.cascade_likeness`; the siteswap juggler's:
    :func:`~motion_envs.models.juggling.siteswap_demonstrations` at the spec's dwell
    ratio, split as the cascade's, held-out share ``FIT_TEST_FRACTION``)."""
    if spec.fitted:
        return cascade_likeness(gravity, "train", spec.balls)
    assert isinstance(spec.tunables, SiteswapStyle) and spec.dwell_ratio is not None
    task = JugglingTask(gravity=gravity)
    demos = siteswap_demonstrations(
        spec.siteswap, spec.dwell_ratio, spec.tunables, task, seed=FIT_SEED
    )
    train, _ = split_cycles(demos, FIT_TEST_FRACTION, FIT_SEED)
    return HumanLikeness(demos, train)


def pattern_tempo(spec: PatternSpec, gravity: float) -> PatternCheck:
    """``spec`` at its juggler's tempo: the beat, the dwell and each throw value's
    :class:`ThrowNeed` (the fitted juggler: :func:`check_pattern` at its fit; the
    siteswap juggler: its plan's flights and release velocities, a hold's all 0)."""
    if spec.fitted:
        fit = cascade_fit(gravity, spec.balls)
        return check_pattern(
            spec.siteswap, fit.pattern, gravity, HAND_SPEED_LIMIT, spec.dwell_ratio
        )
    plan = pattern_plan(spec, gravity)
    tm = plan.timing
    needs = []
    for h in sorted(set(tm.throws), reverse=True):
        if h == 2:
            needs.append(ThrowNeed(h, False, 0.0, 0.0, 0.0))
            continue
        v = float(plan.throw_velocity(h)[1])
        apex = v * v / (2 * gravity) if v > 0 else 0.0
        needs.append(ThrowNeed(h, h % 2 == 1, tm.flight(h), v, apex))
    return PatternCheck(spec.siteswap, plan.balls, plan.beat, tm.dwell, tuple(needs), ())


_KALVAN = (
    "J. Kalvan, 'How many objects can be juggled', 1997: 'My tests show r is usually "
    "about 2/3'; his 'Optimal Juggling', 1996: near 2/3 for cascades of 3, 5, 7 and 9 balls"
)


register_pattern(
    PatternSpec(
        "3",
        "3",
        None,
        "the three-ball cascade; dwell ratio: the SIMULATED training cycles' median",
    )
)
register_pattern(
    PatternSpec(
        "3-human",
        "3",
        2.0 / 3.0,
        "the three-ball cascade at a human dwell ratio of 2/3 (J. Kalvan, 'How many objects "
        "can be juggled', 1997: 'My tests show r is usually about 2/3'); the same flight as "
        "'3', a slower beat",
    )
)
#: The siteswap juggler's registered patterns: (name, what it is).
SITESWAP_PATTERNS = (
    ("5", "the five-ball cascade"),
    ("4", "the four-ball fountain (each hand its own two balls, throws of 4 come back)"),
    ("441", "three balls: two throws of 4 and a pass (a 1)"),
    ("531", "three balls: a 5, a 3 and a pass (a 1)"),
    ("423", "three balls: a 4, a hold (the 2) and a 3"),
    ("51", "three balls: a 5 and a pass (a 1), the shower"),
)
#: The registered patterns' styles where they differ from ``SiteswapStyle()``: 531 at a
#: beat of 0.225 s rather than choose_beat's 0.205 s (10 TRAINING seeds, easy, at most 100
#: catches: median 27 at 0.215 s, 100 at 0.225 s, 73.5 at 0.235 s; within the hand's limits).
STYLES = {"531": SiteswapStyle(beat=0.225)}
for _name, _what in SITESWAP_PATTERNS:
    _style = STYLES.get(_name, SiteswapStyle())
    _tempo = (
        f"at a beat of {_style.beat} s (chosen on training seeds)"
        if _style.beat is not None
        else "at the tempo whose nominal peak acceleration is least (choose_beat)"
    )
    register_pattern(
        PatternSpec(
            _name,
            _name,
            2.0 / 3.0,
            f"{_what}, played by the siteswap juggler at a human dwell ratio of 2/3 "
            f"({_KALVAN}; measured on cascades, taken for every pattern); each throw value's "
            f"flight from Shannon's theorem {_tempo}",
            _style,
        )
    )
