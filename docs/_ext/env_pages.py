"""Sphinx extension: one page per registered environment, generated from its docstring.

As Gymnasium's documentation does, each page is the environment class's docstring
(written in Markdown with ``## Description``, ``## Action Space``, ... sections) under a
title, with a table of what ``gym.make`` gives (spaces, episode limit, vector env) and
the first rendered frame when an offscreen OpenGL backend works. The API reference keeps
only the first paragraph of such docstrings and links to the page, since the Markdown
sections are not reStructuredText.
"""

from __future__ import annotations

import inspect
import warnings
from pathlib import Path
from typing import Any

PAGES = "environments"


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


def _page(env_id: str, out: Path) -> str:
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
        has_frame = _first_frame(env, image)
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
    if has_frame:
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
    ]
    return "\n".join(lines)


def generate(app: Any) -> None:
    """Write ``environments/<id>.md`` and the index of every id into the source folder."""
    import motion_envs

    src = Path(app.srcdir)
    folder = src / PAGES
    folder.mkdir(exist_ok=True)
    names = []
    for env_id in motion_envs.ENV_IDS:
        text = _page(env_id, src)
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
    app.connect("builder-inited", generate)
    app.connect("autodoc-process-docstring", shorten_markdown_docstrings)
    return {"parallel_read_safe": True, "version": "1"}
