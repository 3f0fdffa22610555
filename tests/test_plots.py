"""baselines.plots: the figures carry what a reader needs, and the fitted model drawn is
the model (oracle: the Bézier fit of the task's mean curve, by linearity of least squares)."""

from __future__ import annotations

import numpy as np

from baselines.plots import METHOD_STYLE, residual_figure, save_figure, shapes_figure
from motion_envs.geometry import bezier


def _curves(rng: np.random.Generator, n: int, scale: float) -> np.ndarray:
    tau = np.linspace(0.0, 1.0, 50)
    bump = np.sin(np.pi * tau)[None, :, None]
    return scale * bump * rng.normal(size=(n, 1, 3)) + 0.01 * rng.normal(size=(n, 50, 3)) * bump


def test_residual_figure_draws_the_task_model_over_the_data_with_a_robust_range(tmp_path):
    rng = np.random.default_rng(0)
    R = np.concatenate([_curves(rng, 40, 0.1), _curves(rng, 30, 0.1)])
    R[5] *= 40.0  # one wild curve (about 4 rad) must not set the axis range
    tasks = np.array(["a"] * 40 + ["b"] * 30)
    fig = residual_figure(R, tasks, degree=2, dataset="synthetic")
    axes = fig.axes
    assert len(axes) == 3
    for ax in axes:
        assert ax.get_xlabel().endswith("(rad)") and ax.get_ylabel().endswith("(rad)")
        lim = ax.get_xlim()[1]
        assert lim < 1.0 < np.abs(R[5]).max()  # robust: the outlier is outside the frame
    labels = [t.get_text() for t in fig.legends[0].get_texts()]
    assert labels[1:] == ["task model, d = 2", "null model, d = 2", "origin (start and end)"]
    assert labels[0].startswith("trajectories of task 'a' (n = 40)")
    # the red curve is the degree-2 fit of task a's mean curve (x-y view)
    tau = np.linspace(0.0, 1.0, 50)
    P = bezier.fit(R[tasks == "a"].mean(axis=0), tau, 2)
    expected = bezier.evaluate(P, tau, 2)
    task_line = next(ln for ln in axes[0].get_lines() if ln.get_label() == "task model, d = 2")
    np.testing.assert_allclose(task_line.get_xdata(), expected[:, 0], atol=1e-12)
    np.testing.assert_allclose(task_line.get_ydata(), expected[:, 1], atol=1e-12)
    path = save_figure(fig, tmp_path / "r.png")
    assert path.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert (path.stat().st_mode & 0o777) != 0o600


def test_shapes_figure_one_demonstration_and_every_method_per_panel():
    rng = np.random.default_rng(1)
    methods = ["line", "null", "lippi"]
    truth = {s: rng.normal(size=(3, 20, 2)).cumsum(axis=1) for s in ("A", "B", "C")}
    preds = {s: {m: truth[s] + rng.normal(size=truth[s].shape) for m in methods} for s in truth}
    doc = {
        "dataset": "toy",
        "unit": "mm",
        "methods": methods,
        "split": {"split": "loo"},
        "_truth": truth,
        "_predictions": preds,
    }
    fig = shapes_figure(doc)
    panels = [ax for ax in fig.axes if ax.get_title()]
    assert [ax.get_title() for ax in panels] == ["A", "B", "C"]
    for ax, shape in zip(panels, truth, strict=True):
        curves = [ln for ln in ax.get_lines() if ln.get_label() not in ("start", "end")]
        assert len(curves) == 1 + len(methods)
        np.testing.assert_array_equal(curves[0].get_xdata(), truth[shape][0][:, 0])
        np.testing.assert_array_equal(curves[1].get_ydata(), preds[shape]["line"][0][:, 1])
    assert panels[0].get_xlabel() == "x (mm)" and panels[0].get_ylabel() == "y (mm)"
    labels = [t.get_text() for t in fig.legends[0].get_texts()]
    assert labels[0] == "held-out demonstration"
    assert [METHOD_STYLE[m]["label"] for m in methods] == labels[1 : 1 + len(methods)]


