"""The files and pictures of ``motion-bench juggling``: :func:`write` (results.json,
results.csv, the Figure-6-style plot, the GIF), the matplotlib animation and the MuJoCo
video (a filming wrapper around the scene)."""

from __future__ import annotations

import json
import sys
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from baselines.juggling_bench.scoring import juggling_scene
from baselines.juggling_bench.text import clean_json, results_csv
from motion_envs._io import atomic_write, atomic_write_text, save_figure
from motion_envs.datasets.juggling import PHASES, JugglingDemos, JugglingNoise
from motion_envs.models.juggling import AnalyticJuggler, cycle_rngs, run_cycle

VIDEO_CAPTION = "analytic juggler in the MuJoCo scene (SIMULATED)"

PHASE_COLORS = {"toss": "C3", "go_down": "C0", "catch": "C2", "return": "C1"}


def plot_figure6(doc: dict[str, Any], path: Path) -> Path:
    """Demonstrations (left) and generated cycles (right), phases coloured, ball flights."""
    from matplotlib.figure import Figure
    from matplotlib.lines import Line2D

    demos: JugglingDemos = doc["_demos"]
    fig = Figure(figsize=(11, 4.8))
    axes = fig.subplots(1, 2, sharex=True, sharey=True)
    ax = axes[0]
    shown = 0
    for seg in demos.segments():
        if (seg.recording, seg.cycle) not in doc["_test"] or seg.cycle > 200:
            continue
        ax.plot(*seg.positions.T, color=PHASE_COLORS[seg.phase], lw=0.8, alpha=0.8)
        shown += 1
    rec = demos.recordings[0]
    if rec.ball is not None and rec.phase is not None:
        flying = np.isin(rec.phase, ["go_down", "catch"])
        ax.plot(*np.where(flying[:, None], rec.ball, np.nan).T, color="0.5", lw=0.5, ls=":")
    ax.set_title(f"held-out demonstrations ({'SIMULATED' if demos.simulated else 'recorded'})")
    ax = axes[1]
    for tr in doc["_traces"]:
        for phase in PHASES:
            sel = tr.phase == phase
            ax.plot(*np.where(sel[:, None], tr.hand, np.nan).T, color=PHASE_COLORS[phase], lw=1)
        fly = np.isin(tr.phase, ["go_down", "catch"])
        ax.plot(*np.where(fly[:, None], tr.ball, np.nan).T, color="0.4", lw=0.8, ls="--")
    ax.set_title("analytic juggler (pure model), ball flights dashed")
    for a in axes:
        a.set_xlabel("x (m)")
        a.set_aspect("equal", adjustable="box")
        a.grid(alpha=0.3)
    axes[0].set_ylabel("z (m)")
    handles = [Line2D([], [], color=c, label=p) for p, c in PHASE_COLORS.items()]
    fig.legend(handles=handles, loc="lower center", ncol=4, fontsize=8)
    label = "SIMULATED demonstrations" if demos.simulated else demos.name
    fig.suptitle(f"Juggling, Lippi et al. Fig. 6 style — {label}", fontsize=10)
    fig.tight_layout(rect=(0, 0.06, 1, 1))
    return save_figure(fig, path, dpi=100)


def _save_gif(images: list[Any], path: Path, fps: int) -> Path:
    """PIL images as a looping GIF at ``fps``, written atomically (:mod:`motion_envs._io`)."""
    return atomic_write(
        path,
        lambda fh: images[0].save(
            fh,
            format="GIF",
            save_all=True,
            append_images=images[1:],
            duration=int(1000 / fps),
            loop=0,
        ),
        binary=True,
    )


