"""Variable-length trajectories stored flat, and the common normalised-time grid.

The paper's criteria live on the uniform grid ``tau_k = k / (n_points - 1)``,
``k = 0 .. n_points - 1`` with ``n_points = 50``. Orientation trajectories of
different lengths are packed into one flat array (:class:`RaggedTrajectories`) so that
every step of the pipeline is one vectorised numpy call.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from motion_envs._typing import FloatArray
from motion_envs.geometry import quaternion as quat

if TYPE_CHECKING:
    import pandas as pd

__all__ = [
    "DEFAULT_N_POINTS",
    "MIN_SAMPLES",
    "RaggedTrajectories",
    "check_n_points",
    "normalised_grid",
]

#: Number of points on the common normalised-time grid (the paper's 50).
DEFAULT_N_POINTS = 50
#: Fewest samples accepted for one trajectory (orientation and position CSVs).
MIN_SAMPLES = 5


def check_n_points(n_points: Any) -> int:
    """``n_points`` as an ``int``: the size of a model's normalised-time grid is an integer
    >= 3 (``ValueError`` else)."""
    if isinstance(n_points, bool) or not isinstance(n_points, (int, np.integer)) or n_points < 3:
        raise ValueError(f"n_points must be an integer >= 3; got {n_points!r}")
    return int(n_points)


def normalised_grid(n_points: int = DEFAULT_N_POINTS) -> FloatArray:
    """The uniform normalised-time grid ``tau_k = k / (n_points - 1)``, ``k = 0 .. n_points-1``."""
    if n_points < 2:
        raise ValueError(f"n_points must be >= 2; got {n_points}")
    return np.linspace(0.0, 1.0, n_points)


@dataclass(frozen=True)
class RaggedTrajectories:
    """Variable-length orientation trajectories stored flat.

    Attributes
    ----------
    quaternions:
        ``(N_total, 4)`` unit quaternions ``(w, x, y, z)``, made sign-continuous within
        each trajectory.
    tau:
        ``(N_total,)`` normalised time in ``[0, 1]`` within each trajectory.
    offsets:
        ``(L + 1,)`` start index of each trajectory; trajectory ``l`` is
        ``offsets[l]:offsets[l + 1]``.
    durations:
        ``(L,)`` clock duration ``t_n - t_0`` in the time unit given.
    """

    quaternions: FloatArray
    tau: FloatArray
    offsets: NDArray[np.int64]
    durations: FloatArray

    @property
    def n_trajectories(self) -> int:
        return int(self.offsets.size - 1)

    def __len__(self) -> int:
        return self.n_trajectories

    def __getitem__(self, key: int | slice | ArrayLike) -> RaggedTrajectories:
        """The trajectories selected by ``key``: an index, a slice, integer indices (any
        order, repeats allowed, negative from the end) or a boolean mask ``(L,)``.

        Always returns a :class:`RaggedTrajectories` (an integer gives one trajectory).
        """
        n = self.n_trajectories
        if isinstance(key, slice):
            idx = np.arange(n)[key]
        else:
            k = np.asarray(key)
            if k.dtype == np.bool_:
                if k.shape != (n,):
                    raise IndexError(f"a boolean mask must have shape ({n},); got {k.shape}")
                idx = np.flatnonzero(k)
            elif k.dtype.kind in "iu" and k.ndim <= 1:
                idx = np.atleast_1d(k).astype(np.int64)
                if np.any(idx >= n) or np.any(idx < -n):
                    raise IndexError(f"trajectory index out of range for {n} trajectories")
                idx = np.where(idx < 0, idx + n, idx)
            else:
                raise IndexError(
                    f"select trajectories with an int, a slice, integer indices or a boolean "
                    f"mask; got {key!r}"
                )
        lengths = self.lengths[idx]
        offsets = np.concatenate([[0], np.cumsum(lengths)]).astype(np.int64)
        # sample j of the selection is sample (j - offsets[l]) of trajectory idx[l]
        owner = np.repeat(np.arange(idx.size), lengths)
        samples = np.arange(int(offsets[-1])) - offsets[owner] + self.offsets[idx][owner]
        return RaggedTrajectories(
            quaternions=self.quaternions[samples],
            tau=self.tau[samples],
            offsets=offsets,
            durations=self.durations[idx],
        )

    @property
    def lengths(self) -> NDArray[np.int64]:
        return np.diff(self.offsets)

    @property
    def starts(self) -> FloatArray:
        """``(L, 4)`` first orientation of each trajectory."""
        return self.quaternions[self.offsets[:-1]]

    @property
    def ends(self) -> FloatArray:
        """``(L, 4)`` last orientation of each trajectory (sign-continuous with the start)."""
        return self.quaternions[self.offsets[1:] - 1]

    def to_frame(self) -> pd.DataFrame:
        """One row per sample: ``trajectory``, ``tau``, ``t`` (``tau * duration``),
        ``duration``, ``qw``, ``qx``, ``qy``, ``qz`` (a :class:`pandas.DataFrame`)."""
        import pandas as pd

        idx = self.trajectory_index()
        q = self.quaternions
        return pd.DataFrame(
            {
                "trajectory": idx,
                "tau": self.tau,
                "t": self.tau * self.durations[idx],
                "duration": self.durations[idx],
                "qw": q[:, 0],
                "qx": q[:, 1],
                "qy": q[:, 2],
                "qz": q[:, 3],
            }
        )

    def trajectory_index(self) -> NDArray[np.int64]:
        """``(N_total,)`` index ``l`` of the trajectory each sample belongs to."""
        return np.repeat(np.arange(self.n_trajectories), self.lengths)

    def global_abscissae(self, grid: ArrayLike) -> tuple[FloatArray, FloatArray]:
        """Samples' ``tau + 2 l`` (increasing across trajectories) and the grid's, ``(L * n,)``.

        The offset ``2 l`` keeps the concatenated time axis increasing, so one
        ``np.interp`` or ``np.searchsorted`` serves every trajectory at once.
        """
        g = np.asarray(grid, dtype=np.float64)
        x = self.tau + 2.0 * self.trajectory_index()
        xq = (g[None, :] + 2.0 * np.arange(self.n_trajectories)[:, None]).ravel()
        return x, xq

    @classmethod
    def from_sequences(
        cls,
        quaternions: Sequence[ArrayLike],
        times: Sequence[ArrayLike],
        min_samples: int = MIN_SAMPLES,
    ) -> RaggedTrajectories:
        """Validate and pack trajectories given as lists of ``(n_l, 4)`` and ``(n_l,)`` arrays.

        Raises ``ValueError`` naming the trajectory for: a length mismatch, fewer than
        ``min_samples`` samples, NaN, non-unit quaternions, or times that do not strictly
        increase.
        """
        if len(quaternions) != len(times):
            raise ValueError(
                f"quaternions and times must have the same number of trajectories; "
                f"got {len(quaternions)} and {len(times)}"
            )
        if len(quaternions) == 0:
            raise ValueError("quaternions must contain at least one trajectory")
        qs, taus, lengths, durations = [], [], [], []
        for l, (q_in, t_in) in enumerate(zip(quaternions, times, strict=True)):
            q = quat.as_unit(q_in, name=f"quaternions[{l}]")
            t = np.asarray(t_in, dtype=np.float64)
            if q.ndim != 2 or t.ndim != 1 or t.shape[0] != q.shape[0]:
                raise ValueError(
                    f"trajectory {l}: quaternions must be (n, 4) and times (n,); got "
                    f"{q.shape} and {t.shape}"
                )
            if q.shape[0] < min_samples:
                raise ValueError(
                    f"trajectory {l}: has {q.shape[0]} samples, at least {min_samples} needed"
                )
            if not np.all(np.isfinite(t)):
                raise ValueError(f"times[{l}] contains NaN or infinite values")
            if np.any(np.diff(t) <= 0.0):
                raise ValueError(f"times[{l}] must be strictly increasing")
            qs.append(quat.make_continuous(q))
            duration = t[-1] - t[0]
            taus.append((t - t[0]) / duration)
            lengths.append(q.shape[0])
            durations.append(duration)
        offsets = np.concatenate([[0], np.cumsum(lengths)]).astype(np.int64)
        return cls(
            quaternions=np.concatenate(qs),
            tau=np.concatenate(taus),
            offsets=offsets,
            durations=np.asarray(durations, dtype=np.float64),
        )
