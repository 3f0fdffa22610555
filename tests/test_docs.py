"""The documentation site builds with warnings as errors and documents every public name.

The test build (about 2 minutes of CPU, under a minute and a half of wall time on 2
cores with ``-j 2``) neither runs the gallery (``MOTION_ENVS_DOCS_RUN_EXAMPLES=0``:
tests/test_examples.py runs every script) nor renders the environment pages' animations
(``MOTION_ENVS_DOCS_ANIMATION_FRAMES=0``: the pages show the first frame; rendering the
GIFs takes about a minute of CPU, done once and cached by the documented build). The
animation code is tested on its own below with a few frames.
"""

from __future__ import annotations

import importlib
import inspect
import os
import pkgutil
import subprocess
import sys
from pathlib import Path

import pytest

pytest.importorskip("sphinx")
pytest.importorskip("myst_parser")
pytest.importorskip("furo")
pytest.importorskip("sphinx_gallery")

ROOT = Path(__file__).resolve().parents[1]
SPHINX_ARGS = ("-b", "html", "-W", "--keep-going", "-q", "-j", "2")
#: The test build's settings (see the module docstring).
BUILD_ENV = {"MOTION_ENVS_DOCS_RUN_EXAMPLES": "0", "MOTION_ENVS_DOCS_ANIMATION_FRAMES": "0"}


def public_names() -> set[str]:
    """``module.name`` of every class and function in ``__all__`` of every public module of
    both packages (module-level constants are described in their modules' docstrings)."""
    names: set[str] = set()
    for name, module in public_modules():
        for obj in getattr(module, "__all__", ()):
            value = getattr(module, obj)
            if inspect.isclass(value) or inspect.isroutine(value):
                names.add(f"{name}.{obj}")
    return names


def public_modules() -> list[tuple[str, object]]:
    """Every module of both packages whose dotted name has no private part."""
    import warnings

    out = []
    for package in ("motion_envs", "baselines"):
        root = importlib.import_module(package)
        names = [root.__name__]
        for info in pkgutil.walk_packages(root.__path__, prefix=f"{package}."):
            if not any(part.startswith("_") for part in info.name.split(".")):
                names.append(info.name)
        with warnings.catch_warnings():  # the deprecated modules warn on import
            warnings.simplefilter("ignore", DeprecationWarning)
            out += [(name, importlib.import_module(name)) for name in names]
    return out


def canonical(qualified: str) -> str:
    """Where the object named ``module.name`` is defined (``__module__.__qualname__``)."""
    module, _, name = qualified.rpartition(".")
    obj = getattr(importlib.import_module(module), name)
    return f"{getattr(obj, '__module__', module)}.{getattr(obj, '__qualname__', name)}"


@pytest.fixture(scope="module")
def built_site(tmp_path_factory):
    out = tmp_path_factory.mktemp("site")
    env = {**os.environ, **BUILD_ENV}
    proc = subprocess.run(
        [sys.executable, "-m", "sphinx", *SPHINX_ARGS, "docs", str(out)],
        cwd=ROOT,
        env=env,
        capture_output=True,
        text=True,
        timeout=1800,  # a hang guard: the build took 15 min of wall on a 2-core machine at load 18
    )
    assert proc.returncode == 0, proc.stderr[-4000:]
    return out


@pytest.mark.slow
def test_site_builds_with_warnings_as_errors(built_site):
    assert (built_site / "index.html").exists()
    assert (built_site / "api.html").exists()


@pytest.mark.slow
def test_every_environment_has_a_page(built_site):
    import motion_envs

    for env_id in motion_envs.ENV_IDS:
        page = built_site / "environments" / f"{env_id.split('/')[-1].lower()}.html"
        assert page.exists(), env_id
        text = page.read_text(encoding="utf-8")
        assert "Action Space" in text, env_id
        assert "Version History" in text, env_id


@pytest.mark.slow
def test_tutorials_are_in_the_site(built_site):
    index = (built_site / "tutorials" / "index.html").read_text(encoding="utf-8")
    for name in ("tutorial_train_and_compare", "tutorial_own_recordings", "tutorial_sweep"):
        assert f"auto_examples/{name}.html" in index, name
        assert (built_site / "auto_examples" / f"{name}.html").exists(), name


def test_animation_is_a_seeded_nominal_rollout_and_cached(tmp_path, monkeypatch):
    """The GIF of an environment page: frames of the zero-action episode from seed 0,
    written once; a second build with the same inputs renders nothing."""
    pytest.importorskip("PIL")
    import gymnasium as gym
    import numpy as np
    from PIL import Image

    sys.path.insert(0, str(ROOT / "docs" / "_ext"))
    try:
        import env_pages
    finally:
        sys.path.remove(str(ROOT / "docs" / "_ext"))
    env_id = "MotionEnvs/PositionReach-v1"  # matplotlib renderer: no OpenGL needed
    frames, fps = env_pages.rollout_frames(env_id, 4, size=64)
    assert len(frames) == 4 and fps == 25
    env = gym.make(env_id, render_mode="rgb_array", width=64, height=64)
    env.reset(seed=0)
    np.testing.assert_array_equal(frames[0], env.render())
    env.step(np.zeros(env.action_space.shape, dtype=np.float32))
    np.testing.assert_array_equal(frames[1], env.render())
    env.close()

    monkeypatch.setattr(env_pages, "ANIMATION_SIZE", 64)
    gif = env_pages.animation(env_id, tmp_path, 3)
    assert gif is not None
    with Image.open(gif) as image:
        assert image.size == (64, 64)
        total = 0  # Pillow merges identical consecutive frames, adding their durations
        for k in range(image.n_frames):
            image.seek(k)
            total += image.info["duration"]
        assert total == 3 * 40  # 3 frames, 25 per second of environment time
    before = gif.stat().st_mtime_ns

    def no_rendering(*args, **kwargs):
        raise AssertionError("the cached GIF was rendered again")

    monkeypatch.setattr(env_pages, "rollout_frames", no_rendering)
    assert env_pages.animation(env_id, tmp_path, 3) == gif
    assert gif.stat().st_mtime_ns == before
    with pytest.raises(AssertionError, match="rendered again"):  # other inputs: rendered
        env_pages.animation(env_id, tmp_path, 4)


@pytest.mark.slow
def test_every_public_name_is_in_the_api_reference(built_site):
    from sphinx.util.inventory import InventoryFile

    with open(built_site / "objects.inv", "rb") as fh:
        inventory = InventoryFile.load(fh, "", lambda base, uri: uri)
    data = getattr(inventory, "data", inventory)  # a dict before Sphinx 8.2, an Inventory after
    documented = {name for entries in data.values() for name in entries}
    missing = sorted(
        n for n in public_names() if n not in documented and canonical(n) not in documented
    )
    assert not missing, missing