def write_animation(doc: dict[str, Any], path: Path, fps: int = 25) -> Path:
    """A GIF of the first generated cycles (hand, catch circle, ball), labelled SIMULATED.

    Drawn on a matplotlib ``Figure`` with its own Agg canvas (no pyplot), one RGBA frame
    every ``1 / fps`` s of the trace.
    """
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure
    from matplotlib.patches import Circle
    from PIL import Image

    tr = doc["_traces"][0]
    stride = max(1, round(1 / (fps * doc["task"]["dt"])))
    idx = np.arange(0, len(tr.times), stride)
    fig = Figure(figsize=(4, 4))
    canvas: Any = FigureCanvasAgg(fig)  # matplotlib's canvas methods are untyped
    ax = fig.subplots()
    lo = np.minimum(tr.hand.min(0), tr.ball.min(0)) - 0.1
    hi = np.maximum(tr.hand.max(0), tr.ball.max(0)) + 0.1
    ax.set_xlim(lo[0], hi[0])
    ax.set_ylim(lo[1], hi[1])
    ax.set_aspect("equal")
    hand = Circle(tuple(tr.hand[0]), doc["task"]["catch_radius"], color="C1", alpha=0.4)
    ball = Circle(tuple(tr.ball[0]), doc["task"]["ball_radius"], color="C3")
    ax.add_patch(hand)
    ax.add_patch(ball)
    (path_line,) = ax.plot([], [], color="0.5", lw=0.8)
    title = ax.set_title("")
    ax.text(0.02, 0.02, "SIMULATED, pure model", transform=ax.transAxes, fontsize=7)
    images = []
    for i in idx:
        hand.center = tuple(tr.hand[i])
        ball.center = tuple(tr.ball[i])
        path_line.set_data(tr.hand[: i + 1, 0], tr.hand[: i + 1, 1])
        title.set_text(f"analytic juggler: {tr.phase[i]}  t = {tr.times[i]:.2f} s")
        canvas.draw()
        rgba = np.asarray(canvas.buffer_rgba()).copy()
        # opaque frames as RGB: they quantise to the GIF palette better (as PillowWriter)
        images.append(Image.fromarray(rgba[..., :3] if rgba[..., 3].min() == 255 else rgba))
    return _save_gif(images, path, fps)


class _Filming:
    """A JugglingScene that renders every ``stride``-th step (camera ``side``)."""

    def __init__(self, scene: Any, stride: int, width: int = 480, height: int = 360) -> None:
        from motion_envs.envs.rendering import new_mujoco_renderer

        self.scene, self.stride, self.task = scene, stride, scene.task
        scene.model.vis.global_.offwidth = max(scene.model.vis.global_.offwidth, width)
        scene.model.vis.global_.offheight = max(scene.model.vis.global_.offheight, height)
        self.renderer = new_mujoco_renderer(scene.model, height, width)
        self.frames: list[NDArray[np.uint8]] = []
        self._k = 0

    def _shoot(self) -> None:
        self.scene.sync()
        self.renderer.update_scene(self.scene.data, camera="side")
        self.frames.append(self.renderer.render().copy())

    def reset(self, hand_pos: Any, **kwargs: Any) -> Any:
        state = self.scene.reset(hand_pos, **kwargs)
        self._k = 0
        self._shoot()
        return state

    def step(self, hand_target: Any, release_armed: bool) -> Any:
        state = self.scene.step(hand_target, release_armed)
        self._k += 1
        if self._k % self.stride == 0:
            self._shoot()
        return state


def write_mujoco_video(doc: dict[str, Any], path: Path, cycles: int = 1, fps: int = 20) -> Path:
    """A GIF of the analytic juggler in the MuJoCo scene (``rgb_array`` frames, camera side).

    Replays the figure's first ``cycles`` cycles (same seeds) with a renderer attached.
    """
    from PIL import Image, ImageDraw

    juggler: AnalyticJuggler = doc["_juggler"]
    task = juggler.task
    film = _Filming(juggling_scene(task), max(1, round(1 / (fps * task.dt))))
    for rngs in cycle_rngs(doc["config"]["seed"] + 1, cycles):
        run_cycle(juggler, film, JugglingNoise(), rngs, through_return=True)
    film.renderer.close()
    images = []
    for frame in film.frames:
        img = Image.fromarray(frame)
        ImageDraw.Draw(img).text((8, 8), VIDEO_CAPTION, fill="black")
        images.append(img.convert("P", palette=Image.Palette.ADAPTIVE))
    return _save_gif(images, path, fps)


def write(doc: dict[str, Any], out: str | Path, video: bool = True) -> list[Path]:
    """results.json, results.csv, juggling_fig6.png and (``video``) juggling.gif in ``out``.

    Every file is written atomically through :mod:`motion_envs._io`.
    """
    out = Path(out)
    paths = [
        atomic_write_text(out / "results.json", json.dumps(clean_json(doc), indent=2) + "\n"),
        atomic_write_text(out / "results.csv", results_csv(doc)),
        plot_figure6(doc, out / "juggling_fig6.png"),
    ]
    if video:
        target = out / "juggling.gif"
        if doc["config"]["world"] == "mujoco":
            try:
                paths.append(write_mujoco_video(doc, target))
                return paths
            except Exception as exc:  # no OpenGL context: draw the same cycles with matplotlib
                print(
                    f"motion-bench juggling: MuJoCo rendering unavailable ({exc}); "
                    "the GIF is drawn with matplotlib",
                    file=sys.stderr,
                )
        paths.append(write_animation(doc, target))
    return paths
