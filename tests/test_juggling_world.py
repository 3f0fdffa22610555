"""The one juggling world (``envs.juggling._world``, ``_period``): its MJCF is its spec,
the plain-Python period and the compiled one are the same world bit for bit, a batch of N
worlds is N single worlds, the contact sensors are MuJoCo's contact list, the capture rule
behaves as documented, and the hand stops at the floor."""

from __future__ import annotations

import xml.etree.ElementTree as ET
from typing import Any

import mujoco
import numpy as np
import pytest

from motion_envs.datasets.juggling import JugglingTask
from motion_envs.envs._kernels import numba_available
from motion_envs.envs.juggling import HandsWorld, WorldSpec, _period, world_mjcf

needs_numba = pytest.mark.skipif(not numba_available(), reason="needs numba (fast extra)")
TASK = JugglingTask(gravity=9.81)
SHAPES = [(1, 1), (2, 3), (2, 5), (1, 2), (2, 4)]


@pytest.mark.parametrize(("hands", "balls"), SHAPES)
def test_mjcf_is_the_spec(hands: int, balls: int) -> None:
    spec = WorldSpec.of(TASK, hands=hands, balls=balls, hand_mass=0.7, accel_limit=90.0)
    root = ET.fromstring(world_mjcf(spec))
    motors = root.findall("./actuator/motor")
    assert len(motors) == 2 * hands
    force = 0.7 * 90.0
    for m in motors:  # the force range is hand mass x acceleration limit, from the spec only
        assert [float(v) for v in m.get("forcerange").split()] == [-force, force]
    model = mujoco.MjModel.from_xml_string(world_mjcf(spec))
    assert model.nq == model.nv == 2 * hands + 2 * balls
    assert model.nsensor == balls * (1 + hands)
    assert model.opt.timestep == spec.dt / spec.substeps
    assert model.opt.gravity[2] == -TASK.gravity
    for name in spec.ball_names:
        assert model.geom(name).size[0] == TASK.ball_radius
        assert model.body(name).mass[0] == TASK.ball_mass
    for name in spec.hand_names:
        assert model.body(name).mass[0] == 0.7
        palm = model.geom(name.replace("hand", "palm"))
        assert palm.pos[2] + palm.size[2] == spec.palm_top
    assert model.geom("floor").pos[2] == TASK.floor_z


@pytest.mark.parametrize(
    ("field", "value"),
    [("hands", 3), ("balls", 0), ("balls", 6), ("gravity", 0.0), ("dt", float("nan")),
     ("capture_speed", -1.0), ("substeps", 0), ("hands", True)],
)  # fmt: skip
def test_spec_refuses_what_no_world_is(field: str, value: Any) -> None:
    with pytest.raises(ValueError, match=f"WorldSpec.{field}"):
        WorldSpec(**{field: value})


def _drive(world: HandsWorld, steps: int, seed: int) -> list[np.ndarray]:
    """A seeded random episode: balls launched over the hands, jittered targets, random
    arming; the world's full state after every period."""
    spec, rng = world.spec, np.random.default_rng(seed)
    home = np.array([[0.25, 1.0], [-0.25, 1.0]])[: spec.hands]
    holder = tuple(b if b < spec.hands else -1 for b in range(spec.balls))
    balls = np.array([[0.25 - 0.12 * b, 1.3 + 0.2 * b] for b in range(spec.balls)])
    world.reset_state(home, np.zeros_like(home), holder, (-1,) * spec.balls, balls,
                      np.zeros_like(balls))  # fmt: skip
    world._rng = np.random.default_rng(seed + 1)
    world.release_speed_std = 0.05
    out = []
    for _ in range(steps):
        target = home + rng.normal(0.0, 0.15, home.shape)
        world.period(target, rng.random(spec.hands) < 0.5)
        d = world.data
        flags = (world.holder, world.left, world.dropped, world.caught, world.released)
        out.append(np.concatenate([d.qpos, d.qvel, *(f[0] for f in flags)]))
    return out


