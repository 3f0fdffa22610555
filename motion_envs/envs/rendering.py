"""Frames of the environments: ``uint8`` ``(height, width, 3)`` RGB arrays.

* :class:`HandFrameRenderer` (orientation): a MuJoCo scene
  (``assets/hand_frames.xml``) with three hand frames at the origin, the human's
  (green), the nominal's (translucent grey) and the agent's (orange), each with a long
  pointing axis, a medium and a short axis, labelled with its name; dots trace the tip
  of the human's and the agent's pointing axis so far. MuJoCo renders through the
  OpenGL backend the user chose with ``MUJOCO_GL`` (``egl`` or ``osmesa`` offscreen;
  ``glfw``, the default, needs a display). This module never writes ``os.environ``.
  Without a working backend (e.g. ``glfw`` or no ``MUJOCO_GL`` on a machine without a
  display) the same scene is drawn with matplotlib's Agg canvas instead (``backend``
  says which is used, and one warning says why). The outcome of the first attempt is
  remembered for the process: a failed OpenGL backend is never tried twice (a second
  GLFW initialisation without a display can abort the interpreter).
* :class:`JugglingSketch` (juggling): the fallback of ``Juggling-v0``'s MuJoCo scene
  without a working OpenGL backend (one warning says why): floor, hand (its catch
  radius) and ball in the vertical plane, drawn with matplotlib's Agg canvas.
* :class:`CurveRenderer` (position): the human demonstration, the nominal and the
  agent's positions so far as curves (matplotlib Agg; first two coordinates).
"""

from __future__ import annotations

import os
import sys
import warnings
from importlib import resources
from typing import Any

import numpy as np
from numpy.typing import NDArray

__all__ = [
    "CurveRenderer",
    "HandFrameRenderer",
    "JugglingSketch",
    "mujoco_rendering_failure",
    "new_mujoco_renderer",
    "warn_matplotlib_fallback",
]

# axis lengths of the hand frame (pointing, medium, short), as in the MJCF
_AXES = np.array([0.8, 0.45, 0.25])
_COLORS = {"human": (0.1, 0.65, 0.2), "nominal": (0.5, 0.5, 0.5), "agent": (0.95, 0.5, 0.05)}


# Why MuJoCo rendering is unavailable in this process (None: not known to fail). Set
# once, by the first HandFrameRenderer that tries, and never retried.
_mujoco_failure: str | None = None

_NEEDS_DISPLAY = ("", "glfw", "glx", "enable", "enabled", "on", "true", "1")


def _display_problem() -> str | None:
    """Why MuJoCo's OpenGL backend cannot work here without trying it, or None."""
    gl = os.environ.get("MUJOCO_GL")
    value = "" if gl is None else gl.lower().strip()
    if sys.platform.startswith("linux") and value in _NEEDS_DISPLAY:
        if not os.environ.get("DISPLAY") and not os.environ.get("WAYLAND_DISPLAY"):
            shown = "unset" if gl is None else repr(gl)
            return (
                f"MUJOCO_GL is {shown}, which needs a display, and there is none; set "
                "MUJOCO_GL=egl (libegl) or MUJOCO_GL=osmesa (libosmesa6) for offscreen "
                "rendering"
            )
    return None


def mujoco_rendering_failure() -> str | None:
    """Why MuJoCo rendering is unavailable in this process, or None if not known to fail."""
    return _mujoco_failure or _display_problem()


def new_mujoco_renderer(model: Any, height: int, width: int) -> Any:
    """A ``mujoco.Renderer(model, height, width)``, or ``RuntimeError`` saying why MuJoCo
    rendering is unavailable in this process.

    Uses the process-wide record of :func:`mujoco_rendering_failure` (and adds to it), so
    a failed OpenGL backend is never tried twice; never writes ``os.environ``.
    """
    failure = mujoco_rendering_failure()
    if failure is None:
        import mujoco

        try:
            return mujoco.Renderer(model, height, width)
        except Exception as exc:  # the backend's import or context creation
            failure = _remember_failure(f"{type(exc).__name__}: {exc}")
    raise RuntimeError(f"MuJoCo offscreen rendering is unavailable: {failure}")


def _rotations(q: NDArray[np.float64]) -> NDArray[np.float64]:
    """``(n, 3, 3)`` rotation matrices of scalar-first quaternions (normalised first)."""
    from motion_envs.geometry import quaternion as quat

    rotations: NDArray[np.float64] = quat.to_rotation(quat.normalize(q)).as_matrix()
    return rotations