def test_shapes_figure_draws_3d_data_in_their_own_plane():
    """Once, 3-D recordings were drawn in x-y only: a reach in the x-z plane became a line.
    Now each panel is the demonstration's plane of largest spread: a planar path keeps its
    shape (every distance between its points), and the predictions share the view."""
    from scipy.spatial.distance import pdist

    t = np.linspace(0, np.pi, 30)
    demo = np.stack([np.cos(t), 0.01 * t, 0.5 * np.sin(t)], axis=1)  # nearly the x-z plane
    planar = demo.copy()
    planar[:, 1] = 0.0
    truth = {"reach": np.stack([planar, demo])}
    preds = {"reach": {"line": truth["reach"] + 0.1}}
    doc = {
        "dataset": "rec.c3d",
        "unit": "m",
        "methods": ["line"],
        "split": {"split": "loo"},
        "_truth": truth,
        "_predictions": preds,
    }
    fig = shapes_figure(doc)
    (panel,) = [ax for ax in fig.axes if ax.get_title()]
    drawn = [ln for ln in panel.get_lines() if ln.get_label() not in ("start", "end")]
    xy = np.stack([drawn[0].get_xdata(), drawn[0].get_ydata()], axis=1)
    np.testing.assert_allclose(pdist(xy), pdist(planar), atol=1e-12)
    shifted = np.stack([drawn[1].get_xdata(), drawn[1].get_ydata()], axis=1)
    np.testing.assert_allclose(pdist(shifted), pdist(planar + 0.1), atol=1e-12)
    assert xy[-1, 0] > xy[0, 0]  # the first direction points from start to end
    assert "principal directions" in fig._suptitle.get_text()
    assert panel.get_xlabel() == "1st direction (m)"


def test_learned_ratio_figure_is_readable():
    """Once: 5 pt labels rotated 90 degrees, subjects sorted as text (10 before 9), no
    colour legend, row ids as titles."""
    from baselines.learned.reading import natural_key, ratio_figure, row_words

    per_group = {"10": 0.8, "9": 1.2, "12": 0.9, "Leaf_10": 1.1, "Leaf_2": 0.7}
    comparison = {
        "learned": "mlp_loso",
        "best_analytic": "task_predictor_d2_loso",
        "ratio": 0.9,
        "ratio_ci95": [0.8, 1.0],
        "target_ratio": 0.95,
        "per_group_ratio": per_group,
    }
    fig = ratio_figure([comparison], "vr-kitchen", "subject")
    ax = fig.axes[0]
    labels = [t.get_text() for t in ax.get_yticklabels()]
    assert labels == ["9", "10", "12", "Leaf_2", "Leaf_10"]
    assert labels == sorted(per_group, key=natural_key)
    for t in [*ax.get_yticklabels(), *ax.get_xticklabels()]:
        assert t.get_fontsize() >= 8 and t.get_rotation() == 0
    legend = [t.get_text() for t in fig.legends[0].get_texts()]
    assert legend == ["learned better (< 1)", "analytic better (>= 1)", "target"]
    title = ax.get_title()
    assert "_" not in title and "MLP (leave one subject out)" in title
    assert "task predictor, d = 2" in title and "95 % CI 0.800 to 1.000" in title
    assert row_words("null_d2_path_loso") == (
        "null model, d = 2, in the path frame (leave one subject out)"
    )
    _assert_legends_clear(fig)