@needs_numba
@pytest.mark.parametrize(("hands", "balls"), SHAPES)
def test_plain_python_period_is_the_compiled_one(hands: int, balls: int) -> None:
    spec = WorldSpec.of(TASK, hands=hands, balls=balls)
    for seed in range(2):
        a = _drive(HandsWorld(spec, backend="python"), 150, seed)
        b = _drive(HandsWorld(spec, backend="numba"), 150, seed)
        for x, y in zip(a, b, strict=True):
            np.testing.assert_array_equal(x, y)


@needs_numba
def test_a_batch_of_worlds_is_the_single_worlds() -> None:
    """``world_periods`` over N worlds in one call = each world stepped alone."""
    from motion_envs.envs.juggling import _compiled

    spec = WorldSpec.of(TASK, hands=2, balls=5)
    singles = [HandsWorld(spec) for _ in range(3)]
    batch = [HandsWorld(spec) for _ in range(3)]
    home = np.array([[0.25, 1.0], [-0.25, 1.0]])
    balls = np.array([[0.2 - 0.1 * b, 1.2 + 0.15 * b] for b in range(5)])
    for w in singles + batch:
        w.reset_state(home, np.zeros((2, 2)), (0, 1, -1, -1, -1), (-1,) * 5, balls,
                      np.zeros((5, 2)))  # fmt: skip
    names = ("ref", "vref", "z_before", "holder", "thrower", "left", "dropped", "k")
    state = {n: np.concatenate([getattr(w, n) for w in batch]) for n in names}
    caught, released = np.full((3, 2), -1), np.full((3, 2), -1)
    rng = np.random.default_rng(0)
    links = _compiled.world_links(batch)
    for _ in range(200):
        target = home + rng.normal(0.0, 0.1, (3, 2, 2))
        armed = np.zeros((3, 2), dtype=bool)
        for i, w in enumerate(singles):
            w.period(target[i], armed[i])
        _compiled.world_periods(np.arange(3), links, batch[0].ball_geoms, target, armed,
                                *(state[n] for n in names), batch[0].constants, caught,
                                released)  # fmt: skip
        for i, w in enumerate(singles):
            np.testing.assert_array_equal(w.data.qpos, batch[i].data.qpos)
            np.testing.assert_array_equal(w.data.qvel, batch[i].data.qvel)
            np.testing.assert_array_equal(w.holder[0], state["holder"][i])
            np.testing.assert_array_equal(w.caught[0], caught[i])


def test_contact_sensors_are_the_contact_list(monkeypatch: pytest.MonkeyPatch) -> None:
    """The period reads the scene's contact sensors (per ball: the floor, then each palm):
    after every physics step they are MuJoCo's contact list, and they touch at times."""
    spec = WorldSpec.of(TASK, hands=2, balls=3)
    world = HandsWorld(spec, backend="python")
    step = _period.mj_step_c
    seen = np.zeros(9, dtype=bool)

    def checked(model_addr: int, data_addr: int) -> None:
        step(model_addr, data_addr)
        d = world.data
        pairs = {(int(c.geom1), int(c.geom2)) for c in d.contact[: d.ncon]}
        pairs |= {(b, a) for a, b in pairs}
        others = [world.floor_geom, *world.palm_geoms]
        for i, g in enumerate(world.ball_geoms):
            for j, o in enumerate(others):
                touching = bool(d.sensordata[3 * i + j] > 0)
                assert touching == ((int(g), o) in pairs), (i, j)
                seen[3 * i + j] |= touching

    monkeypatch.setattr(_period, "mj_step_c", checked)
    for seed in range(3):
        _drive(world, 120, seed)
    assert seen[[1, 2, 4, 5, 7, 8]].any() and seen[[0, 3, 6]].any()


def _meet_still_palm(world: HandsWorld, speed: float, offset: float) -> str:
    """A ball falling at ``speed`` onto the still palm of a one-hand world, ``offset``
    from its centre: ``"caught"``, ``"dropped"`` or ``"bounced"``."""
    hand = np.array([[0.0, 1.0]])
    world.reset_state(hand, np.zeros((1, 2)), (-1,), (-1,), np.array([[offset, 1.12]]),
                      np.array([[0.0, -speed]]))  # fmt: skip
    for _ in range(400):
        world.period(hand, (False,))
        if world.caught[0, 0] >= 0:
            return "caught"
        if world.dropped[0, 0]:
            return "dropped"
        if world.data.qvel[3] > 0.0 and world.data.qpos[3] > 1.05:
            return "bounced"
    return "neither"


