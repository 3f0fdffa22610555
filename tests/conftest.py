"""Shared pytest fixtures of the test suite (plain helper functions live in ``_helpers.py``)."""

from __future__ import annotations

import pytest


@pytest.fixture(scope="session")
def mujoco_gl() -> None:
    """Skip the requesting test when MuJoCo's offscreen OpenGL rendering is unusable here.

    Asks the project's own detection (:func:`motion_envs.envs.rendering.new_mujoco_renderer`,
    which consults and records ``mujoco_rendering_failure()``, so a failed backend is never
    tried twice in the process) with a renderer of an empty model.
    """
    import mujoco

    from motion_envs.envs.rendering import new_mujoco_renderer

    try:
        renderer = new_mujoco_renderer(mujoco.MjModel.from_xml_string("<mujoco/>"), 16, 16)
    except RuntimeError as exc:
        pytest.skip(f"no usable MuJoCo OpenGL backend (MUJOCO_GL=egl or osmesa): {exc}")
    renderer.close()
