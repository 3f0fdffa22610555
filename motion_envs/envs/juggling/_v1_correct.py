"""The eq. 10 catch corrections of :class:`~motion_envs.envs.juggling._v1_batch.V1Batch`
made in its arrays, with the controller's numbers, and given to each episode's controller
at its next event or reset (:meth:`Eq10Corrections.sync`)."""

from __future__ import annotations

from typing import Any

import numpy as np
from numpy.typing import NDArray

from motion_envs.models.juggling import JugglingController, eq10_many, eq10_rows

__all__ = ["Eq10Corrections"]


class Eq10Corrections:
    """The catches' eq. 10 rows and corrections of a batch (:class:`V1Batch` holds the
    arrays: ``_pk``, ``_duration``, ``_glen``, ``_grid``, ``_end``, ``_last``,
    ``_values``, the catch rows ``_c_*`` and coefficients ``_coef``, ``_stale`` and
    ``_pending``)."""

    n: int
    parts: list[Any]
    _dt: float
    _fast: bool
    _pk: NDArray[np.int64]
    _glen: NDArray[np.int64]
    _duration: NDArray[np.float64]
    _values: NDArray[np.float64]
    _grid: NDArray[np.float64]
    _end: NDArray[np.float64]
    _last: NDArray[np.float64]
    _coef: NDArray[np.float64]
    _c_basis: NDArray[np.float64]
    _c_derivative: NDArray[np.float64]
    _c_a: NDArray[np.float64]
    _c_pinv: NDArray[np.float64]
    _stale: NDArray[np.bool_]
    _pending: list[list[tuple[float, float]]]

    def _episode(self, i: int) -> JugglingController:
        episode = self.parts[i].controller.juggler.episode
        assert episode is not None
        return episode  # type: ignore[no-any-return]

    def _load_rows(self, i: int, ep: JugglingController) -> None:
        """Copy the eq. 10 rows of ``ep``'s catch plan (shared by the plans of its
        duration: :func:`~motion_envs.models.juggling.eq10_rows`), its basis on the grid
        and its coefficients into row ``i`` of the arrays the corrections gather from."""
        rows = eq10_rows(ep._tau, ep._basis, ep.duration, self._dt)
        m, nb = ep._basis.shape
        if m > self._c_basis.shape[1] or nb != self._c_basis.shape[2]:
            n, width = self.n, max(m, self._c_basis.shape[1])
            if nb != self._c_basis.shape[2]:  # the first catch (one model: one basis size)
                width = m
            self._c_basis = _wider(self._c_basis, (n, width, nb))
            self._c_derivative = _wider(self._c_derivative, (n, width, nb))
            self._c_a = _wider(self._c_a, (n, width, 3, nb))
            self._c_pinv = _wider(self._c_pinv, (n, width, nb, 3))
            self._coef = _wider(self._coef, (n, nb, 2))
        self._c_basis[i, :m] = ep._basis
        self._c_derivative[i, :m] = rows.derivative
        self._c_a[i, :m] = rows.a
        self._c_pinv[i, :m] = rows.pinv
        self._coef[i] = ep.coefficients

    def _correct(self, rows: NDArray[np.int64], target: NDArray[np.float64]) -> None:
        """The eq. 10 corrections of the catches ``rows`` toward the predicted intercepts
        ``target (r, 2)`` (where :meth:`JugglingController.correct` would re-plan): on the
        catch's rows (:meth:`JugglingController.replan`'s numbers: the same stacked
        products, :func:`~motion_envs.models.juggling.eq10_many`, and the same product of
        the basis and the new coefficients for the rest of the grid), or, where the
        controller has no rows for the step, by the episode's own controller. A
        controller gets the corrections made here at its next event or reset
        (:meth:`sync`), as it gets its step count there."""
        if rows.size == 1:  # the batch of one's case: the same numbers, less indexing
            self._correct_one(int(rows[0]), target)
            return
        dt = self._dt
        k = self._pk[rows]
        duration = self._duration[rows]
        tau1 = k * dt / duration
        glen = self._glen[rows]
        on_rows = (tau1 < 1.0) & (k < glen)  # JugglingController._rows is not None
        times = self._values[rows, 0].tolist()
        if not on_rows.all():
            for j in np.flatnonzero(~on_rows).tolist():
                self._replan(int(rows[j]), int(k[j]), times[j], target[j])
            rows, k, glen = rows[on_rows], k[on_rows], glen[on_rows]
            duration, tau1, target = duration[on_rows], tau1[on_rows], target[on_rows]
            times = [t for t, on in zip(times, on_rows.tolist(), strict=True) if on]
            if not rows.size:
                return
        n, nb = rows.size, self._coef.shape[1]
        derivative = np.empty((n, 1, nb))
        derivative[:, 0] = self._c_derivative[rows, k]
        out = eq10_many(
            derivative,
            self._c_a[rows, k],
            self._c_pinv[rows, k],
            self._coef[rows],
            duration,
            self._grid[rows, k],
            target,
        )
        self._coef[rows] = out
        self._end[rows] = target
        self._stale[rows] = True
        basis, grid, pending = self._c_basis, self._grid, self._pending
        for j, (i, kj, gj, t, tj) in enumerate(
            zip(rows.tolist(), k.tolist(), glen.tolist(), times, tau1.tolist(), strict=True)
        ):
            grid[i, kj + 1 : gj] = basis[i, kj + 1 : gj] @ out[j]  # as _grid_from does
            pending[i].append((t, tj))

    def _correct_one(self, i: int, target: NDArray[np.float64]) -> None:
        """:meth:`_correct` of the one catch ``i`` toward ``target (1, 2)``: its arrays
        gathered as contiguous copies of one row, as the indexing of :meth:`_correct`
        gathers them (the same stacked products)."""
        k, glen = int(self._pk[i]), int(self._glen[i])
        duration = self._duration[i : i + 1].copy()
        tau1 = k * self._dt / float(duration[0])
        time = float(self._values[i, 0])
        if not (tau1 < 1.0 and k < glen):
            self._replan(i, k, time, target[0])
            return
        row = slice(i, i + 1)
        out = eq10_many(
            self._c_derivative[row, k : k + 1].copy(),
            self._c_a[row, k].copy(),
            self._c_pinv[row, k].copy(),
            self._coef[row].copy(),
            duration,
            self._grid[row, k].copy(),
            target,
        )
        self._coef[i], self._end[i], self._stale[i] = out[0], target[0], True
        self._grid[i, k + 1 : glen] = self._c_basis[i, k + 1 : glen] @ out[0]
        self._pending[i].append((time, tau1))

    def _replan(self, i: int, k: int, time: float, target: NDArray[np.float64]) -> None:
        """Catch ``i``'s correction at step ``k`` by its own controller (no rows here)."""
        self.sync(i)
        ep = self._episode(i)
        ep.k = k
        ep.replan(time, target.copy())
        self._grid[i, k + 1 : self._glen[i]] = ep.grid[k + 1 :]
        self._end[i] = ep.end
        self._coef[i] = ep.coefficients

    def sync(self, i: int) -> None:
        """Give episode ``i``'s controller the corrections made here since its last event
        (its coefficients, end, grid and their record) and its step count."""
        if not self._fast:
            return
        ep = self._episode(i)
        ep.k = int(self._pk[i])
        ep._last = [self._last[i, 0].copy(), self._last[i, 1].copy()]
        if not self._stale[i]:
            return
        self._stale[i] = False
        ep.coefficients = self._coef[i].copy()
        ep.end = self._end[i].copy()
        ep.grid[:] = self._grid[i, : self._glen[i]]
        ep.corrections.extend(self._pending[i])
        self._pending[i].clear()


def _wider(array: NDArray[np.float64], shape: tuple[int, ...]) -> NDArray[np.float64]:
    """``array`` in a zero array of ``shape``, its old content kept where it fits (the
    basis size axis only grows from the placeholder's 1)."""
    out = np.zeros(shape)
    if array.shape[2:] == shape[2:]:
        out[:, : array.shape[1]] = array
    return out
