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
limit and ``"441"``'s throw of 1 a dwell shorter than a beat; ``"5"`` is played at its
own juggler's tempo (fitted on five-ball demonstrations).

:class:`PatternSpec` and :func:`register_pattern`: a pattern Cascade-v0 plays is a spec
(name, siteswap, dwell ratio, the controller's tunables) plus a registration
(:data:`PATTERNS`); :func:`pattern_spec` finds it or refuses with the reason.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from motion_envs.datasets.juggling import (
    CASCADE_STYLES,
    format_siteswap,
    parse_siteswap,
    siteswap_balls,
    siteswap_flights,
)
from motion_envs.models.juggling._cascade import CascadePattern
from motion_envs.models.juggling._cascade_hand import DEFAULT_TUNABLES, CascadeTunables

__all__ = [
    "PATTERNS",
    "PatternCheck",
    "PatternSpec",
    "ThrowNeed",
    "check_pattern",
    "pattern_reasons",
    "pattern_spec",
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
    """A pattern the cascade juggler plays (:data:`PATTERNS`): its ``name`` (what
    ``pattern=`` takes), its vanilla ``siteswap``, its ``dwell_ratio`` ``D / (V + D)``
    (None: the pattern's training demonstrations' median) with the source of that value
    in ``note``, and the controller's ``tunables`` for it (chosen on training seeds). The
    flight is the juggler's own toss's (fitted on the pattern's SIMULATED
    demonstrations), the tempo Shannon's theorem's."""

    name: str
    siteswap: str
    dwell_ratio: float | None = None
    note: str = ""
    tunables: CascadeTunables = DEFAULT_TUNABLES

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


def pattern_reasons(siteswap: str) -> tuple[str, ...]:
    """Why the cascade juggler cannot play ``siteswap`` whatever its tempo (empty: it
    can): it plays odd cascades (every throw the same odd value, each hand catching the
    other hand's ball) of the ball counts it has demonstrations for
    (:data:`~motion_envs.datasets.juggling.CASCADE_STYLES`). Raises ``ValueError`` for a
    siteswap that is not one."""
    throws = parse_siteswap(siteswap)
    balls = siteswap_balls(throws)
    reasons = []
    if balls % 2 == 0 or set(throws) != {balls}:
        reasons.append(
            "it is not a cascade (every throw the same odd value, each hand catching the "
            "other hand's ball): self-throws, holds, passes and empty beats are not modelled"
        )
    if balls not in CASCADE_STYLES:
        reasons.append(
            f"it has {balls} ball{_s(balls)}; demonstrations exist for "
            f"{', '.join(str(b) for b in sorted(CASCADE_STYLES))}"
        )
    return tuple(reasons)


def register_pattern(spec: PatternSpec) -> PatternSpec:
    """Add ``spec`` to :data:`PATTERNS` (a name is registered once); ``ValueError`` with
    the reasons if the juggler cannot play its siteswap or its dwell ratio is not in
    (0.2, 0.9) or leaves no flight (``N / 2 - r <= 0``)."""
    if not isinstance(spec, PatternSpec):
        raise ValueError(f"register_pattern takes a PatternSpec; got {type(spec).__name__}")
    if spec.name in PATTERNS:
        raise ValueError(f"pattern {spec.name!r} is already registered")
    reasons = pattern_reasons(spec.siteswap)
    if reasons:
        raise ValueError(f"pattern {spec.siteswap!r} cannot be played: " + "; ".join(reasons))
    r = spec.dwell_ratio
    if r is not None and not (isinstance(r, float) and 0.2 < r < 0.9):
        raise ValueError(f"PatternSpec.dwell_ratio must be a float in (0.2, 0.9); got {r!r}")
    if not isinstance(spec.tunables, CascadeTunables):
        raise ValueError(f"PatternSpec.tunables must be a CascadeTunables; got {spec.tunables!r}")
    PATTERNS[spec.name] = spec
    return spec


def pattern_spec(name: str) -> PatternSpec:
    """The registered pattern ``name``; ``ValueError`` naming the registered ones and,
    for a siteswap the juggler cannot play, why."""
    if name in PATTERNS:
        return PATTERNS[name]
    known = ", ".join(repr(p) for p in PATTERNS)
    try:
        reasons = pattern_reasons(name)
    except ValueError as exc:
        raise ValueError(f"pattern must be one of {known}; {exc}") from None
    why = "; ".join(reasons) if reasons else "it is not registered (register_pattern)"
    raise ValueError(f"pattern must be one of {known}; {name!r}: {why}")


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
register_pattern(
    PatternSpec(
        "5",
        "5",
        2.0 / 3.0,
        "the five-ball cascade at a human dwell ratio of 2/3 (J. Kalvan, 'How many objects "
        "can be juggled', 1997: 'My tests show r is usually about 2/3'; his 'Optimal "
        "Juggling', 1996: near 2/3 for cascades of 3, 5, 7 and 9 balls); flight: the "
        "juggler's own toss fitted on the SIMULATED five-ball demonstrations",
    )
)
