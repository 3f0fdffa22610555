"""The MJCF of a juggling world, written from its spec.

:class:`~motion_envs.envs.juggling._world_spec.WorldSpec` says what the world is;
one template for every spec (1-2 hands, 1-5 balls): bodies, slide joints, the hands'
motors with force range ``hand_mass x accel_limit``, the floor limit of each hand, the
contacts and the contact sensors; air drag through MuJoCo's fluid model when the spec
has air. What each part means is in :mod:`motion_envs.envs.juggling._world`.
"""

from __future__ import annotations

import mujoco

from motion_envs.envs.juggling._world_spec import (
    BALL_CONAFFINITY,
    BALL_CONTYPE,
    PALM_HALF_THICKNESS,
    WorldSpec,
)

__all__ = [
    "load_world_model",
    "palm_name",
    "world_mjcf",
]

_BALL_COLOURS = (
    "0.85 0.15 0.15 1",
    "0.15 0.65 0.2 1",
    "0.9 0.75 0.1 1",
    "0.2 0.35 0.85 1",
    "0.7 0.3 0.75 1",
)
_HAND_COLOURS = ("0.9 0.6 0.4", "0.4 0.6 0.9")


def palm_name(hand: str) -> str:
    """The palm geom's name of hand ``hand``."""
    return hand.replace("hand", "palm")


def world_mjcf(spec: WorldSpec) -> str:
    """The MJCF of ``spec``'s world (module docstring): the vertical plane (``x``
    horizontal, ``z`` up; ``y`` unused), SI units; qpos/qvel: each hand's ``x, z`` then
    each ball's. Numbers are written exactly (``repr``)."""
    r, m = spec.ball_radius, spec.ball_mass
    force = spec.hand_mass * spec.accel_limit
    palm_z = -(r + PALM_HALF_THICKNESS)
    # the hand stops where its palm's underside meets the floor
    z_min = spec.floor_z + r + 2 * PALM_HALF_THICKNESS
    hands, balls, motors, sensors = [], [], [], []
    # with air, every palm and ball uses the ellipsoid fluid model; the coefficients are
    # zero (a ball's blunt drag is set per episode by HandsWorld.set_drag)
    extra = ' fluidshape="ellipsoid" fluidcoef="0 0 0 0 0"' if spec.air_density > 0 else ""
    if spec.contact_damping != 1.0:  # springy palms and balls (the default's class: 1)
        extra += f' solref="0.004 {spec.contact_damping!r}"'
    density = f' density="{spec.air_density!r}"' if spec.air_density > 0 else ""
    option = (
        f'<option timestep="{spec.physics_step!r}" gravity="0 0 {-spec.gravity!r}" '
        f'integrator="Euler"{density}/>'
    )
    for h, name in enumerate(spec.hand_names):
        palm, colour = palm_name(name), _HAND_COLOURS[h]
        hands.append(f"""
    <body name="{name}" pos="0 0 0" gravcomp="1">
      <joint name="{name}_x" type="slide" axis="1 0 0" damping="0" armature="0"/>
      <joint name="{name}_z" type="slide" axis="0 0 1" damping="0" armature="0"
             limited="true" range="{z_min!r} 1000" solreflimit="0.004 1"/>
      <inertial pos="0 0 0" mass="{spec.hand_mass!r}" diaginertia="0.001 0.001 0.001"/>
      <geom name="{palm}" type="box" size="0.045 0.03 {PALM_HALF_THICKNESS!r}"
            pos="0 0 {palm_z!r}" rgba="{colour} 1" contype="1" conaffinity="0" condim="3"
            mass="0"{extra}/>
      <geom name="{name}_mark" type="sphere" size="0.02" pos="0 0 -0.06"
            rgba="{colour} 0.35" contype="0" conaffinity="0" mass="0"/>
    </body>""")
        motors += [
            f'    <motor name="{name}_{a}" joint="{name}_{a}" gear="1" '
            f'forcerange="{-force!r} {force!r}"/>'
            for a in ("x", "z")
        ]
    inertia = 0.4 * m * r**2
    for b, name in enumerate(spec.ball_names):
        balls.append(f"""
    <body name="{name}" pos="0 0 0">
      <joint name="{name}_x" type="slide" axis="1 0 0" damping="0" armature="0"/>
      <joint name="{name}_z" type="slide" axis="0 0 1" damping="0" armature="0"/>
      <inertial pos="0 0 0" mass="{m!r}" diaginertia="{inertia!r} {inertia!r} {inertia!r}"/>
      <geom name="{name}" type="sphere" size="{r!r}" mass="0"
            rgba="{_BALL_COLOURS[b]}" contype="{BALL_CONTYPE}"
            conaffinity="{BALL_CONAFFINITY}" condim="3"{extra}/>
    </body>""")
        sensors.append(
            f'    <contact name="{name}_floor" geom1="{name}" geom2="floor" data="found" num="1"/>'
        )
        sensors += [
            f'    <contact name="{name}_{palm_name(h)}" geom1="{name}" '
            f'geom2="{palm_name(h)}" data="found" num="1"/>'
            for h in spec.hand_names
        ]
    camera_x = -0.1 if spec.hands == 1 else 0.0
    return f"""<!-- a juggling world: {spec.hands} hand(s), {spec.balls} ball(s); written by
     motion_envs.envs.juggling._world_mjcf.world_mjcf from {spec!r} -->
<mujoco model="juggling_{spec.hands}h{spec.balls}b">
  <compiler angle="radian" autolimits="true"/>
  {option}
  <visual>
    <global offwidth="640" offheight="480"/>
    <headlight ambient="0.4 0.4 0.4" diffuse="0.6 0.6 0.6"/>
  </visual>
  <asset>
    <texture name="grid" type="2d" builtin="checker" rgb1="0.85 0.85 0.85" rgb2="0.75 0.75 0.75"
             width="256" height="256"/>
    <material name="grid" texture="grid" texrepeat="8 8"/>
    <texture type="skybox" builtin="gradient" rgb1="0.92 0.94 1" rgb2="0.55 0.65 0.8" width="32"
             height="32"/>
  </asset>
  <default>
    <geom solref="0.004 1" solimp="0.95 0.99 0.001"/>
  </default>
  <worldbody>
    <light pos="0 -2 3" dir="0 0.5 -1"/>
    <camera name="side" pos="{camera_x!r} -2.2 1.25" xyaxes="1 0 0 0 0 1" fovy="40"/>
    <geom name="floor" type="plane" size="2 1 0.01" pos="0 0 {spec.floor_z!r}" material="grid"
          contype="1" conaffinity="0" condim="3"/>{"".join(hands)}{"".join(balls)}
  </worldbody>
  <actuator>
{chr(10).join(motors)}
  </actuator>
  <sensor>
{chr(10).join(sensors)}
  </sensor>
</mujoco>
"""


def load_world_model(spec: WorldSpec) -> mujoco.MjModel:
    """Compile :func:`world_mjcf` of ``spec``."""
    return mujoco.MjModel.from_xml_string(world_mjcf(spec))
