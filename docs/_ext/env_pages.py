"""Sphinx extension: one page per registered environment, generated from its docstring.

As Gymnasium's documentation does, each page is the environment class's docstring
(written in Markdown with ``## Description``, ``## Action Space``, ... sections) under a
title, with an animation, a table of what ``gym.make`` gives (spaces, episode limit,
vector env) and the docstring's sections, ending with its version history (a list of the
registered versions when the docstring has none). The API reference keeps only the first
paragraph of such docstrings and links to the page, since the Markdown sections are not
reStructuredText.

The animation is a seeded rollout (``reset(seed=0)``) under the zero action, i.e. the
analytic nominal, drawn by the environment's own ``rgb_array`` renderer (MuJoCo through
``MUJOCO_GL``, e.g. ``osmesa``, or matplotlib) at ``ANIMATION_SIZE`` pixels: up to
``env_pages_animation_frames`` frames (config value; 60 by default), 25 per second of
environment time at most, as a looping GIF in ``_static/animations``. Rendering takes
about 0.1 s of CPU per frame, so a GIF is kept with the hash of its inputs (the
``motion_envs`` sources and assets, the id, the frame count and size) and reused while
they are unchanged; a rebuild renders nothing. ``env_pages_animation_frames = 0`` (the
environment variable ``MOTION_ENVS_DOCS_ANIMATION_FRAMES=0``; the docs test builds this way)
shows the first frame as a PNG instead.
"""

from __future__ import annotations

import functools
import hashlib
import inspect
import os
import tempfile
import warnings
from pathlib import Path
from typing import Any

PAGES = "environments"
#: Frame width and height (pixels) of the animations.
ANIMATION_SIZE = 240
#: Most frames per second of environment time shown (a finer step is subsampled).
ANIMATION_FPS = 25


def slug(env_id: str) -> str:
    """``MotionEnvs/Juggling-v0`` -> ``juggling-v0``."""
    return env_id.split("/")[-1].lower()


def space_text(space: Any) -> str:
    """A one-line description of a space: a Box by shape, dtype and its bounds' range."""
    import numpy as np

    if hasattr(space, "low") and hasattr(space, "high"):
        low, high = np.min(space.low), np.max(space.high)
        return f"Box({low:g}, {high:g}, {space.shape}, {space.dtype})"
    return " ".join(str(space).split())


def _is_markdown_docstring(lines: list[str]) -> bool:
    return any(line.startswith("## ") for line in lines)


def _render(env: Any) -> Any:
    """``env.render()``, or None when rendering is unavailable (no usable GL backend)."""
    try:
        return env.render()
    except Exception:  # the page then says nothing about a picture
        return None


def _write_atomically(path: Path, write: Any) -> None:
    """Call ``write(tmp_path)`` and move the result onto ``path`` in one rename."""
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=f".{path.name}.", suffix=path.suffix)
    os.close(fd)
    try:
        write(Path(tmp))
        os.replace(tmp, path)
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise


@functools.cache
def _sources_hash() -> str:
    """SHA-256 over the ``motion_envs`` package's Python sources and scene assets."""
    import motion_envs

    root = Path(motion_envs.__file__).resolve().parent
    digest = hashlib.sha256()
    for path in sorted(root.rglob("*")):
        if path.suffix in {".py", ".xml", ".json", ".csv", ".yaml"} and path.is_file():
            digest.update(path.relative_to(root).as_posix().encode())
            digest.update(path.read_bytes())
    return digest.hexdigest()


def rollout_frames(
    env_id: str, n_frames: int, size: int = ANIMATION_SIZE
) -> tuple[list[Any], float]:
    """Up to ``n_frames`` rgb_array frames of seeded zero-action episodes of ``env_id``
    and their rate (frames per second of environment time).

    One frame after ``reset(seed=0)`` and one every ``stride`` steps, ``stride`` chosen so
    that a second of environment time gives at most ``ANIMATION_FPS`` frames; an episode
    that ends is followed by the next one (``reset()``) until ``n_frames`` are drawn.
    No frames when the environment cannot render here.
    """
    import gymnasium as gym
    import numpy as np

    import motion_envs  # noqa: F401  (registers the ids)

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        env = gym.make(env_id, render_mode="rgb_array", width=size, height=size)
    try:
        fps = float(env.metadata.get("render_fps") or ANIMATION_FPS)
        stride = max(1, round(fps / ANIMATION_FPS))
        zero = np.zeros(env.action_space.shape, dtype=env.action_space.dtype)
        env.reset(seed=0)
        frames: list[Any] = []
        while len(frames) < n_frames:
            frame = _render(env)
            if frame is None:
                return [], fps / stride
            frames.append(frame)
            for _ in range(stride):
                _, _, terminated, truncated, _ = env.step(zero)
                if terminated or truncated:
                    if len(frames) < n_frames:  # the episode's last state, then the next
                        last = _render(env)
                        if last is not None:
                            frames.append(last)
                    env.reset()
                    break
        return frames[:n_frames], fps / stride
    finally:
        env.close()


