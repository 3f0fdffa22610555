"""Vanilla siteswaps: the notation of juggling patterns, their validity, ball count and
the flight of each throw from the pattern's tempo (Shannon's theorem, throw by throw).

A vanilla siteswap is a periodic sequence of throw values ``t_0 .. t_{p-1}`` (one throw
per beat, the hands throwing in turn): the ball thrown on beat ``i`` is thrown again on
beat ``i + t_i``. A throw of 0 is an empty beat; an odd throw crosses to the other hand,
an even one comes back to the thrower. Written with one character per throw, ``0-9``
then ``a-z`` for 10-35 (``"441"``, ``"5"``, ``"b97531"``).

Validity (:func:`siteswap_balls`): no two balls may land on the same beat, i.e. the
landing beats ``(i + t_i) mod p`` are all distinct (the permutation test); then the
number of balls is the average throw ``sum(t) / p`` (the average theorem: a valid
sequence always has an integer average; a non-integer average fails the permutation
test too).

Timing (:func:`siteswap_flights`): with the beat ``b`` (time between two throws) and the
dwell ``D`` (time a ball spends in a hand, from catch to throw), a ball thrown with value
``h`` is thrown again ``h b`` later, of which ``D`` in the catching hand, so its flight is

    F_h = h b - D.

For the three-ball cascade (``h = 3``, two hands, ``b = C / 2``, ``D = r C``) this is
Shannon's ``(F + D) H = (V + D) N``: ``F = C (N / H - r)``
(:func:`~motion_envs.datasets.juggling.cascade_timing`). A throw with ``F_h <= 0`` cannot
fly: its hand would have to throw before it caught.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

__all__ = [
    "MAX_SITESWAP_PERIOD",
    "SITESWAP_DIGITS",
    "format_siteswap",
    "parse_siteswap",
    "siteswap_balls",
    "siteswap_flights",
]

#: The characters of throw values 0-35, in order.
SITESWAP_DIGITS = "0123456789abcdefghijklmnopqrstuvwxyz"
#: Most throws of a siteswap (its period); a longer text is refused before it is read
#: further (the patterns people juggle have periods of a few throws; a result folder is
#: named after the pattern and a file name holds at most 255 bytes).
MAX_SITESWAP_PERIOD = 64


def parse_siteswap(text: str) -> tuple[int, ...]:
    """The throw values of a vanilla siteswap written as ``text`` (``"441"`` ->
        ``(4, 4, 1)``; letters ``a-z`` are 10-35, case-insensitive; surrounding spaces
        ignored). Raises ``ValueError`` naming the first character that is not a throw, or for
    more than :data:`MAX_SITESWAP_PERIOD` throws.
        Validity is :func:`siteswap_balls`'s."""
    if not isinstance(text, str):
        raise ValueError(f"siteswap must be a string; got {type(text).__name__}")
    value = text.strip().lower()
    if not value:
        raise ValueError("siteswap must not be empty")
    if len(value) > MAX_SITESWAP_PERIOD:
        raise ValueError(
            f"siteswap of {len(value)} throws; at most {MAX_SITESWAP_PERIOD} (its period)"
        )
    throws = []
    for i, ch in enumerate(value):
        h = SITESWAP_DIGITS.find(ch)
        if h < 0:
            raise ValueError(
                f"siteswap {text!r}: character {i + 1} ({ch!r}) is not a throw (0-9, a-z)"
            )
        throws.append(h)
    return tuple(throws)


def siteswap_balls(throws: Sequence[int]) -> int:
    """The number of balls of the valid vanilla siteswap ``throws`` (the average throw).

    Raises ``ValueError`` if ``throws`` is empty, holds a negative value, two of its balls
    land on the same beat (the permutation test; the message names the two throws) or no
    ball is thrown."""
    t = [int(h) for h in throws]
    if not t:
        raise ValueError("siteswap must have at least one throw")
    if any(h < 0 for h in t):
        raise ValueError(f"siteswap {_text(t)}: throw values must be >= 0")
    p = len(t)
    landed: dict[int, int] = {}
    for i, h in enumerate(t):
        beat = (i + h) % p
        if beat in landed:
            j = landed[beat]
            raise ValueError(
                f"siteswap {_text(t)} is not valid: throws {j + 1} ({t[j]}) and {i + 1} "
                f"({h}) land on the same beat"
            )
        landed[beat] = i
    balls = sum(t) // p  # an integer: the landing beats are a permutation
    if balls == 0:
        raise ValueError(f"siteswap {_text(t)} throws no ball")
    return balls


def siteswap_flights(throws: Sequence[int], beat: float, dwell: float) -> tuple[float, ...]:
    """The flight time (s) ``F_h = h b - D`` of each throw of ``throws`` for the beat
    ``b`` and the dwell ``D`` (s); 0.0 for a throw of 0 (no ball). A flight ``<= 0`` means
    the throw cannot be made at that tempo (module docstring). Raises ``ValueError``
    unless ``b > 0`` and ``0 <= D`` (finite)."""
    if not (math.isfinite(beat) and beat > 0):
        raise ValueError(f"beat must be finite and > 0; got {beat!r}")
    if not (math.isfinite(dwell) and dwell >= 0):
        raise ValueError(f"dwell must be finite and >= 0; got {dwell!r}")
    return tuple(0.0 if h == 0 else h * beat - dwell for h in throws)


def format_siteswap(throws: Sequence[int]) -> str:
    """The notation of ``throws`` (``(4, 4, 1)`` -> ``"441"``; the inverse of
    :func:`parse_siteswap` on its lower-case output); a value outside 0-35 is written
    ``[h]``."""
    return "".join(SITESWAP_DIGITS[h] if 0 <= h < 36 else f"[{h}]" for h in throws)


def _text(throws: Sequence[int]) -> str:
    return repr(format_siteswap(throws))
