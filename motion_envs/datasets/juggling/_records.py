"""Juggling recordings: phase examples, continuous recordings, demonstration sets, splits
(of the demonstrations by cycle, and of the environments' episodes by reset seed)."""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import NDArray

from motion_envs._typing import FloatArray
from motion_envs.datasets.juggling._paths import resample_path
from motion_envs.datasets.juggling._task import PHASES, JugglingTask

__all__ = [
    "MIN_SPLIT_CYCLES",
    "SIMULATED_LABEL",
    "JugglingDemos",
    "JugglingRecording",
    "PhaseSegment",
    "split_cycles",
]

#: The label every generated set carries in code, CLI output, results and plots.
SIMULATED_LABEL = "SIMULATED (seeded model of a person; not human recordings)"

#: Complete cycles :func:`split_cycles` needs: the juggler's fit regresses each phase's
#: coefficients on 4 boundary conditions and an intercept (5 unknowns) and needs 6
#: training cycles, one to spare; the default split holds a quarter out for testing, so
#: 8 cycles leave 6 to fit and 2 to test.
MIN_SPLIT_CYCLES = 8
#: First reset seed of each split's episodes of the juggling environments: episode ``i`` of
#: ``split`` is reset with seed ``SPLIT_SEEDS[split] + i`` (:func:`episode_seeds`), so
#: training, validation and test episodes never share a seed (fewer than 10^9 per split).
SPLIT_SEEDS: Mapping[str, int] = {
    "train": 0,
    "val": 1_000_000_000,
    "test": 2_000_000_000,
}
#: Episodes a split holds at most (its seeds stop before the next split's first).
MAX_SPLIT_EPISODES = 1_000_000_000


@dataclass(frozen=True)
class PhaseSegment:
    """One example of a phase: samples ``start .. stop`` (inclusive) of a recording."""

    phase: str
    times: FloatArray  # (n,), starting at the phase start
    positions: FloatArray  # (n, 2)
    recording: int
    cycle: int

    @property
    def duration(self) -> float:
        """``t_last - t_first`` in s."""
        return float(self.times[-1] - self.times[0])

    def resampled(self, n_points: int) -> FloatArray:
        """The positions at ``n_points`` equally spaced points of normalised time
        (:func:`resample_path`)."""
        return resample_path(self.times, self.positions, n_points)


@dataclass(frozen=True)
class JugglingRecording:
    """One continuous recording: hand ``(K, 2)``, optional ball ``(K, 2)`` and labels."""

    name: str
    t: FloatArray
    hand: FloatArray
    ball: FloatArray | None = None
    phase: NDArray[np.str_] | None = None
    person: str = ""

    def segments(self, index: int = 0, toss_to_top: bool = False) -> list[PhaseSegment]:
        """Every labelled phase example: a run of one label plus the next phase's first
        sample (the shared boundary; the last run ends at the last sample). The cycle
        counter advances at each toss; runs before the first toss are skipped.

        ``toss_to_top``: a toss example runs on past the release to the hand's turning
        point, the first sample where the vertical velocity over 5 samples,
        ``(z_k - z_{k-5}) / (5 dt)``, is <= 0 (the user "inverts the motion"; the eq. 9
        plan ends there).
        """
        if self.phase is None:
            raise ValueError(f"recording {self.name!r} has no phase labels; segment it first")
        lab = self.phase
        change = np.flatnonzero(lab[1:] != lab[:-1]) + 1
        starts = np.concatenate([[0], change])
        stops = np.concatenate([change, [len(lab) - 1]])
        out, cycle = [], -1
        for s, e in zip(starts, stops, strict=True):
            name = str(lab[s])
            if name == "toss":
                cycle += 1
            if name == "toss" and toss_to_top:
                z = self.hand[:, 1]
                k = np.arange(max(e, 5), len(z))
                down = np.flatnonzero(z[k] - z[k - 5] <= 0)
                e = int(k[down[0]]) if down.size else e
            if name in PHASES and cycle >= 0 and e - s >= 4:
                out.append(
                    PhaseSegment(
                        name, self.t[s : e + 1] - self.t[s], self.hand[s : e + 1], index, cycle
                    )
                )
        return out


@dataclass(frozen=True)
class JugglingDemos:
    """Juggling demonstrations: recordings (one per person or session) and their origin."""

    name: str
    recordings: tuple[JugglingRecording, ...]
    simulated: bool
    task: JugglingTask = field(default_factory=JugglingTask)

    def segments(self, phase: str | None = None, toss_to_top: bool = False) -> list[PhaseSegment]:
        """All phase examples (of ``phase`` only, if given), recording by recording."""
        if phase is not None and phase not in PHASES:
            raise ValueError(f"phase must be one of {PHASES}; got {phase!r}")
        out = [s for i, r in enumerate(self.recordings) for s in r.segments(i, toss_to_top)]
        return [s for s in out if phase is None or s.phase == phase]

    def cycles(self) -> list[tuple[int, int]]:
        """``(recording, cycle)`` of every cycle that has all four phases."""
        have: dict[tuple[int, int], set[str]] = {}
        for s in self.segments():
            have.setdefault((s.recording, s.cycle), set()).add(s.phase)
        return sorted(k for k, v in have.items() if v == set(PHASES))

    def label(self) -> str:
        """``name`` with ``SIMULATED`` when the data are simulated."""
        return f"{self.name} [{SIMULATED_LABEL}]" if self.simulated else self.name


def split_cycles(
    demos: JugglingDemos, test_fraction: float, seed: int
) -> tuple[set[tuple[int, int]], set[tuple[int, int]]]:
    """Train and test ``(recording, cycle)`` sets: a seeded split by demonstration."""
    if not 0 < test_fraction < 1:
        raise ValueError(f"test_fraction must be in (0, 1); got {test_fraction}")
    cycles = demos.cycles()
    if len(cycles) < MIN_SPLIT_CYCLES:
        raise ValueError(
            f"{demos.name}: {len(cycles)} complete cycle(s); at least {MIN_SPLIT_CYCLES} are "
            "needed: the default split holds a quarter out for testing and the juggler's "
            "fit needs 6 training cycles (each phase regressed on 4 boundary conditions "
            "and an intercept, with one cycle to spare)"
        )
    order = np.random.default_rng(seed).permutation(len(cycles))
    n_test = max(1, round(test_fraction * len(cycles)))
    test = {cycles[i] for i in order[:n_test]}
    return set(cycles) - test, test


def episode_seeds(split: str, n: int) -> NDArray[np.int64]:
    """The reset seeds of the first ``n`` episodes of ``split`` (:data:`SPLIT_SEEDS`)."""
    if split not in SPLIT_SEEDS:
        raise ValueError(f"split must be one of {sorted(SPLIT_SEEDS)}; got {split!r}")
    if not 0 <= n <= MAX_SPLIT_EPISODES:
        raise ValueError(f"episodes must be in [0, {MAX_SPLIT_EPISODES}]; got {n}")
    return SPLIT_SEEDS[split] + np.arange(n, dtype=np.int64)
