"""Peer models for the position benchmark: DMP and ProMP from ``movement_primitives``.

Both are used with the same time normalisation as the sine-series model: every
demonstration is resampled to ``K`` points on ``tau = t / T in [0, 1]`` and the peers run
with execution time 1; their output is read on the same grid.

* :class:`DMPPeer`: one ``movement_primitives.dmp.DMP`` per training demonstration
  (``imitate``), forcing-term weights averaged over the demonstrations (they share the
  canonical system, so the average is the least-squares fit to the pooled forces);
  prediction sets ``start_y``/``goal_y`` to the requested start and goal and runs
  ``open_loop``. A DMP converges to its goal but need not reach it exactly at ``tau = 1``.
* :class:`ProMPPeer`: ``movement_primitives.promp.ProMP.imitate`` on all demonstrations,
  conditioned (``condition_position``) on the start at ``tau = 0`` and the goal at
  ``tau = 1``; the prediction is the conditioned mean trajectory.

``movement_primitives`` is an optional dependency (extra ``peers``);
:func:`peers_available` says whether it is installed.
"""

from __future__ import annotations

import importlib

import numpy as np
from numpy.typing import ArrayLike

from motion_envs._typing import FloatArray

__all__ = ["DMPPeer", "ProMPPeer", "peers_available", "peers_missing_reason"]


def peers_missing_reason() -> str | None:
    """Why the peers cannot run (``None`` when ``movement_primitives`` imports fine)."""
    try:
        importlib.import_module("movement_primitives.dmp")
        importlib.import_module("movement_primitives.promp")
    except ImportError as exc:
        return f"{exc} (pip install 'motion-envs[peers]')"
    return None


def peers_available() -> bool:
    """True when ``movement_primitives`` (and what its DMP module imports) is importable."""
    return peers_missing_reason() is None


def _demos(demos: ArrayLike) -> FloatArray:
    y = np.asarray(demos, dtype=np.float64)
    if y.ndim != 3 or y.shape[1] < 3:
        raise ValueError(f"demos must be (n, K, D) on a common tau grid; got shape {y.shape}")
    if not np.all(np.isfinite(y)):
        raise ValueError("demos contains NaN or infinite values")
    return y


class DMPPeer:
    """DMP with forcing-term weights averaged over demonstrations (see module docstring)."""

    def __init__(self, n_weights_per_dim: int = 10) -> None:
        self.n_weights_per_dim = n_weights_per_dim

    def fit(self, demos: ArrayLike) -> DMPPeer:
        """Fit on ``(n, K, D)`` demonstrations sampled at ``tau_k = k / (K - 1)``."""
        from movement_primitives.dmp import DMP

        y = _demos(demos)
        _, k, d = y.shape
        tau = np.linspace(0.0, 1.0, k)
        weights = []
        for demo in y:
            dmp = DMP(
                n_dims=d,
                execution_time=1.0,
                dt=1.0 / (k - 1),
                n_weights_per_dim=self.n_weights_per_dim,
            )
            dmp.imitate(tau, demo)
            weights.append(dmp.get_weights())
        self.dmp_ = dmp
        self.dmp_.set_weights(np.mean(weights, axis=0))
        self.n_points_ = k
        return self

    def predict(self, start: ArrayLike, goal: ArrayLike) -> FloatArray:
        """``(K, D)`` trajectory from ``start`` to (towards) ``goal`` on the fitted grid."""
        self.dmp_.configure(
            start_y=np.asarray(start, dtype=np.float64), goal_y=np.asarray(goal, dtype=np.float64)
        )
        t, y = self.dmp_.open_loop()
        tau = np.linspace(0.0, 1.0, self.n_points_)
        return np.column_stack([np.interp(tau, t, y[:, j]) for j in range(y.shape[1])])


class ProMPPeer:
    """ProMP conditioned on start (``tau = 0``) and goal (``tau = 1``)."""

    def __init__(self, n_weights_per_dim: int = 10) -> None:
        self.n_weights_per_dim = n_weights_per_dim

    def fit(self, demos: ArrayLike) -> ProMPPeer:
        """Fit on ``(n, K, D)`` demonstrations sampled at ``tau_k = k / (K - 1)``."""
        from movement_primitives.promp import ProMP

        y = _demos(demos)
        n, k, d = y.shape
        self.tau_ = np.linspace(0.0, 1.0, k)
        self.promp_ = ProMP(n_dims=d, n_weights_per_dim=self.n_weights_per_dim)
        self.promp_.imitate(np.tile(self.tau_, (n, 1)), y)
        return self

    def predict(self, start: ArrayLike, goal: ArrayLike) -> FloatArray:
        """``(K, D)`` conditioned mean trajectory on the fitted grid."""
        cond = self.promp_.condition_position(np.asarray(start, dtype=np.float64), t=0.0, t_max=1.0)
        cond = cond.condition_position(np.asarray(goal, dtype=np.float64), t=1.0, t_max=1.0)
        return np.asarray(cond.mean_trajectory(self.tau_), dtype=np.float64)
