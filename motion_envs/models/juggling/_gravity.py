"""The gravities Juggling-v1 and Cascade-v0 can be built at, from the task's timing.

Both environments fit their juggler on SIMULATED demonstrations generated at the env's
gravity. The demonstrations keep their lengths and scale their times with the fall time,
``T ~ sqrt(L / g)``, on the task's fixed grid ``dt = 1/200`` s, so at gravity ``g`` a phase
of ``n`` samples at the paper's gravity ``g0`` holds about ``n sqrt(g0 / g)`` samples:

* too strong a gravity leaves the shortest phase too few samples to determine its
  ``V1_N_SINES`` sine coefficients (Cascade-v0 at 100 m/s^2: 5 samples for 4 sines);
* too weak a gravity makes the demonstrations, the fit and an episode grow without
  bound (1e-6 m/s^2: a thousand times the samples; ``gym.make`` never returned).

:func:`gravity_range` turns the two limits into a range per world: the shortest phase
keeps at least :data:`MIN_PHASE_SAMPLES` samples and the demonstrations at most
:data:`MAX_DEMO_SAMPLES`; :func:`check_gravity` refuses a gravity outside it in one line.
The sample counts at ``g0`` (:data:`TIMING_AT_PAPER_GRAVITY`) are the demonstrations'
own, recomputed from them by ``tests/test_juggling_gravity.py``.
"""

from __future__ import annotations

import math

from motion_envs.models.juggling._fit import PAPER_GRAVITY, V1_N_SINES

__all__ = [
    "MAX_DEMO_SAMPLES",
    "MIN_PHASE_SAMPLES",
    "TIMING_AT_PAPER_GRAVITY",
    "check_gravity",
    "gravity_range",
]

#: Fewest samples of a phase of the demonstrations a fit accepts: twice the sine
#: coefficients plus one (a phase's end points are fixed), so each is over-determined.
MIN_PHASE_SAMPLES = 2 * (V1_N_SINES + 1)
#: Most samples of the SIMULATED demonstrations one environment is fitted on (about a
#: second of generation and fit, tens of MB).
MAX_DEMO_SAMPLES = 1_000_000
#: ``world -> (shortest phase, all samples)`` of the SIMULATED demonstrations at the
#: paper's gravity (``PAPER_GRAVITY``): Juggling-v1's (one hand, ``load_demonstrations``)
#: and Cascade-v0's (two hands, two persons, ``generate_cascade_demonstrations``).
TIMING_AT_PAPER_GRAVITY: dict[str, tuple[int, int]] = {
    "Juggling-v1": (145, 35_716),
    "Cascade-v0": (60, 89_444),
}


def gravity_range(world: str) -> tuple[float, float]:
    """``(low, high)`` gravity (m/s^2) at which ``world`` (``"Juggling-v1"`` or
    ``"Cascade-v0"``) can be built: ``high`` keeps the shortest phase at
    :data:`MIN_PHASE_SAMPLES` samples, ``low`` the demonstrations at
    :data:`MAX_DEMO_SAMPLES` (samples scale as ``sqrt(g0 / g)``)."""
    shortest, total = TIMING_AT_PAPER_GRAVITY[world]
    low = PAPER_GRAVITY * (total / MAX_DEMO_SAMPLES) ** 2
    high = PAPER_GRAVITY * (shortest / MIN_PHASE_SAMPLES) ** 2
    return low, high


def check_gravity(gravity: float, world: str) -> float:
    """``gravity`` when ``world`` can be built at it (:func:`gravity_range`), else a
    one-line ``ValueError`` with the reason."""
    low, high = gravity_range(world)
    g = float(gravity)
    if not math.isfinite(g) or g < low:
        raise ValueError(
            f"gravity {g:g} m/s^2 is too weak for {world}: its demonstrations would exceed "
            f"{MAX_DEMO_SAMPLES} samples (times scale as sqrt(1/g)); expected {low:.3g} to "
            f"{high:.3g} m/s^2"
        )
    if g > high:
        raise ValueError(
            f"gravity {g:g} m/s^2 is too strong for {world}: its shortest phase would last "
            f"fewer than {MIN_PHASE_SAMPLES} samples of the 5 ms grid, too few for "
            f"{V1_N_SINES} sine coefficients; expected {low:.3g} to {high:.3g} m/s^2"
        )
    return g
