"""Renderer creation under every MUJOCO_GL (subprocesses), deepcopy with a live renderer,
make/close memory."""

from __future__ import annotations

import copy
import ctypes
import gc
import json
import os
import subprocess
import sys
import textwrap
import tracemalloc
from pathlib import Path

import gymnasium as gym
import numpy as np
import pytest

import motion_envs  # noqa: F401  (registers the ids)

ORIENTATION = "MotionEnvs/OrientationReach-v0"
POSITION = "MotionEnvs/PositionReach-v0"
ROOT = Path(__file__).resolve().parents[1]

# Creates renderers three times (directly and through two environments), renders, and
# reports the backend, the os.environ keys that changed and the warnings.
_SCRIPT = textwrap.dedent(
    """
    import json, os, warnings
    before = dict(os.environ)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        import gymnasium as gym
        import numpy as np
        import motion_envs
        from motion_envs.envs.rendering import HandFrameRenderer
        backends = []
        for _ in range(3):
            r = HandFrameRenderer(64, 64)
            q = np.tile([1.0, 0.0, 0.0, 0.0], (50, 1))
            assert r.render(q, q, q[:1], 0).shape == (64, 64, 3)
            backends.append(r.backend)
            r.close()
        for _ in range(2 if WITH_ENV else 0):
            env = gym.make("MotionEnvs/OrientationReach-v0", render_mode="rgb_array",
                           width=64, height=64)
            env.reset(seed=0)
            assert env.render().shape == (64, 64, 3)
            env.close()
    after = dict(os.environ)
    changed = sorted(k for k in set(before) | set(after) if before.get(k) != after.get(k))
    print(json.dumps({
        "backends": backends,
        "environ_changed": changed,
        "warnings": [str(w.message) for w in caught if "matplotlib" in str(w.message)],
    }))
    """
)


# Variables third-party imports set: gymnasium (pygame's prompt), scikit-learn (through
# statsmodels/scipy users) and MuJoCo's own EGL/OSMesa modules (PyOpenGL's platform).
_THIRD_PARTY_ENVIRON = {"PYGAME_HIDE_SUPPORT_PROMPT", "KMP_DUPLICATE_LIB_OK", "PYOPENGL_PLATFORM"}


