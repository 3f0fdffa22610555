"""Juggling task constants and states shared by the pure-model world and the MuJoCo scene.

Written on branch h9-juggle-env exactly as the contract (notes/JUGGLING-CONTRACT.md) fixes
it, so that the scene can be built before h9-juggle-model commits its own version (which
replaces this file at merge). SI units, the vertical plane ``(x, z)``.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

__all__ = ["JugglingNoise", "JugglingState", "JugglingTask"]


@dataclass(frozen=True)
class JugglingTask:
    """Every physical constant of the juggling task in one place (SI units, plane x, z)."""

    gravity: float = 2.0  # m/s^2 (the paper's virtual world; 9.81 for real gravity)
    dt: float = 1 / 200  # control period, s (the paper's 200 Hz tracker)
    ball_radius: float = 0.035
    ball_mass: float = 0.13
    catch_radius: float = 0.06  # hand centre to ball centre distance that counts as a catch
    toss_threshold: float = 5.0  # m/s^2: vertical hand acceleration below -threshold releases
    floor_z: float = 0.0  # ball centre below this = drop (ends the cycle)


@dataclass(frozen=True)
class JugglingState:
    """The world after one step (or at reset)."""

    time: float
    hand_pos: NDArray[np.float64]  # (2,) x, z
    hand_vel: NDArray[np.float64]  # (2,)
    ball_pos: NDArray[np.float64]  # (2,)
    ball_vel: NDArray[np.float64]  # (2,)
    held: bool
    released: bool  # a toss happened during the last step
    caught: bool  # a catch happened during the last step
    dropped: bool  # the ball went below floor_z


@dataclass(frozen=True)
class JugglingNoise:
    """Perturbations of a run."""

    release: float = 0.0  # relative std of the release velocity (0.05 = 5 %)
    tracking: float = 0.0  # std (m) of the hand position the controller observes