def _assert_legends_clear(fig):
    """Every legend of ``fig`` covers no bar, line or title, and every text lies inside the
    figure (once: legends over the last bars, clipped titles)."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.patches import Rectangle

    if not hasattr(fig.canvas, "get_renderer"):
        FigureCanvasAgg(fig)
    fig.canvas.draw()
    renderer = fig.canvas.get_renderer()
    whole = fig.bbox
    for ax in fig.axes:
        texts = [ax.title, ax.xaxis.label, ax.yaxis.label]
        for text in texts:
            if text.get_text():
                box = text.get_window_extent(renderer)
                assert whole.x0 - 1 <= box.x0 and box.x1 <= whole.x1 + 1, text.get_text()
                assert whole.y0 - 1 <= box.y0 and box.y1 <= whole.y1 + 1, text.get_text()
        bars = [p for p in ax.patches if isinstance(p, Rectangle) and p.get_height() != 0]
        for legend in [ax.get_legend(), *fig.legends]:
            if legend is None:
                continue
            lbox = legend.get_window_extent(renderer)
            for bar in bars:
                assert not lbox.overlaps(bar.get_window_extent(renderer)), "legend over a bar"
            for text in texts:
                if text.get_text():
                    assert not lbox.overlaps(text.get_window_extent(renderer)), text.get_text()


def test_juggling_agent_figure_shows_the_pooled_deviation_beside_the_phases(tmp_path):
    """Once the figure's per-phase bars said the agent was closer to the demonstrations
    while the console's deviation (the median over all segments) said it was farther:
    the figure now also draws that pooled median, with each group's segment counts."""
    from baselines.agents.evaluate import plot_juggling_agent_vs_nominal

    phases = ["toss", "go_down", "catch", "return"]
    rng = np.random.default_rng(0)
    results = {
        "episodes": {
            "agent_deviation": list(rng.uniform(0.01, 0.03, 20)),
            "nominal_deviation": list(rng.uniform(0.01, 0.03, 20)),
        },
        "algo": "ppo",
        "env_id": "MotionEnvs/Juggling-v1",
        "split": "test",
        "phase_deviation": dict(zip(phases, [0.011, 0.012, 0.02, 0.013], strict=True)),
        "nominal_phase_deviation": dict(zip(phases, [0.012, 0.013, 0.021, 0.014], strict=True)),
        "deviation": 0.016,
        "nominal_deviation": 0.014,
        "phase_segments": dict(zip(phases, [40, 40, 80, 40], strict=True)),
        "nominal_phase_segments": dict(zip(phases, [60, 60, 50, 60], strict=True)),
        "nominal_catch_rate": 0.647,
        "catch_rate": 0.93,
        "deviation_reference": "held-out demonstrations",
    }
    import baselines.agents.evaluate as evaluate

    figures = []
    saved = evaluate.save_figure
    evaluate.save_figure = lambda fig, path, dpi: figures.append(fig)
    try:
        plot_juggling_agent_vs_nominal(results, tmp_path / "agent.png")
    finally:
        evaluate.save_figure = saved
    (fig,) = figures
    bars_ax = fig.axes[1]
    heights = [p.get_height() for p in bars_ax.patches]
    assert heights[:5] == [12.0, 13.0, 21.0, 14.0, 14.0]  # nominal: phases, then all
    assert heights[5:] == [11.0, 12.0, 20.0, 13.0, 16.0]  # agent: closer per phase, not pooled
    ticks = [t.get_text() for t in bars_ax.get_xticklabels()]
    assert ticks[-1] == "all\n(console)\nn=230/200" and ticks[2] == "catch\nn=50/80"
    _assert_legends_clear(fig)


def test_residual_figure_magnifies_models_hidden_at_the_origin():
    """Once, on vr-kitchen the model curves (about 0.02 rad) hid at the origin of axes
    spanning 0.2 rad; now each view has an inset with the models magnified."""
    rng = np.random.default_rng(1)
    tau = np.linspace(0.0, 1.0, 50)[None, :, None]
    bump = np.sin(np.pi * tau)
    R = 0.01 * bump + 0.2 * rng.standard_normal((40, 1, 3)) * bump  # small mean, wide spread
    fig = residual_figure(R, np.array(["a"] * 40), degree=2, dataset="synthetic")
    for ax in fig.axes:
        (inset,) = ax.child_axes
        lines = [ln for ln in inset.get_lines() if len(ln.get_xdata()) > 1]
        extent = max(np.abs(np.concatenate([ln.get_xydata().ravel() for ln in lines])).max(), 0)
        assert inset.get_xlim()[1] < 0.25 * ax.get_xlim()[1]
        assert 0.5 * inset.get_xlim()[1] < extent <= inset.get_xlim()[1]  # fills the inset
        assert "zoom" in inset.get_title()
