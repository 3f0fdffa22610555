"""Figures of one's own fitted models: fit against data, with the criterion marked.

:func:`plot_fit` draws the :class:`~motion_envs.models.fit_errors.FitErrors` of a
position model (``plot_fit(position_fit_errors(model, Ys, Q, rate=120))``) or of an
orientation model (``plot_fit(orientation_fit_errors(model, qs, rate=120))``). It
returns a matplotlib :class:`~matplotlib.figure.Figure` drawn on an Agg
canvas (no pyplot, no global state, no backend switch); save it with
:func:`motion_envs._io.save_figure` (atomic) or ``fig.savefig``. matplotlib is imported
inside the functions, so importing :mod:`motion_envs.models` stays cheap.

Layout: one panel per coordinate (``x, y, z`` for positions, ``w, x, y, z`` for
quaternions) with every recording (solid) and its fit (dashed) against time since the
recording's start, and a last panel with the error ``e_l(t)`` of every recording
(:mod:`motion_envs.models.fit_errors`). The criterion ``median_l max_t e_l(t)`` is
marked: a dot at each recording's maximum error (time, value), the recording whose
maximum is the median drawn thick (data, fit and error) with a star at its maximum and
a vertical line at its time in every panel, and a horizontal line at the criterion.
Artists carry ``gid`` s (``data-l-d``, ``fit-l-d``, ``error-l``, ``max-errors``,
``criterion``, ``criterion-time``, ``median-max``) so that they can be found.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import TYPE_CHECKING

from motion_envs.models.fit_errors import FitErrors

if TYPE_CHECKING:
    from matplotlib.figure import Figure

__all__ = ["plot_fit"]

_HIGHLIGHT = "C3"


def plot_fit(
    errors: FitErrors,
    *,
    coordinates: Sequence[str] | None = None,
    title: str | None = None,
    width: float = 7.0,
    panel_height: float = 1.8,
) -> Figure:
    """Fit vs data of every recording in ``errors``, with the criterion marked (module
    docstring). ``coordinates`` names the panels (default ``x, y, z`` / ``w, x, y, z``,
    else ``y0 ..``)."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    dims = errors.data[0].shape[1]
    if coordinates is None:
        default = {3: ["x", "y", "z"], 4: ["w", "x", "y", "z"]}
        coordinates = default.get(dims, [f"y{d}" for d in range(dims)])
    names = list(coordinates)
    if len(names) != dims:
        raise ValueError(f"coordinates must name the {dims} coordinates; got {names}")
    fig = Figure(figsize=(width, panel_height * (dims + 1)), layout="constrained")
    FigureCanvasAgg(fig)
    axes = fig.subplots(dims + 1, 1, sharex=True)
    med = errors.median_trajectory
    t_med = float(errors.max_error_times[med])
    for ax, d in zip(axes[:-1], range(dims), strict=True):
        for i, (t, y, f) in enumerate(zip(errors.times, errors.data, errors.fit, strict=True)):
            hi = i == med
            style = {"color": _HIGHLIGHT, "lw": 2.0, "zorder": 3} if hi else {
                "color": "0.6", "lw": 0.8, "alpha": 0.7}  # fmt: skip
            (line,) = ax.plot(t, y[:, d], **style, label="data (median trajectory)" if hi else None)
            line.set_gid(f"data-{i}-{d}")
            (line,) = ax.plot(t, f[:, d], ls="--", **style, label="fit" if hi else None)
            line.set_gid(f"fit-{i}-{d}")
        ax.axvline(t_med, color=_HIGHLIGHT, lw=0.8, ls=":").set_gid("criterion-time")
        ax.set_ylabel(names[d])
    axes[0].legend(loc="best", fontsize="small")
    ax = axes[-1]
    for i, (t, e) in enumerate(zip(errors.times, errors.errors, strict=True)):
        hi = i == med
        (line,) = ax.plot(t, e, color=_HIGHLIGHT if hi else "0.6", lw=2.0 if hi else 0.8)
        line.set_gid(f"error-{i}")
    ax.scatter(
        errors.max_error_times, errors.max_errors, s=14, color="k", zorder=4,
        label="max over time",
    ).set_gid("max-errors")  # fmt: skip
    ax.scatter(
        [t_med], [errors.max_errors[med]], s=120, marker="*", color=_HIGHLIGHT, zorder=5,
        label=f"median trajectory ({med})",
    ).set_gid("median-max")  # fmt: skip
    ax.axhline(
        errors.criterion, color=_HIGHLIGHT, lw=1.0, ls="--",
        label=f"criterion = {errors.criterion:.3g} {errors.unit}",
    ).set_gid("criterion")  # fmt: skip
    ax.set_ylabel(f"error ({errors.unit})")
    ax.set_xlabel("time since the start (s)")
    ax.legend(loc="best", fontsize="small")
    fig.suptitle(title or f"{errors.kind} model: fit vs data, {errors.n_trajectories} recordings")
    return fig