def animation(env_id: str, static: Path, n_frames: int) -> Path | None:
    """The GIF of ``env_id`` in ``static/animations``, rendered only when its inputs
    changed (see the module's docstring); None when the environment cannot render."""
    path = static / "animations" / f"{slug(env_id)}.gif"
    key_path = path.with_suffix(".gif.sha256")
    key = hashlib.sha256(
        f"{_sources_hash()} {env_id} {n_frames} {ANIMATION_SIZE} {ANIMATION_FPS}".encode()
    ).hexdigest()
    if path.exists() and key_path.exists() and key_path.read_text().strip() == key:
        return path
    frames, fps = rollout_frames(env_id, n_frames, ANIMATION_SIZE)
    if not frames:
        return None
    from PIL import Image

    images = [Image.fromarray(f) for f in frames]
    duration = round(1000 / fps)  # ms per frame: the environment's own time

    def save(tmp: Path) -> None:
        images[0].save(
            tmp, format="GIF", save_all=True, append_images=images[1:], duration=duration, loop=0
        )

    _write_atomically(path, save)
    _write_atomically(key_path, lambda tmp: tmp.write_text(key + "\n"))
    return path


def _first_frame(env: Any, path: Path) -> bool:
    """Save the first rgb_array frame of ``env`` as PNG; False when rendering is unavailable."""
    try:
        frame = env.render()
    except Exception:  # no usable GL backend on this machine: the page says so
        return False
    if frame is None:
        return False
    import matplotlib.image

    path.parent.mkdir(parents=True, exist_ok=True)
    matplotlib.image.imsave(path, frame)
    return True


def _version_history(env_id: str, doc: str) -> str:
    """The docstring's own ``## Version History``, or one listing the registered versions."""
    if "## Version History" in doc:
        return ""
    import motion_envs

    family = env_id.rsplit("-v", 1)[0]
    versions = [e for e in motion_envs.ENV_IDS if e.rsplit("-v", 1)[0] == family]
    return "\n".join(["## Version History", "", *(f"* `{e}`: registered." for e in versions), ""])


def _page(env_id: str, out: Path, n_frames: int) -> str:
    import gymnasium as gym

    import motion_envs  # noqa: F401  (registers the ids)

    spec = gym.spec(env_id)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        env = gym.make(env_id, render_mode="rgb_array")
    try:
        env.reset(seed=0)
        cls = type(env.unwrapped)
        image = out / "_static" / f"{slug(env_id)}.png"
        gif = animation(env_id, out / "_static", n_frames) if n_frames > 0 else None
        has_frame = gif is not None or _first_frame(env, image)
        rows = [
            ("Entry point", f"`{spec.entry_point}`"),
            ("Action space", f"`{space_text(env.action_space)}`"),
            ("Observation space", f"`{space_text(env.observation_space)}`"),
            ("Episode limit", f"{spec.max_episode_steps or '-'} steps"),
            ("Native vector env", f"`{spec.vector_entry_point or 'no'}`"),
            ("Registered kwargs", f"`{spec.kwargs}`" if spec.kwargs else "-"),
        ]
    finally:
        env.close()
    doc = inspect.cleandoc(cls.__doc__ or "")
    lines = [f"# {env_id}", ""]
    if gif is not None:
        lines += [
            f"![{env_id} under the zero action (the analytic nominal), seed 0]"
            f"(../_static/animations/{gif.name})",
            "",
        ]
    elif has_frame:
        lines += [f"![First frame of {env_id}](../_static/{image.name})", ""]
    lines += [
        "```python",
        "import gymnasium as gym",
        "import motion_envs",
        f'env = gym.make("{env_id}")',
        "```",
        "",
        "| | |",
        "|---|---|",
        *(f"| {k} | {v} |" for k, v in rows),
        "",
        doc,
        "",
        _version_history(env_id, doc),
    ]
    return "\n".join(lines)


def generate(app: Any) -> None:
    """Write ``environments/<id>.md`` and the index of every id into the source folder."""
    import motion_envs

    src = Path(app.srcdir)
    folder = src / PAGES
    folder.mkdir(exist_ok=True)
    names = []
    n_frames = int(app.config.env_pages_animation_frames)
    for env_id in motion_envs.ENV_IDS:
        text = _page(env_id, src, n_frames)
        target = folder / f"{slug(env_id)}.md"
        if not target.exists() or target.read_text(encoding="utf-8") != text:
            target.write_text(text, encoding="utf-8")
        names.append(slug(env_id))
    index = "\n".join(
        [
            "# Environments",
            "",
            "One page per registered id, generated from the environment's docstring.",
            "",
            "```{toctree}",
            ":maxdepth: 1",
            "",
            *names,
            "```",
            "",
        ]
    )
    target = folder / "index.md"
    if not target.exists() or target.read_text(encoding="utf-8") != index:
        target.write_text(index, encoding="utf-8")


def shorten_markdown_docstrings(
    app: Any, what: str, name: str, obj: Any, options: Any, lines: list[str]
) -> None:
    """Keep the first paragraph of a Gymnasium-style (Markdown) docstring and link the page."""
    if not _is_markdown_docstring(lines):
        return
    first: list[str] = []
    for line in lines:
        if not line.strip() or line.startswith("#"):
            if first:
                break
            continue
        first.append(line)
    lines[:] = [*first, "", "The full description is on the environment's page (Environments)."]


def setup(app: Any) -> dict[str, Any]:
    app.add_config_value("env_pages_animation_frames", 60, "env", types=(int,))
    app.connect("builder-inited", generate)
    app.connect("autodoc-process-docstring", shorten_markdown_docstrings)
    return {"parallel_read_safe": True, "version": "1"}