def _new_figure(width: int, height: int) -> Any:
    """A figure on its own Agg canvas (no pyplot, no global backend switch)."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    fig = Figure(figsize=(width / 100, height / 100), dpi=100)
    FigureCanvasAgg(fig)
    return fig


def _figure_to_array(fig: Any) -> NDArray[np.uint8]:
    fig.canvas.draw()
    rgb: NDArray[np.uint8] = np.asarray(fig.canvas.buffer_rgba())[..., :3].copy()
    return rgb


class HandFrameRenderer:
    """Draw the human, nominal and agent hand frames (see the module docstring)."""

    def __init__(self, width: int = 480, height: int = 480, backend: str = "auto") -> None:
        if backend not in ("auto", "mujoco", "matplotlib"):
            raise ValueError(f"backend must be 'auto', 'mujoco' or 'matplotlib'; got {backend!r}")
        self.width, self.height = int(width), int(height)
        self._renderer: Any = None
        self._fig: Any = None
        self.backend = "matplotlib"
        if backend in ("auto", "mujoco"):
            failure = mujoco_rendering_failure()
            if failure is None:
                try:
                    self._init_mujoco()
                    self.backend = "mujoco"
                except Exception as exc:  # the backend's import or context creation
                    failure = _remember_failure(f"{type(exc).__name__}: {exc}")
            if failure is not None:
                if backend == "mujoco":
                    raise RuntimeError(f"MuJoCo offscreen rendering is unavailable: {failure}")
                _warn_once(failure)

    def _init_mujoco(self) -> None:
        import mujoco

        xml = (resources.files("motion_envs.envs") / "assets" / "hand_frames.xml").read_text()
        self._mj = mujoco
        self._model = mujoco.MjModel.from_xml_string(xml)
        self._data = mujoco.MjData(self._model)
        self._renderer = mujoco.Renderer(self._model, self.height, self.width)
        self._mocap = {
            name: int(self._model.body(name).mocapid[0]) for name in ("human", "nominal", "agent")
        }

    def render(
        self,
        human: NDArray[np.float64],
        nominal: NDArray[np.float64],
        agent: NDArray[np.float64],
        step: int,
    ) -> NDArray[np.uint8]:
        """Frame at ``step``: ``human``/``nominal`` ``(n, 4)`` grids, ``agent`` ``(step+1, 4)``."""
        k = int(min(step, human.shape[0] - 1))
        current = {"human": human[k], "nominal": nominal[k], "agent": agent[-1]}
        tips_h = _rotations(human[: k + 1])[:, :, 0] * _AXES[0]
        tips_a = _rotations(agent)[:, :, 0] * _AXES[0]
        if self.backend == "mujoco":
            return self._render_mujoco(current, tips_h, tips_a)
        return self._render_matplotlib(current, tips_h, tips_a, k)

    def _render_mujoco(
        self,
        current: dict[str, NDArray[np.float64]],
        tips_h: NDArray[np.float64],
        tips_a: NDArray[np.float64],
    ) -> NDArray[np.uint8]:
        mj = self._mj
        for name, q in current.items():
            self._data.mocap_quat[self._mocap[name]] = q / np.linalg.norm(q)
        mj.mj_forward(self._model, self._data)
        self._renderer.update_scene(self._data, camera="view")
        scene = self._renderer.scene
        eye = np.eye(3).ravel()
        for tips, rgb in ((tips_h, _COLORS["human"]), (tips_a, _COLORS["agent"])):
            for p in tips:
                if scene.ngeom >= scene.maxgeom:
                    break
                mj.mjv_initGeom(
                    scene.geoms[scene.ngeom],
                    mj.mjtGeom.mjGEOM_SPHERE,
                    np.array([0.012, 0.0, 0.0]),
                    p,
                    eye,
                    np.array([*rgb, 0.9], dtype=np.float32),
                )
                scene.ngeom += 1
        # a text label at the tip of each frame's pointing axis
        for name, q in current.items():
            if scene.ngeom >= scene.maxgeom:
                break
            tip = _rotations(q[None])[0][:, 0] * _AXES[0] * 0.6
            geom = scene.geoms[scene.ngeom]
            mj.mjv_initGeom(
                geom,
                mj.mjtGeom.mjGEOM_LABEL,
                np.zeros(3),
                tip,
                eye,
                np.array([*_COLORS[name], 1.0], dtype=np.float32),
            )
            geom.label = name
            scene.ngeom += 1
        frame: NDArray[np.uint8] = self._renderer.render().copy()
        return frame

    def _render_matplotlib(
        self,
        current: dict[str, NDArray[np.float64]],
        tips_h: NDArray[np.float64],
        tips_a: NDArray[np.float64],
        k: int,
    ) -> NDArray[np.uint8]:
        if self._fig is None:
            self._fig = _new_figure(self.width, self.height)
        from matplotlib.lines import Line2D

        fig = self._fig
        fig.clear()
        ax = fig.add_subplot(projection="3d")
        for name, q in current.items():
            R = _rotations(q[None])[0]
            alpha = 0.35 if name == "nominal" else 1.0
            for j in range(3):
                end = R[:, j] * _AXES[j]
                ax.plot(
                    [0, end[0]], [0, end[1]], [0, end[2]], color=_COLORS[name], lw=3, alpha=alpha
                )
        ax.plot(*tips_h.T, ".", color=_COLORS["human"], ms=3)
        ax.plot(*tips_a.T, ".", color=_COLORS["agent"], ms=3)
        for setter in (ax.set_xlim, ax.set_ylim, ax.set_zlim):
            setter(-0.85, 0.85)
        handles = [
            Line2D([], [], color=_COLORS[name], lw=3, alpha=0.35 if name == "nominal" else 1.0)
            for name in ("human", "nominal", "agent")
        ]
        ax.legend(handles, ["human", "nominal", "agent"], loc="upper left", fontsize=8)
        ax.set_title(f"hand frames, step {k}", fontsize=8)
        return _figure_to_array(fig)

    def close(self) -> None:
        if self._renderer is not None:
            self._renderer.close()
            self._renderer = None
        self._fig = None


def _remember_failure(reason: str) -> str:
    global _mujoco_failure
    _mujoco_failure = " ".join(reason.split())
    return _mujoco_failure


_warned: set[tuple[str, str]] = set()


def _warn_once(reason: str, what: str = "hand frames") -> None:
    if (what, reason) not in _warned:
        _warned.add((what, reason))
        warnings.warn(f"{what} are drawn with matplotlib: {reason}", UserWarning, stacklevel=3)


class CurveRenderer:
    """Draw position curves: human (black), nominal (grey dashed), agent (orange)."""

    def __init__(
        self, width: int, height: int, low: NDArray[np.float64], high: NDArray[np.float64]
    ) -> None:
        self.width, self.height = int(width), int(height)
        self._fig = _new_figure(self.width, self.height)
        self._lim = (float(low[0]), float(high[0]))

    def render(
        self,
        human: NDArray[np.float64],
        nominal: NDArray[np.float64],
        agent: NDArray[np.float64],
        title: str = "",
    ) -> NDArray[np.uint8]:
        fig = self._fig
        fig.clear()
        ax = fig.add_subplot()
        ax.plot(human[:, 0], human[:, 1], "-", color="black", lw=1.5, label="human")
        ax.plot(nominal[:, 0], nominal[:, 1], "--", color="0.55", lw=1.5, label="nominal")
        ax.plot(
            agent[:, 0], agent[:, 1], "-o", color=_COLORS["agent"], lw=1.5, ms=2.5, label="agent"
        )
        k = min(agent.shape[0] - 1, human.shape[0] - 1)
        ax.plot(*human[k, :2], "s", color="black", ms=5)
        ax.plot(*human[0, :2], "k^", ms=6)
        ax.plot(*human[-1, :2], "k*", ms=9)
        ax.set_xlim(*self._lim)
        ax.set_ylim(*self._lim)
        ax.set_aspect("equal")
        ax.grid(alpha=0.3)
        ax.legend(loc="upper right", fontsize=7)
        ax.set_title(title, fontsize=8)
        fig.subplots_adjust(left=0.12, right=0.97, bottom=0.08, top=0.92)
        return _figure_to_array(fig)

    def close(self) -> None:
        pass


class JugglingSketch:
    """The juggling scene drawn with matplotlib (the fallback without OpenGL): the floor
    (grey line), the hand (orange circle of the catch radius) and the ball (blue), within
    ``limits = (x_low, x_high, z_low, z_high)`` (m)."""

    def __init__(
        self,
        width: int,
        height: int,
        limits: tuple[float, float, float, float],
        floor_z: float,
        catch_radius: float,
        ball_radius: float,
    ) -> None:
        self.width, self.height = int(width), int(height)
        self._fig = _new_figure(self.width, self.height)
        self._limits = limits
        self._floor, self._catch, self._ball = floor_z, catch_radius, ball_radius

    def render(
        self, hand: NDArray[np.float64], ball: NDArray[np.float64], title: str = ""
    ) -> NDArray[np.uint8]:
        from matplotlib.patches import Circle

        fig = self._fig
        fig.clear()
        ax = fig.add_subplot()
        x0, x1, z0, z1 = self._limits
        ax.axhline(self._floor, color="0.5", lw=2)
        ax.add_patch(Circle((float(hand[0]), float(hand[1])), self._catch, color=_COLORS["agent"]))
        ax.add_patch(Circle((float(ball[0]), float(ball[1])), self._ball, color=(0.1, 0.3, 0.9)))
        ax.set_xlim(x0, x1)
        ax.set_ylim(z0, z1)
        ax.set_aspect("equal")
        ax.set_xlabel("x (m)", fontsize=7)
        ax.set_ylabel("z (m)", fontsize=7)
        ax.set_title(title, fontsize=8)
        return _figure_to_array(fig)

    def close(self) -> None:
        self._fig = None


def warn_matplotlib_fallback(what: str, reason: str) -> None:
    """One ``UserWarning`` per (``what``, ``reason``) in the process: ``what`` is drawn
    with matplotlib because MuJoCo rendering is unavailable."""
    _warn_once(reason, what)
