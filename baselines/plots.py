"""Figures of the benchmarks, for a paper or a report: functions from results to figures.

Every function takes result arrays or documents and returns a
:class:`matplotlib.figure.Figure` on its own Agg canvas (no pyplot, no global backend
switch, so a user's interactive backend is left alone); :func:`save_figure` (the
project's one atomic writer, :func:`motion_envs._io.save_figure`) writes one as PNG.

* :func:`residual_figure`: Faraway & Choe's Figure 5 view of one task's slerp residual
  curves (three orthogonal projections, radians) with the fitted task and null models
  drawn over the data and an axis range that ignores the extreme 2 % of samples.
* :func:`shapes_figure`: one panel per shape with one held-out demonstration and each
  method's prediction of it (``line`` included), axes in the data's unit and one legend
  outside the panels.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Any

import numpy as np
from numpy.typing import NDArray

from motion_envs._io import save_figure

__all__ = [
    "METHOD_STYLE",
    "new_figure",
    "residual_figure",
    "save_figure",
    "shapes_figure",
]

#: Colour, line style and legend label of each position method.
METHOD_STYLE: dict[str, dict[str, Any]] = {
    "line": {"color": "0.45", "ls": ":", "label": "line (start to end)"},
    "null": {"color": "C2", "ls": "-", "label": "null (line + mean residual)"},
    "lippi": {"color": "C3", "ls": "-", "label": "Lippi et al. (sine regression)"},
    "dmp": {"color": "C0", "ls": "--", "label": "DMP"},
    "promp": {"color": "C1", "ls": "--", "label": "ProMP"},
    "ridge": {"color": "C4", "ls": "-.", "label": "ridge (learned residual)"},
    "mlp": {"color": "C5", "ls": "-.", "label": "MLP (learned residual, torch)"},
}


def new_figure(width: float, height: float) -> Any:
    """A ``width`` x ``height`` inch figure on its own Agg canvas (no pyplot)."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    fig = Figure(figsize=(width, height), layout="constrained")
    FigureCanvasAgg(fig)
    return fig


def _robust_limit(points: NDArray[np.float64], quantile: float = 0.98) -> float:
    """Half-width of a square axis range holding ``quantile`` of the coordinates."""
    if points.size == 0:
        return 1.0
    lim = float(np.quantile(np.abs(points), quantile)) * 1.15
    return lim if lim > 0 else 1.0


def _model_inset(
    ax: Any,
    task_curve: NDArray[np.float64],
    null_curve: NDArray[np.float64],
    dims: tuple[int, int],
    model_lim: float,
    lim: float,
) -> Any:
    """An inset of ``ax`` (upper right) with the two model curves magnified to
    ``model_lim``, so that curves much smaller than the data's spread stay visible; the
    zoomed square is marked in the main axes."""
    i, j = dims
    ins = ax.inset_axes([0.6, 0.55, 0.38, 0.38])
    ins.plot(task_curve[:, i], task_curve[:, j], color="C3", lw=2.0)
    ins.plot(null_curve[:, i], null_curve[:, j], color="C0", lw=1.8, ls="--")
    ins.plot(0, 0, "k+", ms=8, mew=1.2)
    ins.set_xlim(-model_lim, model_lim)
    ins.set_ylim(-model_lim, model_lim)
    ins.set_aspect("equal")
    ins.tick_params(labelsize=7, length=2)
    ins.set_title(f"models, {lim / model_lim:.0f}x zoom", fontsize=8, pad=2)
    ins.set_facecolor("white")
    ins.grid(alpha=0.3)
    ax.indicate_inset_zoom(ins, edgecolor="0.3")
    return ins


