"""The juggling scene's MJCF agrees with the task's constants, and the compiled scene draws
the task it is given (the floor at ``floor_z``)."""

from __future__ import annotations

import xml.etree.ElementTree as ET
from importlib import resources

import pytest

from motion_envs.datasets.juggling import JugglingTask


def test_mjcf_holds_the_task_defaults():
    task = JugglingTask()
    text = resources.files("motion_envs.envs.juggling").joinpath("juggling.xml").read_text()
    root = ET.fromstring(text)
    option = root.find("option")
    assert float(option.get("timestep")) == task.dt
    assert [float(v) for v in option.get("gravity").split()] == [0.0, 0.0, -task.gravity]
    geoms = {g.get("name"): g for g in root.iter("geom")}
    assert float(geoms["ball"].get("size")) == task.ball_radius
    assert float(geoms["ball"].get("mass")) == task.ball_mass
    assert float(geoms["hand"].get("size")) == task.catch_radius
    assert float(geoms["floor"].get("pos").split()[2]) == task.floor_z
    assert "juggling_task" not in text and "models.juggling_" not in text  # no stale module


@pytest.mark.parametrize("task", [JugglingTask(), JugglingTask(gravity=9.81, floor_z=0.2)])
def test_compiled_scene_draws_the_task(task):
    """The compiled model, and where MuJoCo puts the floor, follow the task given."""
    import mujoco

    from motion_envs.envs.juggling import load_juggling_model

    model = load_juggling_model(task)
    data = mujoco.MjData(model)
    mujoco.mj_kinematics(model, data)
    assert model.opt.timestep == task.dt
    assert model.opt.gravity[2] == -task.gravity
    assert data.geom("floor").xpos[2] == task.floor_z
    assert model.geom("ball").size[0] == task.ball_radius
    assert model.geom("hand").size[0] == task.catch_radius


def test_first_frame_uses_the_side_camera():
    """``sync`` places the camera before any ``mj_step`` (the ball held since the reset)."""
    import numpy as np

    from motion_envs.envs.juggling import JugglingScene

    scene = JugglingScene()
    scene.reset([0.2, 1.0])
    scene.step([0.2, 1.001], False)
    scene.sync()
    np.testing.assert_allclose(scene.data.cam("side").xpos, scene.model.cam("side").pos)
