"""Issue 17 item 5: a run folder holds exactly one run's files.

Once, an interrupted ``train`` left ``normalization.npz`` in ``--out``; a second run without
normalisation into the same folder listed the stale file in ``run.json`` and
``motion-bench agent`` applied it (a silent wrong score); two concurrent runs could share
one folder; ``run.json`` could name files outside the folder.
"""

from __future__ import annotations

import dataclasses
import json

import numpy as np
import pytest

pytest.importorskip("stable_baselines3")

from baselines.agents.rundir import file_sha256, load_run, manifest_sha256, staged_run_folder
from baselines.agents.train import run as train_run
from motion_envs._io import current_umask
from tests.test_agent_train import tiny_config

pytestmark = pytest.mark.filterwarnings("ignore:.*out of date.*:DeprecationWarning")
ENV = "MotionEnvs/OrientationReach-v1"


def _config(out, normalize: bool):
    cfg = tiny_config("ppo", ENV, out)
    overrides = {**cfg.overrides, "normalize": {"obs": normalize, "reward": False}}
    return dataclasses.replace(cfg, overrides=overrides)


def _interrupt(ev):
    raise KeyboardInterrupt


def test_interrupted_run_leaves_nothing_and_rerun_has_no_stale_normalisation(tmp_path):
    out = tmp_path / "run"
    with pytest.raises(KeyboardInterrupt):  # Ctrl-C after the first best checkpoint
        train_run(_config(out, normalize=True), on_evaluation=_interrupt)
    assert not out.exists() and list(tmp_path.iterdir()) == []  # no staging folder left
    train_run(_config(out, normalize=False))
    manifest = json.loads((out / "run.json").read_text())
    assert "normalization.npz" not in manifest["files"]
    assert not (out / "normalization.npz").exists()
    loaded = load_run(out)
    assert loaded.normalizer.mean is None  # identity: no stale statistics applied
    obs = np.ones((1, loaded.model.observation_space.shape[0]), dtype=np.float32)
    assert np.array_equal(loaded.normalizer(obs), obs)


def test_non_empty_out_refused_and_empty_out_accepted(tmp_path):
    stale = tmp_path / "stale"
    stale.mkdir()
    (stale / "normalization.npz").write_bytes(b"old")
    with pytest.raises(ValueError, match="not an empty folder"):
        train_run(_config(stale, normalize=False))
    assert [p.name for p in stale.iterdir()] == ["normalization.npz"]
    empty = tmp_path / "empty"
    empty.mkdir()
    train_run(_config(empty, normalize=False))
    assert (empty / "run.json").is_file()


def test_second_run_to_finish_into_one_folder_is_refused(tmp_path):
    out = tmp_path / "run"

    def other_run_finishes(ev):  # another train renames its run into --out meanwhile
        # (out exists already: this run created it, empty, to lock it; a writer that
        # ignores the lock can still fill it)
        if not (out / "run.json").exists():
            out.mkdir(exist_ok=True)
            (out / "run.json").write_text("{}\n")

    with pytest.raises(ValueError, match="filled by another run"):
        train_run(_config(out, normalize=False), on_evaluation=other_run_finishes)
    assert [p.name for p in out.iterdir()] == ["run.json"]
    assert sorted(p.name for p in tmp_path.iterdir()) == ["run"]


def test_staging_folder_permissions_follow_umask(tmp_path):
    with staged_run_folder(tmp_path / "r") as staging:
        (staging / "x").write_text("1")
    assert (tmp_path / "r" / "x").read_text() == "1"
    assert (tmp_path / "r").stat().st_mode & 0o777 == 0o777 & ~current_umask()


@pytest.mark.parametrize("name", ["../outside.json", "/etc/passwd", "a/../../b", ""])
def test_run_json_paths_stay_inside_the_run_folder(tmp_path, name):
    out = tmp_path / "run"
    train_run(_config(out, normalize=False))
    (tmp_path / "outside.json").write_text("{}")
    manifest = json.loads((out / "run.json").read_text())
    target = (out / name) if name else out
    manifest["files"][name] = file_sha256(target) if target.is_file() else "0"
    manifest["manifest_sha256"] = manifest_sha256(manifest)  # as a careful tamperer would
    (out / "run.json").write_text(json.dumps(manifest))
    with pytest.raises(ValueError, match="not a file name inside the run folder"):
        load_run(out)


def test_agent_final_checkpoint_does_not_overwrite_the_best_evaluation(tmp_path):
    """Once, ``motion-bench agent DIR --checkpoint final`` overwrote ``DIR/eval-test/``."""
    from baselines.cli import main

    out = tmp_path / "run"
    train_run(_config(out, normalize=False))
    assert main(["agent", str(out), "--episodes", "2"]) == 0
    best = (out / "eval-test" / "results.json").read_bytes()
    assert main(["agent", str(out), "--episodes", "2", "--checkpoint", "final"]) == 0
    assert (out / "eval-test" / "results.json").read_bytes() == best
    final = json.loads((out / "eval-test-final" / "results.json").read_text())
    assert final["checkpoint"] == "final"
    assert json.loads(best)["checkpoint"] == "best"