def _run(mujoco_gl: str | None, with_env: bool = False) -> dict:
    env = {k: v for k, v in os.environ.items() if k not in ("DISPLAY", "WAYLAND_DISPLAY")}
    env.pop("MUJOCO_GL", None)
    env.pop("PYOPENGL_PLATFORM", None)
    if mujoco_gl is not None:
        env["MUJOCO_GL"] = mujoco_gl
    env["PYTHONPATH"] = str(ROOT) + os.pathsep + env.get("PYTHONPATH", "")
    proc = subprocess.run(
        [sys.executable, "-c", f"WITH_ENV = {with_env}\n" + _SCRIPT],
        env=env,
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert proc.returncode == 0, (mujoco_gl, proc.returncode, proc.stderr[-2000:])
    out = json.loads(proc.stdout.strip().splitlines()[-1])
    out["environ_unchanged"] = set(out["environ_changed"]) <= _THIRD_PARTY_ENVIRON
    return out


@pytest.mark.parametrize("mujoco_gl", [None, "", "glfw", "GLFW"])
def test_display_backends_without_a_display_fall_back_once(mujoco_gl):
    out = _run(mujoco_gl, with_env=mujoco_gl in (None, "glfw"))
    assert out["backends"] == ["matplotlib"] * 3
    assert out["environ_unchanged"]
    assert len(out["warnings"]) == 1 and "MUJOCO_GL" in out["warnings"][0]


@pytest.mark.parametrize("mujoco_gl", ["egl", "osmesa"])
def test_offscreen_backends_render_with_mujoco_or_fall_back(mujoco_gl):
    out = _run(mujoco_gl)
    assert out["environ_unchanged"]
    if out["backends"][0] == "matplotlib":
        assert out["backends"] == ["matplotlib"] * 3 and len(out["warnings"]) == 1
        pytest.skip(f"MUJOCO_GL={mujoco_gl} is not usable here: {out['warnings'][0]}")
    assert out["backends"] == ["mujoco"] * 3 and out["warnings"] == []


def test_an_invalid_backend_falls_back_with_the_reason():
    out = _run("bogus")
    assert out["backends"] == ["matplotlib"] * 3
    assert len(out["warnings"]) == 1 and "bogus" in out["warnings"][0]


def test_library_code_never_writes_os_environ_or_switches_the_matplotlib_backend():
    offenders = []
    for path in [*(ROOT / "motion_envs").rglob("*.py"), *(ROOT / "baselines").rglob("*.py")]:
        text = path.read_text()
        for needle in ("os.environ[", "os.environ.setdefault", "os.putenv", "matplotlib.use("):
            if needle in text:
                offenders.append(f"{path.relative_to(ROOT)}: {needle}")
    assert offenders == []


# -- deepcopy ---------------------------------------------------------------------------


def _rollout(env: gym.Env, steps: int = 60) -> list[np.ndarray]:
    rng = np.random.default_rng(3)
    out = []
    for _ in range(steps):
        obs, reward, terminated, truncated, _ = env.step(
            rng.uniform(-1, 1, env.action_space.shape).astype(np.float32)
        )
        out.append(np.append(obs, reward))
        if terminated or truncated:
            env.reset()
    return out


def test_deepcopy_with_a_live_renderer_continues_identically_and_renders():
    """(A deepcopy without a renderer, for every id: ``test_env_contract.py``.)"""
    env = gym.make(ORIENTATION, render_mode="rgb_array", width=32, height=32)
    env.reset(seed=11)
    _rollout(env, 7)
    env.render()  # a live renderer is not copied
    twin = copy.deepcopy(env)
    a, b = _rollout(env), _rollout(twin)
    for x, y in zip(a, b, strict=True):
        np.testing.assert_array_equal(x, y)
    assert twin.render().shape == (32, 32, 3)
    env.close()
    twin.close()


def test_deepcopy_of_a_native_vector_env():
    venv = gym.make_vec(
        POSITION, num_envs=3, vectorization_mode="vector_entry_point", shapes=["GShape"]
    )
    venv.reset(seed=2)
    twin = copy.deepcopy(venv)
    actions = np.random.default_rng(0).uniform(-1, 1, (20, 3, 2)).astype(np.float32)
    for a in actions:
        for x, y in zip(venv.step(a)[:4], twin.step(a)[:4], strict=True):
            np.testing.assert_array_equal(x, y)


# -- make/close 200 times ---------------------------------------------------------------


def _rss_bytes() -> int:
    """The process's resident memory, after glibc returns its free heap pages to the OS
    (``malloc_trim``): without it, arena fragmentation from the native renderers (osmesa)
    moves RSS by tens of MiB up and down with no leak (measured: +/-40 MiB untrimmed, flat
    within 0.3 MiB trimmed, over 400 cycles)."""
    gc.collect()
    try:
        ctypes.CDLL("libc.so.6").malloc_trim(0)
    except (OSError, AttributeError):  # not glibc: measure as is
        pass
    with open("/proc/self/statm") as fh:
        return int(fh.read().split()[1]) * os.sysconf("SC_PAGE_SIZE")


@pytest.mark.skipif(not Path("/proc/self/statm").exists(), reason="needs /proc (Linux)")
@pytest.mark.parametrize(
    ("env_id", "kwargs"),
    [
        (ORIENTATION, {"render_mode": "rgb_array", "width": 48, "height": 48}),
        (POSITION, {"shapes": ["GShape"], "render_mode": "rgb_array", "width": 48, "height": 48}),
    ],
)
def test_make_close_200_times_keeps_memory_flat(env_id, kwargs):
    """Python allocations (tracemalloc) and the process RSS after 200 make/reset/step/
    close cycles (every 25th also renders, creating and closing a renderer) stay within
    a tolerance of their level after 40 cycles: a leak of one observation space, one
    environment or one figure per cycle would exceed it."""

    def cycle(i: int) -> None:
        env = gym.make(env_id, **kwargs)
        env.reset(seed=i)
        env.step(env.action_space.sample())
        if i % 25 == 0:
            assert env.render().shape == (48, 48, 3)
        env.close()

    for i in range(40):  # warm-up: caches, lazy imports, the first renderer
        cycle(i)
    gc.collect()
    tracemalloc.start()
    traced_0, rss_0 = tracemalloc.get_traced_memory()[0], _rss_bytes()
    for i in range(40, 200):
        cycle(i)
    gc.collect()
    traced_1, rss_1 = tracemalloc.get_traced_memory()[0], _rss_bytes()
    tracemalloc.stop()
    assert traced_1 - traced_0 < 160 * 1024, f"Python memory grew {traced_1 - traced_0} bytes"
    assert rss_1 - rss_0 < 24 * 2**20, f"RSS grew {(rss_1 - rss_0) / 2**20:.1f} MiB"


def test_hand_frames_are_labelled_human_nominal_agent():
    from motion_envs.envs.rendering import HandFrameRenderer

    renderer = HandFrameRenderer(120, 120, backend="matplotlib")
    q = np.tile([1.0, 0.0, 0.0, 0.0], (50, 1))
    renderer.render(q, q, q[:2], 1)
    legend = renderer._fig.axes[0].get_legend()
    assert [t.get_text() for t in legend.get_texts()] == ["human", "nominal", "agent"]