def residual_figure(
    residuals: NDArray[np.float64],
    tasks: Sequence[str] | NDArray[np.str_],
    task: str | None = None,
    degree: int = 2,
    dataset: str = "",
    simulated: bool = False,
) -> Any:
    """Three orthogonal views of one task's residual curves with the fitted models.

    ``residuals`` is ``(L, n, 3)`` (radians), ``tasks`` the ``(L,)`` task labels; ``task``
    (default: the most frequent) selects the curves drawn. Drawn over them: the task
    model (Bézier curve of ``degree`` through the mean control points of the task) and
    the null model (mean control points of all curves), both fitted by
    :mod:`motion_envs.models.bezier_models` on every curve shown. The axes hold 98 % of
    the task's samples (a few extreme curves may leave the frame; the caption says how
    far the farthest goes). When the model curves are under a quarter of that range (as
    on vr-kitchen, where they would hide at the origin) each view gets an inset with the
    models magnified.
    """
    from motion_envs.models.bezier_models import NullBezierModel, TaskBezierModel

    R = np.asarray(residuals, dtype=np.float64)
    labels = np.asarray(tasks).astype(str)
    names, counts = np.unique(labels, return_counts=True)
    chosen = str(names[np.argmax(counts)]) if task is None else str(task)
    if chosen not in names:
        raise ValueError(f"task must be one of {names.tolist()}; got {chosen!r}")
    mine = R[labels == chosen]
    task_curve = TaskBezierModel(degree).fit(R, tasks=labels).predict(tasks=[chosen])[0]
    null_curve = NullBezierModel(degree).fit(R).predict(n=1)[0]
    lim = max(_robust_limit(mine), 1.1 * float(np.abs(task_curve).max()))
    farthest = float(np.linalg.norm(mine, axis=2).max())
    model_lim = 1.3 * float(max(np.abs(task_curve).max(), np.abs(null_curve).max(), 1e-12))

    fig = new_figure(12.5, 4.6)
    axes = fig.subplots(1, 3)
    for ax, (i, j) in zip(axes, [(0, 1), (0, 2), (1, 2)], strict=True):
        for k, curve in enumerate(mine):
            ax.plot(
                curve[:, i],
                curve[:, j],
                color="0.55",
                lw=0.7,
                alpha=0.55,
                label=f"trajectories of task {chosen!r} (n = {len(mine)})" if k == 0 else None,
            )
        ax.plot(
            task_curve[:, i],
            task_curve[:, j],
            color="C3",
            lw=2.4,
            label=f"task model, d = {degree}",
        )
        ax.plot(
            null_curve[:, i],
            null_curve[:, j],
            color="C0",
            lw=2.0,
            ls="--",
            label=f"null model, d = {degree}",
        )
        ax.plot(0, 0, "k+", ms=11, mew=1.5, label="origin (start and end)")
        if model_lim < 0.25 * lim:  # the models would hide at the origin: magnify them
            _model_inset(ax, task_curve, null_curve, (i, j), model_lim, lim)
        ax.set_xlim(-lim, lim)
        ax.set_ylim(-lim, lim)
        ax.set_aspect("equal")
        ax.set_xlabel(f"residual {'xyz'[i]} (rad)")
        ax.set_ylabel(f"residual {'xyz'[j]} (rad)")
        ax.set_title(f"{'xyz'[i]}-{'xyz'[j]} view", fontsize=10)
        ax.grid(alpha=0.3)
    handles, names_ = axes[0].get_legend_handles_labels()
    fig.legend(handles, names_, loc="outside lower center", ncols=4, fontsize=9, frameon=False)
    sim = " (SIMULATED data)" if simulated else ""
    fig.suptitle(
        f"Empirical slerp residuals, {dataset}{sim}, task {chosen!r}: axes hold 98 % of the "
        f"samples; farthest point {farthest:.2f} rad from the origin",
        fontsize=11,
    )
    return fig