def test_capture_rule_behaves_as_documented() -> None:
    """The docstring of ``envs.juggling._world``: on a still palm a falling ball is caught
    at every closing speed up to 10 m/s wherever it meets the palm, and up to 20 m/s
    within 2 cm of its centre (the soft contact slows it below ``capture_speed`` within a
    physics step); only fast balls meeting the palm's edge slide off and drop."""
    world = HandsWorld(WorldSpec.of(TASK, hands=1, balls=1))
    for speed in (1.0, 3.0, 4.9, 5.1, 6.0, 8.0, 10.0):
        for offset in (0.0, 0.02, 0.04, 0.06, 0.075):
            assert _meet_still_palm(world, speed, offset) == "caught", (speed, offset)
    for speed in (15.0, 20.0):
        for offset in (0.0, 0.02):
            assert _meet_still_palm(world, speed, offset) == "caught", (speed, offset)
    assert _meet_still_palm(world, 20.0, 0.075) == "dropped"
    assert _meet_still_palm(world, 5.0, 0.09) == "dropped"  # misses the palm


def test_a_rising_ball_is_never_caught() -> None:
    world = HandsWorld(WorldSpec.of(TASK, hands=1, balls=1))
    hand = np.array([[0.0, 1.0]])
    world.reset_state(hand, np.zeros((1, 2)), (-1,), (-1,), np.array([[0.0, 0.95]]),
                      np.array([[0.0, 0.5]]))  # fmt: skip
    for _ in range(5):
        world.period(hand, (False,))
        assert world.caught[0, 0] < 0


def test_hand_stops_at_the_floor() -> None:
    """A target far below the floor: the palm's underside stops at the floor (a MuJoCo
    joint limit), where before the hand passed through it."""
    spec = WorldSpec.of(TASK, hands=2, balls=3)
    world = HandsWorld(spec)
    home = np.array([[0.25, 0.8], [-0.25, 0.8]])
    world.reset_state(home, np.zeros((2, 2)), (0, 1, -1), (-1, -1, -1), np.zeros((3, 2)) + 2.0,
                      np.zeros((3, 2)))  # fmt: skip
    lowest = np.inf
    for _ in range(300):
        world.period(home - [0.0, 2.0], (False, False))
        lowest = min(lowest, world.data.qpos[1], world.data.qpos[3])
    palm_bottom = lowest + spec.palm_top - 2 * 0.008
    assert palm_bottom > TASK.floor_z - 0.01  # a soft limit: millimetres of give
    assert palm_bottom < TASK.floor_z + 0.01  # and it did reach the floor


@needs_numba
def test_single_env_likeness_is_the_models_number() -> None:
    """``LikenessQuery`` (the single env's compiled search) gives
    ``HumanLikeness.distance``'s number bit for bit, also far away and for non-finite
    states, and survives pickling."""
    import pickle

    from motion_envs.datasets.juggling import PHASES
    from motion_envs.envs.juggling._likeness import LikenessQuery
    from motion_envs.models.juggling import v1_likeness

    likeness = v1_likeness(9.81, "train")
    query = pickle.loads(pickle.dumps(LikenessQuery(likeness)))
    rng = np.random.default_rng(0)
    pos = rng.normal([0.2, 1.1], 0.3, (400, 2))
    vel = rng.normal(0.0, 2.0, (400, 2))
    pos[:5] *= 1e3  # far from every sample
    pos[5], vel[6], pos[7] = np.nan, np.inf, -np.inf
    for i in range(400):
        phase = PHASES[i % len(PHASES)]
        expected = likeness.distance(phase, pos[i], vel[i])
        assert query.distance(phase, pos[i], vel[i]) == expected