def shapes_figure(doc: dict[str, Any], shapes: Sequence[str] | None = None, demo: int = 0) -> Any:
    """One panel per shape: one held-out demonstration and each method's prediction of it.

    ``doc`` is :func:`baselines.position_bench.run_benchmark`'s result (with its
    ``_truth`` and ``_predictions``); ``shapes`` defaults to every scored shape; ``demo``
    picks which of each shape's scored demonstrations is drawn (the first by default,
    not chosen by any method's error). A panel holds that demonstration (black) and the
    prediction of every method, ``line`` included; axes are in the data's unit; one
    legend below the panels.
    """
    shapes = list(doc["_truth"]) if shapes is None else list(shapes)
    methods = list(doc["methods"])
    unit = doc.get("unit") or "data unit"
    cols = min(6, len(shapes))
    rows = math.ceil(len(shapes) / cols)
    fig = new_figure(2.35 * cols + 0.4, 2.3 * rows + 1.0)
    axes = np.atleast_2d(fig.subplots(rows, cols, squeeze=False))
    dims = int(next(iter(doc["_truth"].values())).shape[-1]) if shapes else 2
    for ax, shape in zip(axes.ravel(), shapes, strict=False):
        truth = doc["_truth"][shape]
        k = min(demo, truth.shape[0] - 1)
        view = _plane(truth[k])  # x-y in 2-D; the demonstration's own plane in 3-D
        y = truth[k] @ view
        ax.plot(y[:, 0], y[:, 1], color="black", lw=2.2, label="held-out demonstration")
        for method in methods:
            style = METHOD_STYLE.get(method, {"color": "C4", "ls": "-", "label": method})
            pred = doc["_predictions"][shape][method][k] @ view
            ax.plot(
                pred[:, 0],
                pred[:, 1],
                color=style["color"],
                ls=style["ls"],
                lw=1.3,
                label=style["label"],
            )
        ax.plot(*y[0, :2], "k^", ms=5, label="start")
        ax.plot(*y[-1, :2], "k*", ms=8, label="end")
        # a square window around the demonstration, a quarter of its extent wider
        lo, hi = y[:, :2].min(axis=0), y[:, :2].max(axis=0)
        centre, half = (lo + hi) / 2, 0.75 * float(np.max(hi - lo) or 1.0)
        ax.set_xlim(centre[0] - half, centre[0] + half)
        ax.set_ylim(centre[1] - half, centre[1] + half)
        ax.set_aspect("equal", adjustable="box")
        ax.set_title(shape, fontsize=9)
        ax.tick_params(labelsize=7)
        ax.grid(alpha=0.25)
    for ax in axes.ravel()[len(shapes) :]:
        ax.axis("off")
    names = ("x", "y") if dims == 2 else ("1st direction", "2nd direction")
    for ax in axes[:, 0]:
        ax.set_ylabel(f"{names[1]} ({unit})", fontsize=8)
    for ax in axes[-1, :]:
        ax.set_xlabel(f"{names[0]} ({unit})", fontsize=8)
    handles, labels = axes.ravel()[0].get_legend_handles_labels()
    fig.legend(handles, labels, loc="outside lower center", ncols=4, fontsize=8, frameon=False)
    split = doc.get("split", {}).get("split", "loo")
    scored = "leave one demonstration out" if split == "loo" else f"{split} split"
    plane = (
        ""
        if dims == 2
        else f"\n{dims}-D data, each panel in its demonstration's plane of largest spread "
        "(its two principal directions)"
    )
    fig.suptitle(
        f"{doc.get('dataset', '')}: one held-out demonstration per shape and each method's "
        f"prediction of it from its start, end and duration ({scored}){plane}",
        fontsize=10,
    )
    return fig


def _plane(path: NDArray[np.float64]) -> NDArray[np.float64]:
    """``(D, 2)``: the axes a panel draws ``path`` ``(n, D)`` in: x and y for 2-D data;
    for 3-D or more, the path's two principal directions (the plane it spreads most in),
    signed so that the first points from its start towards its end."""
    d = path.shape[1]
    if d <= 2:
        return np.eye(d, 2)
    centred = path - path.mean(axis=0)
    _, _, vt = np.linalg.svd(centred, full_matrices=False)
    basis: NDArray[np.float64] = vt[:2].T.copy()
    if (path[-1] - path[0]) @ basis[:, 0] < 0:
        basis[:, 0] *= -1
    return basis
